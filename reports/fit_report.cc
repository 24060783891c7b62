#include "reports/fit_report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "io/csv.h"
#include "records/extrapolation.h"
#include "reports/excitation_report.h"
#include "reports/fit_file.h"
#include "reports/plots.h"
#include "reports/record_windows.h"
#include "reports/residual_spectrum_report.h"
#include "reports/select_report.h"

namespace pz::reports {
namespace fs = std::filesystem;
namespace {

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
                    const FitReportRun& a, const records::ExcitationReport& excitation,
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
  if (a.figures) {
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

}  // namespace

std::vector<std::string> WriteFitFolder(
    const io::RecordSet& set, const records::FitResult& r, const FitReportRun& a,
    const records::ExcitationReport& excitation, const records::TrainingDriveProposal& proposal,
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
  WriteTraces(fs::path(a.out) / "figures", set, r, a.figures ? &scripts : nullptr);
  if (a.figures)
    WriteResidualSpectrumFigures(fs::path(a.out) / "figures", set, r, nullptr, scripts);
  std::vector<std::string> errors;
  if (!scripts.empty()) {
    if (GnuplotAvailable()) {
      RenderPlots(fs::path(a.out) / "figures", scripts, &errors);
    } else {
      errors.push_back("gnuplot not found: figure scripts written to " +
                       (fs::path(a.out) / "figures").string());
    }
  }
  return errors;
}

void PrintFitSummary(std::ostream& out, const io::RecordSet& set, const records::FitResult& r,
                     const FitReportRun& a,
                     const std::vector<records::ExtrapolationCheck>& extrapolation) {
  const int name_width = NameColumnWidth(set), role_width = RoleColumnWidth(set);
  for (size_t i = 0; i < set.records.size(); ++i) {
    const auto& e = r.metrics[i];
    out << "  " << std::left << std::setw(role_width) << model::CaseRoleName(e.role)
        << std::setw(name_width) << e.name << " ";
    if (Finite(e)) {
      out << "RMSE " << Fmt(e.rmse) << " " << set.response_unit << ", max " << Fmt(e.max_abs)
          << " at " << Fmt(e.max_at_s) << " s, NRMSE " << NrmseText(e) << "\n";
    } else {
      out << kDiverges << "\n";
    }
  }
  if (r.resolution.used) out << "  preisach grid: " << r.resolution.Describe() << "\n";
  if (r.regularisation.used) out << "  regularisation: " << r.regularisation.Describe() << "\n";
  if (r.spectrum_regularisation.used)
    out << "  creep spectrum: roughness " << r.spectrum_regularisation.Describe() << "\n";
  if (const std::string s = r.SpectrumIdentification(); !s.empty()) out << "  note: " << s << "\n";
  for (const auto& c : extrapolation)
    if (c.flagged)
      out << "  warning: extrapolation: " << c.Describe(set.drive_unit, set.response_unit) << "\n";
  out << "  search: " << SearchSentence(r) << "\n";
  out << r.evaluations << " evaluations in " << Fmt(r.wall_time_s, 3) << " s"
      << (!a.master.empty() ? " (search and polish on the workers of " + a.master + ")"
                            : std::string())
      << "; report in " << (fs::path(a.out) / "report.md").string() << "\n";
}

}  // namespace pz::reports
