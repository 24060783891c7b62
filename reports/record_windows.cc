#include "reports/record_windows.h"

#include <algorithm>
#include <string_view>

#include "io/csv.h"
#include "records/registry.h"

namespace pz::reports {

io::RecordSet LoadRecordSetWithWindows(const std::string& path, const std::vector<std::string>& tr,
                                       const std::vector<std::string>& va,
                                       const std::vector<std::string>& te, double settle_s) {
  io::RecordSet set = io::LoadRecordSet(path);
  std::vector<io::WindowSpec> w;
  for (const auto& s : tr)
    w.push_back(io::ParseWindow(s, model::CaseRole::kTrain, "--train-window"));
  for (const auto& s : va)
    w.push_back(io::ParseWindow(s, model::CaseRole::kValidate, "--validate-window"));
  for (const auto& s : te) w.push_back(io::ParseWindow(s, model::CaseRole::kTest, "--test-window"));
  io::SplitIntoWindows(set, w);
  io::SkipSettling(set, settle_s, io::RecordReadOptions{}.min_scored,
                   "--settle-s " + io::FormatNumber(settle_s));
  return set;
}

std::string SettlingSentence(double settle_s) {
  if (settle_s == 0) return "";
  return "Every record is scored from " + io::FormatNumber(settle_s) +
         " s after the end of its rest (--settle-s): the models start at rest with the memory of "
         "their initial "
         "state (--initial-state), a stack at rest sits where its last move left it, and where the "
         "two differ they "
         "do until the first large reversal (io::SkipSettling).";
}

std::string InitialStateSentence(const records::Family& family) {
  if (!records::TakesInitialState(family.name())) return "";
  return InitialStateSentence(family.initial_state(), "The model starts");
}

std::string InitialStateSentence(model::InitialState s, const std::string& subject) {
  return subject + " at rest at each record's first drive in the **" + model::InitialStateName(s) +
         "** state" +
         (s == model::InitialState::kAuto ? " (descended at a rest at the bottom of the training "
                                            "drive range, ascended at its top, else centred)"
                                          : "") +
         " (--initial-state; docs/records.md).";
}

int NameColumnWidth(const io::RecordSet& set) {
  size_t w = 14;
  for (const io::Record& r : set.records) w = std::max(w, r.name.size());
  return static_cast<int>(w + 2);
}

int RoleColumnWidth(const io::RecordSet& set) {
  size_t w = 5;
  for (const io::Record& r : set.records)
    w = std::max(w, std::string_view(model::CaseRoleName(r.role)).size());
  return static_cast<int>(w + 2);
}

}  // namespace pz::reports
