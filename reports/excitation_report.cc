#include "reports/excitation_report.h"

#include <sstream>

#include "fit.pb.h"
#include "io/csv.h"
#include "model/format.h"

namespace pz::reports {
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

void ExcitationOf(const io::RecordSet& set, const records::ExcitationReport& r,
                  const records::TrainingDriveProposal& p, const std::string& drive_file,
                  proto::Excitation* out) {
  proto::Excitation e;
  const records::DriveExcitation& t = r.training;
  proto::ExcitationTraining& g = *e.mutable_training();
  g.set_drive_min(t.u_min);
  g.set_drive_max(t.u_max);
  g.set_duration_s(t.duration_s);
  g.set_reversals(static_cast<int64_t>(t.turns));
  g.set_rate_p95(t.rate_p95);
  g.set_rate_max(t.rate_max);
  g.set_longest_hold_s(t.longest_hold_s);
  for (double w : t.depth_weight) g.add_depth_cycles_per_tenth(w);
  for (double w : t.level_weight) g.add_turns_per_tenth(w);
  for (const std::string& l : r.training_lines) g.add_summary(l);
  for (const records::WithheldExcitation& w : r.withheld) {
    proto::ExcitationWithheld& h = *e.add_withheld();
    h.set_record(set.records[w.record].name);
    h.set_drive_min(w.drive.u_min);
    h.set_drive_max(w.drive.u_max);
    h.set_reversals(static_cast<int64_t>(w.drive.turns));
    h.set_rate_p95(w.drive.rate_p95);
    h.set_longest_hold_s(w.drive.longest_hold_s);
    h.set_uncovered_share(w.uncovered_share);
    for (const records::ExcitationNeed& n : w.needs) {
      proto::ExcitationNeed& k = *h.add_needs();
      k.set_kind(records::ExcitationNeedName(n.kind));
      k.set_amount(n.amount);
      k.set_text(n.text);
    }
  }
  e.set_excitation_gap(r.HasGap());
  proto::ProposedDrive& q = *e.mutable_proposed_drive();
  q.set_file(drive_file);
  q.set_fs_hz(p.fs_hz);
  q.set_duration_s(static_cast<double>(p.u.size()) / p.fs_hz);
  for (const std::string& s : p.segments) q.add_segments(s);
  *out = std::move(e);
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

}  // namespace pz::reports
