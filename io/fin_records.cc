#include "io/fin_records.h"

#include "io/quantum.h"
#include "io/csv.h"

namespace pz::io {

RecordSet RecordsFromCaseSet(const CaseSet& set) {
  if (set.cases.empty()) throw InputError(set.dir.string() + ": the bench has no case");
  RecordSet out;
  out.source = set.dir;
  out.format = "bimorph-fin-bench";
  out.drive_unit = "V";
  out.response_unit = "deg";
  for (const BenchCase& c : set.cases) {
    const model::Sinusoid s = c.Drive();
    const std::string at = c.file.string() + " (case " + std::to_string(c.number) + ")";
    if (c.t.size() < 2 || c.angle_deg.size() != c.t.size())
      throw InputError(at + ": " + std::to_string(c.angle_deg.size()) + " angle samples on " +
                       std::to_string(c.t.size()) + " times; a record needs 2 at least");
    if (s.NumSamples() != static_cast<int>(c.t.size()))
      throw InputError(at + ": the stated sinusoid (" + FormatNumber(s.cycles) + " cycles at " +
                       FormatNumber(s.frequency_hz) + " Hz, fs " + FormatNumber(s.sample_rate_hz) +
                       " Hz) has " + std::to_string(s.NumSamples()) + " samples, the case " +
                       std::to_string(c.t.size()));
    Record r;
    r.name = "case" + std::to_string(c.number);
    r.role = c.role;
    r.file = c.file;
    r.t = c.t;
    r.u.resize(c.t.size());
    for (size_t k = 0; k < c.t.size(); ++k) r.u[k] = s.Value(c.t[k]);
    r.y = c.angle_deg;
    r.dt = 1.0 / c.sample_rate_hz;
    r.first_scored = 0;
    r.end_scored = r.t.size();
    r.rest_samples = 1;
    while (r.rest_samples < r.u.size() && r.u[r.rest_samples] == r.u[0]) ++r.rest_samples;
    r.offset_mode = OffsetMode::kFixed;
    r.offset = 0;
    r.quantum = EstimateQuantum(r.y);
    r.frequency_hz = c.frequency_hz;
    r.sinusoid = {c.number, s.amplitude_v, s.frequency_hz, s.cycles, s.sample_rate_hz};
    out.records.push_back(std::move(r));
  }
  return out;
}

}  // namespace pz::io
