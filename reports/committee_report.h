// The committee machine's report (its computation is complete/committee.h): report.md with the
// paper's Tables 3–16 analogues, committee.json, and loop figures per band.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "complete/committee.h"

namespace pz::proto {
class CommitteeFile;
}

namespace pz::reports {

using complete::CommitteeResult;

/// report.md: settings, per-band tables like the paper's Tables 3–16, selection, reduction, timing.
void WriteCommitteeReport(std::ostream& out, const CommitteeResult& r);
/// The study as its stored message (committee.json, proto/committee.proto; `out` replaced).
void CommitteeOf(const CommitteeResult& r, proto::CommitteeFile* out);
/// committee.json (io/proto_json.h: keys sorted, a non-finite number as null).
std::string CommitteeJson(const CommitteeResult& r);
/// Loop figures (displacement vs voltage over the last drive cycle, measured / committee / best
/// complete) per test record, grouped by band: <dir>/loop_band<b>_f<f>.{csv,gp,png}. Returns the
/// scripts written; renders them when gnuplot is available (failures appended to warnings).
std::vector<std::string> WriteCommitteeFigures(const std::string& dir, const CommitteeResult& r,
                                               std::vector<std::string>* warnings);

}  // namespace pz::reports
