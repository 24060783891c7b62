// libFuzzer target: the record-set reader (io/records.h) and what `piezoid fit` and `diagnose
// --records` compute from a set before any search (the data scale, the excitation report and its
// proposed drive, the noise floor). The first input byte picks the reader, the rest is split at
// the byte 0x1E (ASCII record separator) into files written to a scratch folder:
//   0 manifest folder   manifest.csv, a.csv, b.csv
//   1 one CSV file      record.csv; the next two parts, when present, are --train-window and
//                       --validate-window (START:END) and the set is split into those windows
//   2 stack bench       records.csv, a.csv, b.csv
//   3 fin bench         cases.csv, a.csv, b.csv
// Every outcome must be a set whose records hold what io::Record promises, or a pz::InputError
// with a message; anything else (a signal, a sanitizer report, another exception) is a finding.
// Build and run: fuzz/run.sh (clang, -fsanitize=fuzzer,address,undefined).
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "io/records.h"
#include "model/status.h"
#include "records/excitation.h"
#include "records/families.h"
#include "records/model.h"
#include "records/noise_floor.h"

namespace {

namespace fs = std::filesystem;
using pz::io::Record;
using pz::io::RecordSet;

fs::path g_dir;

[[noreturn]] void Fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_records: %s\n", what.c_str());
  std::abort();
}

void Write(const fs::path& file, std::string_view text) {
  std::ofstream f(file, std::ios::binary | std::ios::trunc);
  f.write(text.data(), static_cast<std::streamsize>(text.size()));
}

std::vector<std::string_view> Split(std::string_view in) {
  std::vector<std::string_view> parts;
  for (;;) {
    const size_t at = in.find('\x1e');
    parts.push_back(in.substr(0, at));
    if (at == std::string_view::npos) return parts;
    in.remove_prefix(at + 1);
  }
}

// What io::Record promises to every reader of a loaded set.
void CheckRecord(const Record& r, const pz::io::RecordReadOptions& o) {
  const size_t n = r.size();
  if (r.u.size() != n || r.y.size() != n)
    Fail("record '" + r.name + "': columns of different lengths");
  if (n < 2) Fail("record '" + r.name + "': fewer than two samples");
  if (!(r.first_scored < r.end_scored && r.end_scored <= n))
    Fail("record '" + r.name + "': window outside the record");
  if (r.scored() < o.min_scored) Fail("record '" + r.name + "': window shorter than min_scored");
  if (r.rest_samples < 1 || r.rest_samples > n)
    Fail("record '" + r.name + "': rest outside the record");
  if (!(std::isfinite(r.dt) && r.dt > 0))
    Fail("record '" + r.name + "': sample step not finite and > 0");
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite(r.t[k]) || !std::isfinite(r.u[k]) || !std::isfinite(r.y[k]))
      Fail("record '" + r.name + "': a sample that is not finite");
    if (k > 0 && !(r.t[k] > r.t[k - 1])) Fail("record '" + r.name + "': time not increasing");
  }
  if (!std::isfinite(r.offset) || !std::isfinite(r.quantum))
    Fail("record '" + r.name + "': offset not finite");
  (void)r.Label();
}

// What the fit computes from the set before its search (client/cmd_fit.cc, records/fit.cc).
void Analyse(const RecordSet& set) {
  const auto train = set.WithRole(pz::model::CaseRole::kTrain);
  if (!train.empty()) {
    const pz::records::DataScale s = pz::records::MeasureScale(train);
    (void)s;
    for (const Record* r : train) (void)pz::records::SimulatedFrom(*r, r->end_scored);
  }
  const auto report = pz::records::AnalyseExcitation(set);
  (void)pz::records::ProposeTrainingDrive(set, report);
  const auto floor = pz::records::EstimateNoiseFloor(set);
  if (std::isnan(floor.sigma)) Fail("a noise floor that is NaN");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char tmpl[] = "/tmp/fuzz_records.XXXXXX";
  if (mkdtemp(tmpl) == nullptr) Fail("mkdtemp");
  g_dir = tmpl;
  std::atexit([] {
    std::error_code ec;
    fs::remove_all(g_dir, ec);
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const int mode = data[0] % 4;
  const std::vector<std::string_view> parts =
      Split(std::string_view(reinterpret_cast<const char*>(data) + 1, size - 1));
  for (const auto& e : fs::directory_iterator(g_dir)) fs::remove(e.path());
  static const char* const kManifest[] = {"manifest.csv", "record.csv", "records.csv", "cases.csv"};
  Write(g_dir / kManifest[mode], parts[0]);
  if (mode != 1) {
    if (parts.size() > 1) Write(g_dir / "a.csv", parts[1]);
    if (parts.size() > 2) Write(g_dir / "b.csv", parts[2]);
  }
  const pz::io::RecordReadOptions options;
  try {
    RecordSet set = pz::io::LoadRecordSet(mode == 1 ? g_dir / "record.csv" : g_dir, options);
    if (mode == 1 && parts.size() > 1) {
      std::vector<pz::io::WindowSpec> w{
          pz::io::ParseWindow(parts[1], pz::model::CaseRole::kTrain, "--train-window")};
      if (parts.size() > 2)
        w.push_back(
            pz::io::ParseWindow(parts[2], pz::model::CaseRole::kValidate, "--validate-window"));
      pz::io::SplitIntoWindows(set, w, options);
    }
    if (set.records.empty()) Fail("a set without records");
    for (const Record& r : set.records) CheckRecord(r, options);
    pz::io::SkipSettling(set, 0.01 * static_cast<double>(data[0]), options.min_scored, "settle");
    for (const Record& r : set.records) CheckRecord(r, options);
    Analyse(set);
  } catch (const pz::InputError& e) {
    if (std::string_view(e.what()).empty()) Fail("an InputError without a message");
  }
  return 0;
}
