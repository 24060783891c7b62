#include "reports/select_report.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "fit.pb.h"
#include "io/csv.h"

namespace pz::reports {
namespace {

std::string G(double x, int prec = 4) {
  if (std::isnan(x)) return "—";
  if (!std::isfinite(x)) return "∞";
  std::ostringstream s;
  s << std::setprecision(prec) << x;
  return s.str();
}

/// "best", "within 1 SE", "1.8 SE above" (the paired SE of its folds less the best's).
std::string FromBest(const records::SelectionResult& s, const records::ModelScore& c) {
  if (c.round != 2 || !std::isfinite(c.cv_rmse)) return "";
  if (c.cv_rmse <= s.best_cv_rmse) return "best";
  if (c.within_one_se) return "within 1 SE";
  return c.se_vs_best > 0 ? G((c.cv_rmse - s.best_cv_rmse) / c.se_vs_best, 2) + " SE above"
                          : "above";
}

}  // namespace

void PrintSelection(std::ostream& os, const io::RecordSet& set, const records::SelectionResult& s,
                    size_t screened) {
  const std::string u = set.response_unit;
  os << "  model selection: " << s.folds
     << "-fold blocked cross-validation on the training records (" << s.fold_fits << " fold fits, "
     << G(s.wall_time_s, 3) << " s); the withheld records are scored after the "
     << "choice, never used for it\n";
  os << "  noise floor " << s.noise.Summary(u) << "\n";
  if (!s.noise.warning.empty()) os << "  warning: " << s.noise.warning << "\n";
  if (!s.grid_note.empty()) os << "  " << s.grid_note << "\n";
  if (!s.unexcited.empty()) os << "  " << s.unexcited << "\n";
  os << "    " << std::left << std::setw(52) << "candidate" << std::right << std::setw(7)
     << "params" << std::setw(12) << "CV RMSE" << std::setw(10) << "SE*" << std::setw(12)
     << "withheld" << std::setw(8) << "/floor"
     << "  \n";
  size_t shown = 0;
  for (size_t i = 0; i < s.ranking.size(); ++i) {
    const records::ModelScore& c = s.ranking[i];
    if (c.round == 1 && shown++ >= screened) break;
    os << "  " << (i == s.chosen ? "* " : "  ") << std::left << std::setw(52)
       << c.candidate.Describe() << std::right << std::setw(7) << c.parameters << std::setw(12)
       << G(c.cv_rmse) << std::setw(10) << G(c.round == 2 ? c.se_vs_best : c.cv_se, 2)
       << std::setw(12) << G(c.withheld_rmse) << std::setw(8)
       << (std::isfinite(c.withheld_rmse) && s.noise.sigma > 0
               ? G(c.withheld_rmse / s.noise.sigma, 3)
               : "—")
       << "  " << (c.round == 1 ? "screened" : FromBest(s, c))
       << (c.error.empty() ? "" : "; " + c.error) << "\n";
  }
  os << "    (SE*: finalists, the paired SE of their fold RMSEs less the best's; screened, their "
        "own";
  if (s.ranking.size() > shown) os << "; " << s.ranking.size() << " candidates in all: report.md";
  os << ")\n";
  os << (s.unexcited.empty() ? "  chosen (the fewest parameters within one SE of the best CV "
                               "RMSE): "
                             : "  chosen (the fewest parameters within one SE of the best CV RMSE "
                               "among the finalists that do not part on their own): ")
     << s.ranking[s.chosen].candidate.Describe() << "\n";
  if (const std::string l = s.ranking[s.chosen].LevelsDescribe(); !l.empty())
    os << "  its resolution: " << l << " " << u << "\n";
  for (const auto& e : s.initial_states)
    os << "  initial state, " << model::CaseRoleName(e.role) << " " << e.record << ": "
       << e.Describe(u) << (e.role == model::CaseRole::kTrain ? "" : " (shown, not used)") << "\n";
}

void WriteSelectionMarkdown(std::ostream& os, const io::RecordSet& set,
                            const records::SelectionResult& s) {
  const std::string u = set.response_unit;
  const records::ModelScore& chosen = s.ranking[s.chosen];
  os << "\n## Model selection (`--family auto`)\n\n"
     << "Chosen: **" << chosen.candidate.Describe() << "** — CV RMSE " << G(chosen.cv_rmse) << " ± "
     << G(chosen.cv_se, 2) << " " << u << ", " << chosen.parameters
     << " parameters (searched + solved weights). The rule: the fewest "
     << "parameters among the finalists whose CV RMSE is within one standard error of the lowest ("
     << G(s.best_cv_rmse) << " " << u
     << "; the paired SE: of the candidate's fold RMSEs less the best's).\n\n"
     << "How: each training record's scored window cut into " << s.folds
     << " contiguous blocks; each fold fits on "
     << "the other blocks (simulated from the record's rest, only the scoring masked) and scores "
        "its block, the "
     << "offset refitted on the fold's training samples. A screening round with a small search "
        "ranks the grid; "
     << "the best of it and the simplest within one SE of its best are cross-validated again with "
        "the full search "
     << "and each initial state worth trying (" << s.fold_fits << " fold fits, "
     << G(s.wall_time_s, 3) << " s). "
     << "**The withheld records never choose**: their errors are those of each finalist refitted "
        "on all the "
     << "training records, shown after the choice. Noise floor " << s.noise.Summary(u) << "."
     << (s.noise.warning.empty() ? "" : " **Warning:** " + s.noise.warning + ".")
     << (s.grid_note.empty() ? "" : "\n\nThe grid: " + s.grid_note + ".")
     << (s.unexcited.empty() ? "" : "\n\n" + s.unexcited) << "\n\n"
     << "| | candidate | parameters | CV RMSE [" << u
     << "] | ± SE | SE vs best | folds | round | withheld RMSE "
     << "(after, not used) | withheld / floor |\n|---|---|---:|---:|---:|---:|---|---|---:|---:|\n";
  for (size_t i = 0; i < s.ranking.size(); ++i) {
    const records::ModelScore& c = s.ranking[i];
    std::string folds;
    for (double f : c.fold_rmse) folds += (folds.empty() ? "" : " ") + G(f, 3);
    os << "| " << (i == s.chosen ? "**chosen**" : "") << " | " << c.candidate.Describe() << " | "
       << c.parameters << " | " << G(c.cv_rmse) << " | " << G(c.cv_se, 2) << " | "
       << (c.round == 2 ? G(c.se_vs_best, 2) : "") << " | " << folds << " | "
       << (c.round == 2 ? "final (" + FromBest(s, c) + ")" : "screening")
       << (c.error.empty() ? "" : ": " + c.error) << " | " << G(c.withheld_rmse) << " | "
       << (std::isfinite(c.withheld_rmse) && s.noise.sigma > 0
               ? G(c.withheld_rmse / s.noise.sigma, 3)
               : "—")
       << " |\n";
  }
  bool levels = false;
  for (const records::ModelScore& c : s.ranking) levels = levels || !c.LevelsDescribe().empty();
  if (levels)
    os << "\nResolutions chosen by the screening's folds (each fold's weights re-solved at the "
          "coarsest rung's effects; CV RMSE in "
       << u << "):\n\n";
  for (const records::ModelScore& c : s.ranking)
    if (const std::string l = c.LevelsDescribe(); !l.empty())
      os << "- " << c.candidate.Describe() << ": " << l << "\n";
  os << "\n### The memory at rest from each record's first branch\n\n"
     << "A 12-play Prandtl–Ishlinskii operator fitted on the training records; each record's first "
        "branch (from "
     << "the end of its rest until its drive has been within 5 % of both ends of the training "
        "range) simulated from "
     << "each memory at rest with its weights. The training records' majority chose **"
     << model::InitialStateName(s.detected) << "**; the withheld records are shown, not used.\n\n"
     << "| record | role | branch [samples] | drive change | centred | descended | ascended | "
        "shows |\n"
     << "|---|---|---|---:|---:|---:|---:|---|\n";
  for (const auto& e : s.initial_states) {
    os << "| " << e.record << " | " << model::CaseRoleName(e.role) << " | ";
    if (!e.note.empty()) {
      os << e.note << " | | | | | |\n";
      continue;
    }
    os << e.from << "–" << e.to << " | " << G(e.rise) << " " << set.drive_unit << " | "
       << G(e.rmse[0]) << " | " << G(e.rmse[1]) << " | " << G(e.rmse[2]) << " | "
       << model::InitialStateName(e.state) << " |\n";
  }
}

void SelectionOf(const records::SelectionResult& s, proto::Selection* out) {
  proto::Selection m;
  m.set_method("blocked cross-validation on the training records; one-standard-error rule");
  m.set_folds(s.folds);
  m.set_fold_fits(static_cast<int64_t>(s.fold_fits));
  m.set_chosen(s.ranking[s.chosen].candidate.Describe());
  m.set_best_cv_rmse(s.best_cv_rmse);
  m.set_noise_floor(s.noise.sigma);
  // Optional: a fit.json written before them reads and writes back the same bytes.
  if (!s.noise.used.empty()) m.set_noise_floor_used(s.noise.used);
  if (!s.noise.estimates.empty()) m.set_noise_floor_summary(s.noise.Summary(""));
  if (!s.noise.warning.empty()) m.set_noise_floor_warning(s.noise.warning);
  if (!s.unexcited.empty()) m.set_unexcited(s.unexcited);
  if (!s.grid_note.empty()) m.set_grid_note(s.grid_note);
  m.set_wall_time_s(s.wall_time_s);
  m.set_detected_initial_state(model::InitialStateName(s.detected));
  for (size_t i = 0; i < s.ranking.size(); ++i) {
    const records::ModelScore& c = s.ranking[i];
    proto::SelectionCandidate& g = *m.add_ranking();
    g.set_candidate(c.candidate.Describe());
    g.set_family(c.candidate.family);
    for (const auto& e : c.candidate.effects) g.add_effects(records::EffectName(e));
    g.set_levels(c.candidate.levels);
    g.set_initial_state(model::InitialStateName(c.candidate.initial_state));
    g.set_parameters(static_cast<int64_t>(c.parameters));
    g.set_round(c.round);
    g.set_cv_rmse(c.cv_rmse);
    g.set_cv_se(c.cv_se);
    if (c.round == 2) {
      g.set_se_vs_best(c.se_vs_best);
      g.set_within_one_se(c.within_one_se);
    }
    for (double r : c.fold_rmse) g.add_fold_rmse(r);
    g.set_withheld_rmse_after_choice(c.withheld_rmse);
    g.set_train_rmse(c.train_rmse);
    g.set_chosen(i == s.chosen);
    if (!c.error.empty()) g.set_error(c.error);
    if (std::isfinite(c.parting)) g.set_parting(c.parting);
  }
  for (const auto& e : s.initial_states) {
    proto::SelectionInitialState& g = *m.add_initial_states();
    g.set_record(e.record);
    g.set_role(model::CaseRoleName(e.role));
    if (!e.note.empty()) {
      g.set_note(e.note);
    } else {
      g.set_from(static_cast<int64_t>(e.from));
      g.set_to(static_cast<int64_t>(e.to));
      g.set_rmse_centred(e.rmse[0]);
      g.set_rmse_descended(e.rmse[1]);
      g.set_rmse_ascended(e.rmse[2]);
      g.set_shows(model::InitialStateName(e.state));
    }
  }
  *out = std::move(m);
}

}  // namespace pz::reports
