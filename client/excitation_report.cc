#include "client/excitation_report.h"

#include <sstream>

#include "io/csv.h"
#include "model/format.h"

namespace pz::client {
namespace {

std::string G(double x) { return FormatG(x, 4); }

}  // namespace

void WriteExcitationMarkdown(std::ostream& os, const io::RecordSet& set,
                             const records::ExcitationReport& r,
                             const records::TrainingDriveProposal& p,
                             const std::string& drive_file) {
  os << "\n## Excitation (before fitting)\n\nWhat the training records excite:\n\n";
  for (const std::string& line : r.training_lines) os << "- " << line << "\n";
  if (r.withheld.empty()) {
    os << "\nNo withheld records: nothing to compare with the training excitation. A richer "
          "training drive is in `"
       << drive_file << "`: " << p.description << ".\n";
    return;
  }
  os << "\n| withheld record | drive [" << r.drive_unit
     << "] | reversals | cycles outside training | needs beyond training |\n"
     << "|---|---|---|---|---|\n";
  for (const records::WithheldExcitation& w : r.withheld) {
    std::string needs;
    for (const records::ExcitationNeed& n : w.needs) needs += (needs.empty() ? "" : "; ") + n.text;
    os << "| " << set.records[w.record].name << " | " << G(w.drive.u_min) << " … "
       << G(w.drive.u_max) << " | " << w.drive.turns << " | " << G(100 * w.uncovered_share)
       << " % | " << (needs.empty() ? "nothing: within the training excitation" : needs) << " |\n";
  }
  if (r.HasGap()) {
    os << "\nA withheld error on a record that needs what training lacks is an **excitation gap** "
          "(the model "
          "extrapolates), not necessarily missing physics. Proposed training drive (`"
       << drive_file << "`): " << p.description << ".\n";
  } else {
    os << "\nEvery withheld record lies within the training excitation. A richer training drive is "
          "in `"
       << drive_file << "`: " << p.description << ".\n";
  }
}

json::Value ExcitationJson(const io::RecordSet& set, const records::ExcitationReport& r,
                           const records::TrainingDriveProposal& p, const std::string& drive_file) {
  using namespace json;  // NOLINT
  Struct root;
  auto& f = *root.mutable_fields();
  const records::DriveExcitation& t = r.training;
  Struct tr;
  auto& g = *tr.mutable_fields();
  g["drive_min"] = Num(t.u_min);
  g["drive_max"] = Num(t.u_max);
  g["duration_s"] = Num(t.duration_s);
  g["reversals"] = Num(static_cast<double>(t.turns));
  g["rate_p95"] = Num(t.rate_p95);
  g["rate_max"] = Num(t.rate_max);
  g["longest_hold_s"] = Num(t.longest_hold_s);
  std::vector<Value> depths, levels, lines;
  for (double w : t.depth_weight) depths.push_back(Num(w));
  for (double w : t.level_weight) levels.push_back(Num(w));
  for (const std::string& l : r.training_lines) lines.push_back(Text(l));
  g["depth_cycles_per_tenth"] = List(depths);
  g["turns_per_tenth"] = List(levels);
  g["summary"] = List(lines);
  f["training"] = Obj(tr);
  std::vector<Value> withheld;
  for (const records::WithheldExcitation& w : r.withheld) {
    Struct x;
    auto& h = *x.mutable_fields();
    h["record"] = Text(set.records[w.record].name);
    h["drive_min"] = Num(w.drive.u_min);
    h["drive_max"] = Num(w.drive.u_max);
    h["reversals"] = Num(static_cast<double>(w.drive.turns));
    h["rate_p95"] = Num(w.drive.rate_p95);
    h["longest_hold_s"] = Num(w.drive.longest_hold_s);
    h["uncovered_share"] = Num(w.uncovered_share);
    std::vector<Value> needs;
    for (const records::ExcitationNeed& n : w.needs) {
      Struct y;
      auto& k = *y.mutable_fields();
      k["kind"] = Text(records::ExcitationNeedName(n.kind));
      k["amount"] = Num(n.amount);
      k["text"] = Text(n.text);
      needs.push_back(Obj(y));
    }
    h["needs"] = List(needs);
    withheld.push_back(Obj(x));
  }
  f["withheld"] = List(withheld);
  f["excitation_gap"] = Bool(r.HasGap());
  Struct prop;
  auto& q = *prop.mutable_fields();
  q["file"] = Text(drive_file);
  q["fs_hz"] = Num(p.fs_hz);
  q["duration_s"] = Num(static_cast<double>(p.u.size()) / p.fs_hz);
  std::vector<Value> segments;
  for (const std::string& s : p.segments) segments.push_back(Text(s));
  q["segments"] = List(segments);
  f["proposed_drive"] = Obj(prop);
  return Obj(root);
}

void PrintExcitationSummary(std::ostream& os, const io::RecordSet& set,
                            const records::ExcitationReport& r) {
  if (r.withheld.empty()) {
    os << "excitation: no withheld records\n";
    return;
  }
  if (!r.HasGap()) {
    os << "excitation: every withheld record lies within the training excitation\n";
    return;
  }
  for (const records::WithheldExcitation& w : r.withheld) {
    for (const records::ExcitationNeed& n : w.needs)
      os << "excitation: " << set.records[w.record].name << " needs " << n.text << "\n";
  }
}

void WriteProposedDrive(const std::filesystem::path& path, const io::RecordSet& set,
                        const records::TrainingDriveProposal& p) {
  io::WriteFileWith(path, [&](std::ostream& os) {
    os << "t_s,drive_" << set.drive_unit << "\n";
    for (size_t k = 0; k < p.u.size(); ++k)
      os << io::FormatNumber(static_cast<double>(k) / p.fs_hz) << "," << io::FormatNumber(p.u[k])
         << "\n";
  });
}

}  // namespace pz::client
