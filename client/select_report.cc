#include "client/select_report.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "io/csv.h"

namespace pz::client {
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
  os << "  noise floor " << G(s.noise.sigma) << " " << u << " (" << s.noise.used << ")\n";
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
  os << "  chosen (the fewest parameters within one SE of the best CV RMSE): "
     << s.ranking[s.chosen].candidate.Describe() << "\n";
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
     << "training records, shown after the choice. Noise floor " << G(s.noise.sigma) << " " << u
     << " (" << s.noise.used << ").\n\n"
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

json::Value SelectionJson(const records::SelectionResult& s) {
  using namespace json;  // NOLINT
  Struct root;
  auto& f = *root.mutable_fields();
  f["method"] = Text("blocked cross-validation on the training records; one-standard-error rule");
  f["folds"] = Num(s.folds);
  f["fold_fits"] = Num(static_cast<double>(s.fold_fits));
  f["chosen"] = Text(s.ranking[s.chosen].candidate.Describe());
  f["best_cv_rmse"] = Num(s.best_cv_rmse);
  f["noise_floor"] = Num(s.noise.sigma);
  f["wall_time_s"] = Num(s.wall_time_s);
  f["detected_initial_state"] = Text(model::InitialStateName(s.detected));
  std::vector<Value> ranking;
  for (size_t i = 0; i < s.ranking.size(); ++i) {
    const records::ModelScore& c = s.ranking[i];
    Struct x;
    auto& g = *x.mutable_fields();
    g["candidate"] = Text(c.candidate.Describe());
    g["family"] = Text(c.candidate.family);
    std::vector<Value> effects;
    for (const auto& e : c.candidate.effects) effects.push_back(Text(records::EffectName(e)));
    g["effects"] = List(effects);
    g["levels"] = Num(c.candidate.levels);
    g["initial_state"] = Text(model::InitialStateName(c.candidate.initial_state));
    g["parameters"] = Num(static_cast<double>(c.parameters));
    g["round"] = Num(c.round);
    g["cv_rmse"] = Num(c.cv_rmse);
    g["cv_se"] = Num(c.cv_se);
    if (c.round == 2) {
      g["se_vs_best"] = Num(c.se_vs_best);
      g["within_one_se"] = Bool(c.within_one_se);
    }
    std::vector<Value> folds;
    for (double r : c.fold_rmse) folds.push_back(Num(r));
    g["fold_rmse"] = List(folds);
    g["withheld_rmse_after_choice"] = Num(c.withheld_rmse);
    g["train_rmse"] = Num(c.train_rmse);
    g["chosen"] = Bool(i == s.chosen);
    if (!c.error.empty()) g["error"] = Text(c.error);
    ranking.push_back(Obj(x));
  }
  f["ranking"] = List(ranking);
  std::vector<Value> states;
  for (const auto& e : s.initial_states) {
    Struct x;
    auto& g = *x.mutable_fields();
    g["record"] = Text(e.record);
    g["role"] = Text(model::CaseRoleName(e.role));
    if (!e.note.empty()) {
      g["note"] = Text(e.note);
    } else {
      g["from"] = Num(static_cast<double>(e.from));
      g["to"] = Num(static_cast<double>(e.to));
      g["rmse_centred"] = Num(e.rmse[0]);
      g["rmse_descended"] = Num(e.rmse[1]);
      g["rmse_ascended"] = Num(e.rmse[2]);
      g["shows"] = Text(model::InitialStateName(e.state));
    }
    states.push_back(Obj(x));
  }
  f["initial_states"] = List(states);
  return Obj(root);
}

}  // namespace pz::client
