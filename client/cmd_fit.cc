// `piezoid fit`: identify one plant family on a record set of any drive (issue 14, records/fit.h),
// and `piezoid records`: check and describe a record set (io/records.h). The fit writes report.md
// (parameters, RMSE / max / NRMSE on train and on withheld records), fit.json, per-record traces
// (CSV) and figures (time traces, hysteresis loops). fit.json is versioned and holds the model
// section (client/fit_file.h) that `piezoid export` and `piezoid compensate` rebuild the model
// from. Before the fit, the excitation report
// (records/excitation.h): what the training records excite, what each withheld record needs beyond
// it, and a proposed training drive (excitation_drive.csv).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "client/cmd_service.h"
#include "client/commands.h"
#include "client/excitation_report.h"
#include "client/fit_file.h"
#include "client/plots.h"
#include "client/record_windows.h"
#include "client/residual_spectrum_report.h"
#include "client/search_flags.h"
#include "client/select_report.h"
#include "io/csv.h"
#include "io/records.h"
#include "model/preisach.h"
#include "records/excitation.h"
#include "records/extrapolation.h"
#include "records/fit.h"
#include "records/select.h"
#include "svcclient/complete_service.h"

namespace pz::client {
namespace fs = std::filesystem;
namespace {

/// The families `--family auto` tries when none are named (records::FamilyDef::auto_grid).
std::string AutoGridList() {
  std::string s;
  for (const records::FamilyDef* f : records::Families())
    if (f->auto_grid) s += (s.empty() ? "" : ", ") + std::string(f->name);
  return s;
}

/// The width of a column of record names: the longest name and two spaces, at least 16.
int NameColumnWidth(const io::RecordSet& set) {
  size_t w = 14;
  for (const io::Record& r : set.records) w = std::max(w, r.name.size());
  return static_cast<int>(w + 2);
}

/// The width of a column of roles: the longest role name of the set and two spaces.
int RoleColumnWidth(const io::RecordSet& set) {
  size_t w = 5;
  for (const io::Record& r : set.records)
    w = std::max(w, std::string_view(model::CaseRoleName(r.role)).size());
  return static_cast<int>(w + 2);
}

struct FitArgs {
  std::string records;
  // The default is the choice by cross-validation: on the real-like stack it chose the model the
  // whole grid fitted by hand ranks first (docs/performance.md, "fit --family auto").
  std::string family = "auto";
  std::vector<std::string> effects;
  std::vector<std::string> train_windows, validate_windows, test_windows;
  double settle_s = 0;
  std::string initial_state;  ///< --initial-state (empty: the default)
  std::string out = "fit-out";
  std::string algorithm = "pso";
  SearchFlags search;
  int threads = 2;
  int substeps = 2;
  int pi_operators = 12;
  std::string pi_operators_text = "12";  ///< --pi-operators: a count, or auto (preisach)
  int lm_iterations = 60;
  std::string lm_differences =
      "auto";  ///< the polish's Jacobian: auto, forward-central, forward or central
  bool no_polish = false;
  bool no_figures = false;
  bool quiet = false;
  CompleteServiceFlags service;  ///< --master: the global search's evaluations on the service
  records::FitOptions::Sizing
      sizing;  ///< the PSO budget sized by the searched parameters, but for the flags given
  opt::LineOptions line;  ///< --line-grid, --line-brackets, --line-tolerance
  // --family auto (records/select.h)
  bool pi_operators_given = false;         ///< --pi-operators: the one resolution tried
  std::vector<std::string> auto_families;  ///< --auto-families (empty: the registry's auto grid)
  int folds = 5;
  int finalists = 4;
  bool selected = false;  ///< the report's family was chosen by --family auto
};

/// The global search as run: "PSO 10 particles × ≤ 30 iterations, …, 2 repetitions (sized for 1
/// searched parameter): 340 search evaluations, 357 with the polish; 2 polishes, the kept one from
/// repetition 2's best (the search's best: repetition 1)".
std::string SearchSentence(const records::FitResult& r) {
  if (r.searched_parameters == 0)
    return "nothing searched (the weights are solved by least squares)";
  std::string s = r.algorithm == opt::SearchAlgorithm::kPso ? r.budget.Describe()
                  : r.algorithm == opt::SearchAlgorithm::kLine
                      ? "line search: " + r.line.Describe()
                      : std::string(opt::SearchAlgorithmName(r.algorithm)) + ", " +
                            std::to_string(r.budget.repetitions) + " repetitions";
  s += r.budget_sized
           ? (r.algorithm == opt::SearchAlgorithm::kLine ? " (the rule for " : " (sized for ")
           : " (as given, for ";
  s += std::to_string(r.searched_parameters) + " searched parameter" +
       (r.searched_parameters == 1 ? "" : "s");
  if (r.spectrum_solved)
    s += "; the creep spectrum's " + std::to_string(r.solved_parameters) +
         " weights solved with the family's in every evaluation, not searched";
  s += ")";
  s += ": " + std::to_string(r.search.evaluations) + " search evaluations, " +
       std::to_string(r.evaluations) + " with the polish";
  if (r.polishes > 0) {
    s += "; " + std::to_string(r.polishes) + (r.polishes == 1 ? " polish" : " polishes");
    if (r.best_polish_repetition >= 0 && r.best_polish_repetition == r.search.best_repetition) {
      s += ", the kept one from the search's best (repetition " +
           std::to_string(r.best_polish_repetition + 1) + ")";
    } else if (r.best_polish_repetition >= 0) {
      s += ", the kept one from repetition " + std::to_string(r.best_polish_repetition + 1) +
           "'s best (the search's best: repetition " +
           std::to_string(r.search.best_repetition + 1) + ")";
    }
  }
  return s;
}

std::string Fmt(double x, int prec = 4) {
  std::ostringstream s;
  s << std::setprecision(prec) << x;
  return s.str();
}

/// The fitted model's prediction is finite on the record (a withheld record's may diverge: a drive
/// beyond the training range, an oscillator's resonance).
bool Finite(const records::RecordMetrics& e) { return std::isfinite(e.rmse); }
constexpr const char* kDiverges =
    "— (the model's prediction is not finite: it diverges on this record)";

/// The NRMSE with its unit, or why there is none: a record whose measured response is constant
/// over its window has no range to divide by (records::RecordMetrics::nrmse_pct is infinite).
std::string NrmseText(const records::RecordMetrics& e) {
  return std::isfinite(e.nrmse_pct) ? Fmt(e.nrmse_pct, 3) + " %"
                                    : "— (the measured response is constant)";
}

/// The averaging window of the creep figure: one period of the dominant drive frequency (a whole
/// loop's error averages out, the drift stays), at least 5 samples.
double TrendWindow(const records::DataScale& s) {
  const double period = s.f_dom > 0 ? 1.0 / s.f_dom : 1.0;
  return std::max(period, 5.0 / s.fs);
}

/// Per record: its trace CSV (time, drive, measured, model, error; then measured and model less the
/// record's offset, so records share one frame; the error averaged over TrendWindow; measured and
/// model less the offset and the training records' straight line a·u + b) and its
/// error by reversal depth (depth_<name>.csv). Figures (when `scripts`): the trace, the loop of
/// each record less the line (measured as dots, model as a line, over the training records'
/// measured major loop in grey: minor loops inside it), one figure of error against reversal depth
/// for every record and one of the averaged error over time (creep).
void WriteTraces(const fs::path& dir, const io::RecordSet& set, const records::FitResult& r,
                 std::vector<fs::path>* scripts) {
  fs::create_directories(dir);
  const records::DataScale& scale = r.model->scale();
  const double window_s = TrendWindow(scale);
  const std::string yu = set.response_unit, du = set.drive_unit;
  // The straight line y = a u + b through the training records (offsets removed): the loops less it
  // show the hysteresis at the scale of its width, not of the stroke, so minor loops can be seen.
  const double a = scale.polarity * scale.gain;
  double b = 0, nb = 0;
  std::vector<PlotSeries> major, depth, creep;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& rec = set.records[i];
    if (rec.role != model::CaseRole::kTrain) continue;
    for (size_t k = rec.first_scored; k < rec.end_scored; ++k)
      b += rec.y[k] - r.metrics[i].offset - a * rec.u[k];
    nb += static_cast<double>(rec.scored());
    major.push_back({"trace_" + rec.name + ".csv", 2, 9, "training " + rec.name + " (measured)",
                     "lines lc rgb '#c8c8c8'"});
  }
  if (nb > 0) b /= nb;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& rec = set.records[i];
    const std::string stem = "trace_" + rec.name;
    const double offset = r.metrics[i].offset;
    const std::vector<double> trend = records::ResidualTrend(rec, r.yhat[i], window_s);
    io::WriteFileWith(dir / (stem + ".csv"), [&](std::ostream& os) {
      os << "t_s,drive_" << du << ",measured_" << yu << ",model_" << yu << ",error_" << yu
         << ",measured_less_offset_" << yu << ",model_less_offset_" << yu << ",error_mean_"
         << io::FormatNumber(window_s) << "s_" << yu << ",measured_less_line_" << yu
         << ",model_less_line_" << yu << "\n";
      for (size_t k = rec.first_scored; k < rec.end_scored; ++k) {
        os << io::FormatNumber(rec.t[k]) << "," << io::FormatNumber(rec.u[k]) << ","
           << io::FormatNumber(rec.y[k]) << "," << io::FormatNumber(r.yhat[i][k]) << ","
           << io::FormatNumber(rec.y[k] - r.yhat[i][k]) << ","
           << io::FormatNumber(rec.y[k] - offset) << "," << io::FormatNumber(r.yhat[i][k] - offset)
           << "," << io::FormatNumber(trend[k - rec.first_scored]) << ","
           << io::FormatNumber(rec.y[k] - offset - a * rec.u[k] - b) << ","
           << io::FormatNumber(r.yhat[i][k] - offset - a * rec.u[k] - b) << "\n";
      }
    });
    const std::vector<records::DepthBin> bins =
        records::ErrorByReversalDepth(rec, r.yhat[i], scale.u_max - scale.u_min);
    const std::string depth_file = "depth_" + rec.name + ".csv";
    io::WriteFileWith(dir / depth_file, [&](std::ostream& os) {
      os << "swing_lo_pct,swing_hi_pct,swing_mid_pct,pieces,samples,rmse_" << yu << "\n";
      for (const records::DepthBin& b : bins) {
        if (b.samples == 0) continue;  // an empty bin has no error to show
        const double hi = std::isfinite(b.hi) ? b.hi : b.lo + 0.2;
        os << io::FormatNumber(100 * b.lo) << ","
           << (std::isfinite(b.hi) ? io::FormatNumber(100 * b.hi) : "inf") << ","
           << io::FormatNumber(50 * (b.lo + hi)) << "," << b.pieces << "," << b.samples << ","
           << io::FormatNumber(b.rmse) << "\n";
      }
    });
    if (!scripts) continue;
    const std::string role = model::CaseRoleName(rec.role);
    const bool train = rec.role == model::CaseRole::kTrain;
    Plot trace{stem,
               rec.name + " (" + role + "): measured and " + r.model->Describe(),
               "t [s]",
               "response [" + yu + "]",
               false,
               {{stem + ".csv", 1, 3, "measured", "lines"},
                {stem + ".csv", 1, 4, "model", "lines"},
                {stem + ".csv", 1, 5, "error", "lines"}}};
    scripts->push_back(WritePlotScript(dir, trace));
    Plot loop{"loop_" + rec.name,
              rec.name + " (" + role + "): loop less the training line " + Fmt(a) + "·u + " +
                  Fmt(b) + " " + yu,
              "drive [" + du + "]",
              "response − offset (" + Fmt(offset) + ") − line [" + yu + "]",
              false,
              {}};
    // The y range of the loop: the model's and 99.8 % of the measured samples, so that a sample or
    // two at a jump from rest (a sensor lag reads the old level) does not squash the loops; they
    // stay in the trace figure and the CSV, and the title counts them.
    std::vector<double> measured, model;
    for (size_t k = rec.first_scored; k < rec.end_scored; ++k) {
      measured.push_back(rec.y[k] - offset - a * rec.u[k] - b);
      model.push_back(r.yhat[i][k] - offset - a * rec.u[k] - b);
    }
    std::vector<double> sorted = measured;
    std::sort(sorted.begin(), sorted.end());
    const size_t cut = sorted.size() / 1000;
    double lo = sorted[cut], hi = sorted[sorted.size() - 1 - cut];
    for (double x : model) {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    const double pad = 0.08 * std::max(hi - lo, 1e-12);
    lo -= pad;
    hi += pad;
    const auto outside =
        std::count_if(measured.begin(), measured.end(), [&](double x) { return x < lo || x > hi; });
    if (outside > 0) {
      loop.yrange = "[" + io::FormatNumber(lo) + ":" + io::FormatNumber(hi) + "]";
      loop.title += "; " + std::to_string(outside) + " sample(s) off-scale";
    }
    if (!train) loop.series = major;  // the major loop behind: the withheld minor loops inside it
    loop.series.push_back(
        {stem + ".csv", 2, 9, rec.name + " measured", "points pt 7 ps 0.3 lc rgb '#1f77b4'"});
    loop.series.push_back({stem + ".csv", 2, 10, rec.name + " model", "lines lc rgb '#d62728'"});
    scripts->push_back(WritePlotScript(dir, loop));
    depth.push_back({depth_file, 3, 6, rec.name + " (" + role + ")",
                     train ? "points pt 5 ps 1.5" : "linespoints pt 7 ps 1.2"});
    creep.push_back({stem + ".csv", 1, 8, rec.name + " (" + role + ")", "lines"});
  }
  if (!scripts) return;
  scripts->push_back(WritePlotScript(dir, Plot{"error_vs_depth",
                                               "RMSE of each monotone piece of the drive by its "
                                               "swing (minor loops are the shallow pieces)",
                                               "swing [% of the training drive range], bin centre",
                                               "RMSE [" + yu + "]", true, depth, "[0:100]"}));
  scripts->push_back(
      WritePlotScript(dir, Plot{"creep",
                                "error (measured − model) averaged over " + Fmt(window_s, 3) +
                                    " s: slow drift is creep the model lacks",
                                "t [s]", "mean error [" + yu + "]", false, creep}));
}

/// report.md's parameter table (value, unit, range, σ, sensitivity, identifiability; the solved
/// weights), the uncertainty's note and the regularisations chosen.
void WriteParametersSection(std::ostream& os, const io::RecordSet& set,
                            const records::FitResult& r) {
  const auto& m = *r.model;
  const auto& u = r.uncertainty;
  os << "## Parameters\n\n| parameter | value | unit | search range | ± σ | sensitivity ["
     << set.response_unit << "] | identifiability |\n|---|---|---|---|---|---|---|\n";
  for (size_t i = 0; i < m.params().size(); ++i) {
    const auto& p = m.params()[i];
    os << "| " << p.name << " | " << Fmt(r.params[i], 6) << " | " << p.unit << " | ["
       << Fmt(p.lower) << ", " << Fmt(p.upper) << "]" << (p.log_scale ? " log" : "") << " | ";
    if (i < u.params.size()) {
      const auto& e = u.params[i];
      os << (std::isfinite(e.std_error) ? Fmt(e.std_error, 3) : "—") << " | "
         << Fmt(e.sensitivity, 3) << " | " << opt::IdentifiabilityName(e.identifiability)
         << (e.note.empty() ? "" : "; " + e.note) << " |\n";
    } else {
      os << " | | |\n";
    }
  }
  const auto wn = m.family().weight_names();
  for (size_t i = 0; i < r.weights.size(); ++i) {
    os << "| " << wn[i] << " | " << Fmt(r.weights[i], 6)
       << " | y/V | ≥ 0 (least squares) | | | |\n";
  }
  if (!u.params.empty()) {
    os << "\nσ from the training residuals (s = " << Fmt(u.residual_sigma, 4) << " "
       << set.response_unit
       << ") and their Jacobian at the solution; sensitivity: the RMS change of the output per "
          "step of one "
          "unit range (a log-scaled parameter: ∂x/∂u). Singular values of J·diag(scale):";
    for (double v : u.singular_values) os << " " << Fmt(v, 3);
    os << "; weakest direction: " << u.weakest_direction << ".";
    if (!r.weights.empty())
      os << " The solved weights are not in the table (they follow from the others).";
    os << "\n";
  }
  if (r.resolution.used) os << "\nPreisach grid: " << r.resolution.Describe() << ".\n";
  if (r.regularisation.used)
    os << "\nRegularisation of the weights: " << r.regularisation.Describe() << ".\n";
  if (r.spectrum_regularisation.used)
    os << "\nRoughness penalty of the creep spectrum's weights (towards equal weights per decade): "
       << r.spectrum_regularisation.Describe() << ".\n";
  if (const std::string s = r.SpectrumIdentification(); !s.empty()) os << "\nNote: " << s << ".\n";
}

void WriteFitReport(std::ostream& os, const io::RecordSet& set, const records::FitResult& r,
                    const FitArgs& a, const records::ExcitationReport& excitation,
                    const records::TrainingDriveProposal& proposal,
                    const std::vector<records::ExtrapolationCheck>& extrapolation) {
  const auto& m = *r.model;
  os << "# piezoid fit: " << m.Describe() << "\n\n"
     << "Records: `" << set.source.string() << "` (" << set.format << ", " << set.records.size()
     << " records; drive in " << set.drive_unit << ", response in " << set.response_unit << ").\n\n"
     << "Model: " << m.family().title() << " — `" << m.family().equation() << "`";
  for (records::EffectKind e : m.effects()) os << "; + " << records::EffectName(e);
  os << ".\nOutput polarity " << (m.scale().polarity > 0 ? "+1" : "-1")
     << " (sign of the drive-to-response slope); offsets per record as stated below.\n"
     << "Data scale (training records, sets the search ranges): drive " << Fmt(m.scale().u_min)
     << " … " << Fmt(m.scale().u_max) << " " << set.drive_unit << ", response half range "
     << Fmt(m.scale().y_half) << " " << set.response_unit << ", gain " << Fmt(m.scale().gain) << " "
     << set.response_unit << "/" << set.drive_unit << ", dominant frequency "
     << Fmt(m.scale().f_dom) << " Hz, sampled at " << Fmt(m.scale().fs) << " Hz.\n\n";
  WriteParametersSection(os, set, r);
  os << "\n## Errors\n\n";
  if (const std::string s = InitialStateSentence(m.family()); !s.empty()) os << s << "\n\n";
  if (a.settle_s > 0) os << SettlingSentence(a.settle_s) << "\n\n";
  os << "| record | role | window [s] | samples | offset | RMSE | max | max at [s] | NRMSE [% of "
        "range] |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  for (size_t i = 0; i < set.records.size(); ++i) {
    const auto& rec = set.records[i];
    const auto& e = r.metrics[i];
    os << "| " << rec.name << " | " << model::CaseRoleName(rec.role) << " | "
       << Fmt(rec.t[rec.first_scored]) << "–" << Fmt(rec.t[rec.end_scored - 1]) << " | "
       << e.samples << " | " << Fmt(e.offset) << " (" << io::OffsetModeName(rec.offset_mode)
       << ") | ";
    if (Finite(e)) {
      os << Fmt(e.rmse) << " | " << Fmt(e.max_abs) << " | " << Fmt(e.max_at_s) << " | "
         << NrmseText(e) << " |\n";
    } else {
      os << kDiverges << " | | | |\n";
    }
  }
  if (!extrapolation.empty()) {
    os << "\n## Extrapolation (records/extrapolation.h)\n\n";
    for (const auto& c : extrapolation)
      os << "- " << c.Describe(set.drive_unit, set.response_unit) << "\n";
    os << "\nError against reversal depth (each monotone piece of the drive by its swing, % of the "
          "training drive "
          "range; minor loops are the shallow pieces):\n\n";
    for (size_t i = 0; i < set.records.size(); ++i) {
      const auto& rec = set.records[i];
      if (rec.role == model::CaseRole::kTrain) continue;
      os << "- " << rec.name << ": "
         << (Finite(r.metrics[i]) ? records::DescribeDepthBins(records::ErrorByReversalDepth(
                                        rec, r.yhat[i], m.scale().u_max - m.scale().u_min))
                                  : std::string(kDiverges))
         << "\n";
    }
  }
  if (!a.no_figures) {
    os << "\n## Figures (figures/)\n\n"
       << "- `loop_<record>.png`: the hysteresis loop, response less the record's offset and the "
          "training records' "
          "straight line a·u + b against drive (the loop at the scale of its width), measured "
          "(dots) and model (line); "
          "a withheld record's loops over the training records' measured major loop (grey): its "
          "minor loops inside it.\n"
       << "- `error_vs_depth.png`: the RMSE of each record's monotone drive pieces by their swing "
          "(the table above, "
          "`depth_<record>.csv`): shallow swings are minor loops.\n"
       << "- `creep.png`: the error averaged over " << Fmt(TrendWindow(m.scale()), 3)
       << " s (one period of the dominant drive frequency, column 8 of `trace_<record>.csv`): a "
          "slow drift is creep "
          "the model lacks.\n"
       << "- `trace_<record>.png`: measured, model and error over time.\n";
  }
  os << "\nSearch: " << SearchSentence(r) << ".\n";
  os << "\nUnits: " << set.response_unit << ". Training MSE " << Fmt(r.train_mse, 6) << "; "
     << r.evaluations << " evaluations, " << Fmt(r.wall_time_s, 3) << " s";
  if (!r.stop_reason.empty()) os << "; search stop: " << r.stop_reason;
  os << "; LM iterations " << r.lm_iterations << " (" << r.lm_differences
     << " differences).\n\nCommand: `piezoid fit --records " << a.records << " --family "
     << (a.selected ? "auto" : a.family) << "`"
     << (a.selected ? " (this model chosen: the section below)" : "") << ".\n";
  WriteExcitationMarkdown(os, set, excitation, proposal, kProposedDriveFile);
}

/// The fit's options of the flags (--family auto: the selection's fit options), checked: the
/// families of --auto-families, --initial-state, the preisach grid's bound on --pi-operators.
records::FitOptions FitOptionsOf(const FitArgs& a) {
  const bool select = a.family == "auto";
  records::FitOptions o;
  o.family = a.family;
  for (const auto& e : a.effects) o.effects.push_back(records::ParseEffect(e));
  o.family_options.substeps = a.substeps;
  o.family_options.pi_operators = a.pi_operators;
  if (select) {
    if (!a.initial_state.empty())
      o.family_options.initial_state = model::ParseInitialState(a.initial_state, "--initial-state");
    for (const auto& f : a.auto_families)
      if (records::FindFamily(f) == nullptr)
        throw InputError("--auto-families '" + f +
                         "': not a family (families: " + records::FamilyList() + ")");
  } else {
    if (!a.auto_families.empty()) throw InputError("--auto-families: only with --family auto");
    o.family_options.initial_state = InitialStateOfFlag(a.initial_state, a.family);
  }
  // The grid's own bound, refused under the flag's name.
  if ((a.family == "preisach" || (select && a.pi_operators_given)) &&
      a.pi_operators != records::kAutoLevels) {
    const Status levels = model::PreisachGrid{0, 1, a.pi_operators}.Validate();
    if (!levels.ok() && (!select || a.auto_families.empty() ||
                         std::find(a.auto_families.begin(), a.auto_families.end(), "preisach") !=
                             a.auto_families.end()))
      throw InputError("--pi-operators " + std::to_string(a.pi_operators) + ": " +
                       levels.message());
  }
  if (a.service.enabled() && !select)
    o.evaluator_factory =
        svcclient::RecordsServiceFactory(a.service.Options(), o.family_options, "piezoid fit");
  o.search.algorithm = opt::ParseSearchAlgorithm(a.algorithm);
  ApplySearchFlags(a.search, &o.search);
  o.search.line = a.line;
  o.sizing = a.sizing;
  o.polish_repetitions = true;
  o.polish = !a.no_polish;
  o.lm.max_iterations = a.lm_iterations;
  o.lm.central = a.lm_differences == "central";
  o.lm.central_to_finish = a.lm_differences == "forward-central";
  o.lm_differences_auto = a.lm_differences == "auto";
  o.threads = a.threads;
  if (!a.quiet) o.progress = [](const std::string& s) { std::cout << "  " << s << std::endl; };
  return o;
}

/// The fit, or with --family auto the selection and its fit (`a` then names the chosen family,
/// resolution and effects). A service error is printed and its exit code returned.
std::optional<int> FitOrSelect(const io::RecordSet& set, const records::FitOptions& o, FitArgs& a,
                               records::FitResult& r, records::SelectionResult& selection) {
  const bool select = a.family == "auto";
  try {
    if (select) {
      records::SelectOptions so;
      so.fit = o;
      so.fit.progress = nullptr;
      so.initial_state_given = !a.initial_state.empty();
      so.families = a.auto_families;
      if (a.pi_operators_given) so.levels = {a.pi_operators};
      if (!o.effects.empty()) so.effect_sets = {o.effects};
      so.folds = a.folds;
      so.finalists = static_cast<size_t>(a.finalists);
      if (a.service.enabled()) {
        const svcclient::ServiceEvaluatorOptions service = a.service.Options();
        so.service = [service](const records::FamilyOptions& f) {
          return svcclient::RecordsServiceFactory(service, f, "piezoid fit --family auto");
        };
      }
      if (!a.quiet) so.progress = [](const std::string& s) { std::cout << "  " << s << std::endl; };
      selection = records::SelectModel(set, so);
      r = selection.fit;
      a.family = r.model->family().name();
      a.pi_operators = selection.fit_options.family_options.pi_operators;
      a.effects.clear();
      for (records::EffectKind e : r.model->effects()) a.effects.push_back(records::EffectName(e));
      a.selected = true;
      PrintSelection(std::cout, set, selection);
    } else {
      r = records::FitRecords(set, o);
    }
  } catch (const svcclient::ServiceError& e) {
    std::cerr << "piezoid fit: error: " << e.what() << "\n";
    return ExitCodeOf(e.status());
  }
  return std::nullopt;
}

/// report.md, fit.json, the proposed training drive, the traces and (unless --no-figures) the
/// figures in --out.
void WriteFitOutputs(const io::RecordSet& set, const records::FitResult& r, const FitArgs& a,
                     const records::ExcitationReport& excitation,
                     const records::TrainingDriveProposal& proposal,
                     const std::vector<records::ExtrapolationCheck>& extrapolation,
                     const records::SelectionResult* selection) {
  fs::create_directories(a.out);
  WriteProposedDrive(fs::path(a.out) / kProposedDriveFile, set, proposal);
  io::WriteFileWith(fs::path(a.out) / "report.md", [&](std::ostream& os) {
    WriteFitReport(os, set, r, a, excitation, proposal, extrapolation);
    WriteFittedModeMarkdown(os, set, r);
    WriteResidualSpectrumMarkdown(os, set, r, nullptr);
    if (selection) WriteSelectionMarkdown(os, set, *selection);
  });
  io::WriteFileWith(fs::path(a.out) / "fit.json", [&](std::ostream& os) {
    os << FitJson(set, r, excitation, proposal, extrapolation, selection,
                  {.settle_s = a.settle_s,
                   .substeps = a.substeps,
                   .pi_operators = a.pi_operators,
                   .search = SearchSentence(r),
                   .drive_file = kProposedDriveFile});
  });
  std::vector<fs::path> scripts;
  WriteTraces(fs::path(a.out) / "figures", set, r, a.no_figures ? nullptr : &scripts);
  if (!a.no_figures)
    WriteResidualSpectrumFigures(fs::path(a.out) / "figures", set, r, nullptr, scripts);
  if (!scripts.empty()) {
    std::vector<std::string> errors;
    if (GnuplotAvailable()) {
      RenderPlots(fs::path(a.out) / "figures", scripts, &errors);
    } else {
      errors.push_back("gnuplot not found: figure scripts written to " +
                       (fs::path(a.out) / "figures").string());
    }
    for (const auto& e : errors) std::cerr << "piezoid fit: warning: " << e << "\n";
  }
}

/// The console's summary: each record's errors, the resolution and regularisation chosen, the
/// extrapolation warnings and the search.
void PrintFitSummary(const io::RecordSet& set, const records::FitResult& r, const FitArgs& a,
                     const std::vector<records::ExtrapolationCheck>& extrapolation) {
  const int name_width = NameColumnWidth(set), role_width = RoleColumnWidth(set);
  for (size_t i = 0; i < set.records.size(); ++i) {
    const auto& e = r.metrics[i];
    std::cout << "  " << std::left << std::setw(role_width) << model::CaseRoleName(e.role)
              << std::setw(name_width) << e.name << " ";
    if (Finite(e)) {
      std::cout << "RMSE " << Fmt(e.rmse) << " " << set.response_unit << ", max " << Fmt(e.max_abs)
                << " at " << Fmt(e.max_at_s) << " s, NRMSE " << NrmseText(e) << "\n";
    } else {
      std::cout << kDiverges << "\n";
    }
  }
  if (r.resolution.used) std::cout << "  preisach grid: " << r.resolution.Describe() << "\n";
  if (r.regularisation.used)
    std::cout << "  regularisation: " << r.regularisation.Describe() << "\n";
  if (r.spectrum_regularisation.used)
    std::cout << "  creep spectrum: roughness " << r.spectrum_regularisation.Describe() << "\n";
  if (const std::string s = r.SpectrumIdentification(); !s.empty())
    std::cout << "  note: " << s << "\n";
  for (const auto& c : extrapolation)
    if (c.flagged)
      std::cout << "  warning: extrapolation: " << c.Describe(set.drive_unit, set.response_unit)
                << "\n";
  std::cout << "  search: " << SearchSentence(r) << "\n";
  std::cout << r.evaluations << " evaluations in " << Fmt(r.wall_time_s, 3) << " s"
            << (a.service.enabled()
                    ? " (search and polish on the workers of " + a.service.master + ")"
                    : std::string())
            << "; report in " << (fs::path(a.out) / "report.md").string() << "\n";
}

int RunFit(const FitArgs& args) {
  FitArgs a = args;  // --family auto: the chosen family and resolution replace the flag's
  const bool select = a.family == "auto";
  io::RecordSet set = LoadRecordSetWithWindows(a.records, a.train_windows, a.validate_windows,
                                               a.test_windows, a.settle_s);
  const records::FitOptions o = FitOptionsOf(a);
  std::cout << "piezoid fit: " << set.records.size() << " record(s) from " << a.records << " ("
            << set.format << "), family " << a.family << std::endl;
  const records::ExcitationReport excitation = records::AnalyseExcitation(set);
  const records::TrainingDriveProposal proposal = records::ProposeTrainingDrive(set, excitation);
  PrintExcitationSummary(std::cout, set, excitation);
  records::FitResult r;
  records::SelectionResult selection;
  if (const std::optional<int> code = FitOrSelect(set, o, a, r, selection)) return *code;
  const std::vector<records::ExtrapolationCheck> extrapolation =
      records::CheckExtrapolation(set, r);
  WriteFitOutputs(set, r, a, excitation, proposal, extrapolation, select ? &selection : nullptr);
  PrintFitSummary(set, r, a, extrapolation);
  return 0;
}

}  // namespace

namespace {

constexpr const char* kPiOperatorsRule = "must be a count in 1 … 10000, or auto (preisach)";

/// --pi-operators as a count 1 … 10000 (the whole text a number), or none.
std::optional<int> PiOperatorsCount(const std::string& text) {
  size_t used = 0;
  int n = 0;
  try {
    n = std::stoi(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != text.size() || n < 1 || n > 10000) return std::nullopt;
  return n;
}

/// One searched parameter: the line search's budget (records::FitOptions::Sizing,
/// opt::LineOptions): --line-grid, --line-brackets, --line-tolerance.
void AddLineFlags(CLI::App* cmd, opt::LineOptions* out) {
  const opt::LineOptions line;
  cmd->add_option("--line-grid", out->grid,
                  "one searched parameter (the default search then): grid points over its range, "
                  "ends included")
      ->check(CLI::Range(3, 100000))
      ->default_str(std::to_string(line.grid));
  cmd->add_option(
         "--line-brackets", out->brackets,
         "one searched parameter: the grid's lowest local minima refined by Brent's method")
      ->check(CLI::Range(1, 100000))
      ->default_str(std::to_string(line.brackets));
  cmd->add_option("--line-tolerance", out->tolerance,
                  "one searched parameter: Brent's tolerance, a fraction of the range, in (0, 0.5)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            double x = 0;
            if (!CLI::detail::lexical_cast(v, x) || !(x > 0 && x < 0.5))
              return "Value " + v + " not in (0, 0.5)";
            return "";
          },
          "in (0, 0.5)"))
      ->default_str(io::FormatNumber(line.tolerance));
}

}  // namespace

void RegisterFit(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<FitArgs>();
  CLI::App* cmd =
      app.add_subcommand("fit",
                         "Identify a plant family on measured records of any drive (a record-set "
                         "folder with manifest.csv, "
                         "a stack or fin bench folder, or one CSV file with windows): global "
                         "search + Levenberg-Marquardt, "
                         "offsets explicit; writes report.md, fit.json, traces and loop figures.");
  cmd->add_option("--records", a->records,
                  "record set: folder (manifest.csv) or one CSV (time, drive, response)")
      ->required()
      ->type_name("PATH");
  cmd->add_option("--family", a->family,
                  "auto (chosen with its effects, plays / levels and initial state by blocked "
                  "cross-validation on the training records; records/select.h), " +
                      records::FamilyList())
      ->default_str("auto");
  cmd->add_option(
         "--auto-families", a->auto_families,
         "--family auto: the families tried (comma-separated; default " + AutoGridList() + ")")
      ->delimiter(',');
  cmd->add_option("--folds", a->folds,
                  "--family auto: blocks per training window (the cross-validation's folds)")
      ->check(CLI::Range(2, 50))
      ->default_str("5");
  cmd->add_option(
         "--finalists", a->finalists,
         "--family auto: the screening round's best cross-validated again with the full search")
      ->check(CLI::Range(1, 100))
      ->default_str("4");
  cmd->add_option("--effects", a->effects, "effects added to the family (comma-separated)")
      ->delimiter(',');
  cmd->add_option("--train-window", a->train_windows,
                  "one CSV: a training window START:END [s] (repeatable)");
  cmd->add_option("--validate-window", a->validate_windows,
                  "one CSV: a withheld validation window START:END [s]");
  cmd->add_option("--test-window", a->test_windows,
                  "one CSV: a withheld test window START:END [s]");
  cmd->add_option("--settle-s", a->settle_s,
                  "score every record from this long after the end of its rest [s] (the models "
                  "start at rest with the "
                  "memory of --initial-state; docs/records.md)")
      ->check(CLI::Range(0.0, 1e6));
  AddInitialStateFlag(cmd, &a->initial_state);
  cmd->add_option("--out", a->out, "output folder")->default_str("fit-out");
  cmd->add_option("--algorithm", a->algorithm,
                  "pso, ga-real, ga-binary, de or line (one searched parameter)")
      ->default_str("pso; line for one searched parameter");
  AddSearchFlags(cmd, &a->search, /*sized=*/true);
  AddLineFlags(cmd, &a->line);
  cmd->add_option("--lm-iterations", a->lm_iterations, "Levenberg-Marquardt polish iterations")
      ->default_str("60");
  cmd->add_option(
         "--lm-differences", a->lm_differences,
         "the polish's Jacobian: auto (forward after the line search of one parameter, else "
         "forward-central), forward-central (forward differences, p + 1 evaluations, until the "
         "polish "
         "converges, then central ones from there until it converges again), forward, or central "
         "(2 p)")
      ->check(CLI::IsMember({"auto", "forward-central", "forward", "central"}))
      ->default_str("auto");
  cmd->add_flag("--no-polish", a->no_polish, "no Levenberg-Marquardt after the search");
  cmd->add_option("--threads", a->threads, "evaluation threads")->default_str("2");
  cmd->add_option("--substeps", a->substeps, "integration sub-steps per sample (1 … 512)")
      ->default_str("2");
  cmd->add_option("--pi-operators", a->pi_operators_text,
                  "Prandtl-Ishlinskii / asymmetric-pi play operators (1 … 10000); preisach grid "
                  "levels (1 … 200), or auto: the levels chosen by cross-validation on the "
                  "training records")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            if (v == "auto" || PiOperatorsCount(v)) return "";
            return std::string(kPiOperatorsRule) + ", not " + v;
          },
          "COUNT|auto"))
      ->default_str("12");
  cmd->add_flag("--no-figures", a->no_figures, "no figures (the trace CSVs are still written)");
  cmd->add_flag("--quiet", a->quiet, "no progress lines");
  AddCompleteServiceFlags(cmd, a->service);  // --master: the same result, bit for bit
  cmd->callback([a, cmd, &exit_code] {
    // The PSO budget is sized by the searched parameters (records::SizedSearchBudget) but for the
    // search flags given.
    a->sizing.enabled = true;
    a->sizing.keep_particles = cmd->count("--particles") > 0;
    a->sizing.keep_iterations = cmd->count("--iterations") > 0;
    a->sizing.keep_stall = cmd->count("--stall") > 0;
    a->sizing.keep_repetitions = cmd->count("--repetitions") > 0;
    a->sizing.keep_algorithm = cmd->count("--algorithm") > 0;
    a->sizing.line_given = cmd->count("--line-grid") > 0 || cmd->count("--line-brackets") > 0 ||
                           cmd->count("--line-tolerance") > 0;
    // --pi-operators: a count 1 … 10000, or auto for the preisach grid (its levels by validation).
    const std::string& ops = a->pi_operators_text;
    if (ops == "auto") {
      if (a->family != "preisach")
        throw InputError(
            "--pi-operators auto: the levels chosen by validation are the preisach "
            "family's; give a count for " +
            a->family);
      a->pi_operators = records::kAutoLevels;
    } else {
      const std::optional<int> n = PiOperatorsCount(ops);
      if (!n) throw InputError("--pi-operators " + ops + ": " + kPiOperatorsRule);
      a->pi_operators = *n;
    }
    a->pi_operators_given = cmd->count("--pi-operators") > 0;
    exit_code = RunFit(*a);
  });
}

void RegisterRecords(CLI::App& app, int& exit_code) {
  auto path = std::make_shared<std::string>();
  auto convert = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "records",
      "Check a record set and describe it (records, roles, windows, units, rest, sample rate, "
      "quantum, repeat groups, the noise floor); --convert writes it in the manifest format.");
  cmd->add_option("path,--records", *path, "record set folder or CSV file")->required();
  cmd->add_option("--convert", *convert, "write the set as a manifest-format folder");
  cmd->callback([path, convert, &exit_code] {
    const io::RecordSet set = io::LoadRecordSet(*path);
    std::cout << set.source.string() << ": " << set.format << ", " << set.records.size()
              << " record(s), drive in " << set.drive_unit << ", response in " << set.response_unit
              << "\n";
    const int name_width = NameColumnWidth(set), role_width = RoleColumnWidth(set);
    for (const io::Record& r : set.records) {
      std::cout << "  " << std::left << std::setw(name_width) << r.name << std::setw(role_width)
                << model::CaseRoleName(r.role) << r.size() << " samples at "
                << Fmt(r.sample_rate_hz(), 6) << " Hz, scored " << Fmt(r.t[r.first_scored]) << "–"
                << Fmt(r.t[r.end_scored - 1]) << " s (" << r.scored() << "), rest "
                << Fmt(r.rest_samples * r.dt) << " s, offset " << io::OffsetModeName(r.offset_mode);
      if (r.offset_mode != io::OffsetMode::kFit) std::cout << " " << Fmt(r.offset);
      if (r.quantum > 0) std::cout << ", quantum " << Fmt(r.quantum);
      if (!r.repeat.empty()) std::cout << ", repeat group " << r.repeat;
      std::cout << "\n";
    }
    // The noise floor from the records alone (records/noise_floor.h): every estimate.
    try {
      const records::NoiseFloor nf = records::EstimateNoiseFloor(set);
      std::cout << "noise floor " << nf.Summary(set.response_unit) << "\n";
      for (const records::NoiseEstimate& e : nf.estimates)
        std::cout << "  " << e.method << ": " << Fmt(e.sigma) << " " << set.response_unit << " ("
                  << e.samples << " samples; " << e.detail << ")\n";
      if (!nf.warning.empty()) std::cout << "  warning: " << nf.warning << "\n";
    } catch (const InputError& e) {
      std::cout << "noise floor: none (" << e.what() << ")\n";
    }
    if (!convert->empty()) {
      io::WriteRecordSet(set, *convert);
      std::cout << "written to " << *convert << "\n";
    }
    exit_code = 0;
  });
}

}  // namespace pz::client
