#include "client/record_windows.h"

namespace pz::client {

io::RecordSet LoadRecordSetWithWindows(const std::string& path, const std::vector<std::string>& tr,
                                       const std::vector<std::string>& va, const std::vector<std::string>& te) {
  io::RecordSet set = io::LoadRecordSet(path);
  std::vector<io::WindowSpec> w;
  for (const auto& s : tr) w.push_back(io::ParseWindow(s, model::CaseRole::kTrain, "--train-window"));
  for (const auto& s : va) w.push_back(io::ParseWindow(s, model::CaseRole::kValidate, "--validate-window"));
  for (const auto& s : te) w.push_back(io::ParseWindow(s, model::CaseRole::kTest, "--test-window"));
  io::SplitIntoWindows(set, w);
  return set;
}

}  // namespace pz::client
