#include "reports/boucwen_report.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "boucwen.pb.h"
#include "complete/boucwen_benchmark.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "reports/plots.h"

namespace pz::reports {
namespace {

using complete::kBwSampleRateHz;

std::string Sci(double v, int digits = 4) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*e", digits - 1, v);
  return buf;
}

/// The run as report.json's message (proto/boucwen.proto; the one conversion).
proto::BoucwenReport ReportOf(const BoucwenRun& a, const BwOutcome& o) {
  const opt::SearchResult& result = o.result;
  proto::BoucwenReport r;
  r.set_algorithm(opt::SearchAlgorithmName(o.options.algorithm));
  r.set_seed(a.seed);
  r.set_repetitions(o.options.repetitions);
  r.set_threads(o.threads);
  r.set_evaluated_on(a.on_service ? "service" : "local");
  r.set_substeps(a.substeps);
  r.set_training_samples(static_cast<int64_t>(o.n_train));
  r.set_evaluations(result.evaluations);
  r.set_iterations(result.iterations);
  r.set_wall_time_s(result.wall_time_s);
  r.set_evaluations_per_s(static_cast<double>(result.evaluations) / result.wall_time_s);
  r.set_evaluations_to_final(result.trace.evaluations[o.reach]);
  r.set_seconds_to_final(result.trace.wall_time_s[o.reach]);
  r.set_stop_reason(result.stop_reason);
  r.set_best_repetition(result.best_repetition);
  r.set_training_rms_m(o.train_rms);
  r.set_test_multisine_rms_m(o.rms_ms);
  r.set_test_sinesweep_rms_m(o.rms_sw);
  r.set_test_multisine_max_abs_m(o.max_ms);
  r.set_test_sinesweep_max_abs_m(o.max_sw);
  r.set_true_model_multisine_rms_m(o.rms_ms_true);
  r.set_true_model_sinesweep_rms_m(o.rms_sw_true);
  for (size_t i = 0; i < o.box.size(); ++i) {
    proto::BoucwenParameter& p = (*r.mutable_parameters())[o.box.names[i]];
    p.set_identified(result.best[i]);
    p.set_true_(o.theta_true[i]);
    p.set_relative_error(result.best[i] / o.theta_true[i] - 1);
    p.set_lower(o.box.lower[i]);
    p.set_upper(o.box.upper[i]);
  }
  for (double c : result.repetition_costs) r.add_repetition_training_rms_m(std::sqrt(c));
  return r;
}

void WriteReportMarkdown(const std::filesystem::path& file, const BoucwenRun& a,
                         const BwOutcome& o) {
  const opt::SearchResult& result = o.result;
  io::WriteFileWith(file, [&](std::ostream& os) {
    os << "# Bouc–Wen benchmark: complete-model identification\n\n"
       << "Algorithm " << opt::SearchAlgorithmName(o.options.algorithm) << ", "
       << o.options.repetitions << " repetitions from seed " << a.seed << " (best kept: repetition "
       << result.best_repetition << ", " << result.stop_reason << "); " << result.evaluations
       << " evaluations in " << result.wall_time_s << " s on " << o.threads << o.where
       << ". Training: train_A + train_B (" << o.n_train
       << " samples; train_A simulated from rest, train_B, a steady-state record, after a "
          "one-period warm-up), "
          "output-error MSE of a free-run simulation (RK4, "
       << a.substeps << " sub-steps per sample).\n\n"
       << "| parameter | identified | true | error |\n| --- | --- | --- | --- |\n";
    for (size_t i = 0; i < o.box.size(); ++i) {
      char e[32];
      std::snprintf(e, sizeof e, "%+.3f %%", 100 * (result.best[i] / o.theta_true[i] - 1));
      os << "| " << o.box.names[i] << " | " << Sci(result.best[i], 6) << " | "
         << Sci(o.theta_true[i], 6) << " | " << e << " |\n";
    }
    os << "\n| set | simulation RMS error [m] | max abs error [m] | true model RMS [m] |\n| --- | "
          "--- | --- | --- |\n"
       << "| training (A + B, noisy) | " << Sci(o.train_rms) << " | | |\n"
       << "| test multisine | " << Sci(o.rms_ms) << " | " << Sci(o.max_ms) << " | "
       << Sci(o.rms_ms_true) << " |\n"
       << "| test sine sweep | " << Sci(o.rms_sw) << " | " << Sci(o.max_sw) << " | "
       << Sci(o.rms_sw_true) << " |\n\n"
       << "Best published black-box result on the multisine test set: 7.53e-6 m (gr-SS-NN). "
          "Target: <= 5e-6 m "
          "on both sets.\n";
  });
}

/// The figures' data (convergence, both test sets) and, unless --no-plots, their gnuplot figures.
std::vector<std::string> WriteFigures(const std::filesystem::path& out, const BoucwenRun& a,
                                      const BwOutcome& o) {
  namespace fs = std::filesystem;
  const std::vector<double>&y_ms = o.measured_ms, &y_sw = o.measured_sw;
  const opt::SearchResult& result = o.result;
  io::WriteFileWith(out / "convergence.csv", [&](std::ostream& os) {
    os << "evaluations,best_rms_m,wall_time_s\n";
    for (size_t i = 0; i < result.trace.evaluations.size(); ++i) {
      os << result.trace.evaluations[i] << ","
         << io::FormatNumber(std::sqrt(result.trace.best_cost[i])) << ","
         << io::FormatNumber(result.trace.wall_time_s[i]) << "\n";
    }
  });
  io::WriteFileWith(out / "test_multisine.csv", [&](std::ostream& os) {
    os << "t_s,y_test_m,y_model_m,error_m\n";
    for (size_t i = 0; i < o.yms.size(); ++i) {
      os << io::FormatNumber(i / kBwSampleRateHz) << "," << io::FormatNumber(y_ms[i]) << ","
         << io::FormatNumber(o.yms[i]) << "," << io::FormatNumber(y_ms[i] - o.yms[i]) << "\n";
    }
  });
  io::WriteFileWith(out / "test_sinesweep.csv", [&](std::ostream& os) {
    os << "t_s,y_test_m,y_model_m,error_m,error_true_model_m\n";
    for (size_t i = 0; i < o.ysw.size(); i += 5) {
      os << io::FormatNumber(i / kBwSampleRateHz) << "," << io::FormatNumber(y_sw[i]) << ","
         << io::FormatNumber(o.ysw[i]) << "," << io::FormatNumber(y_sw[i] - o.ysw[i]) << ","
         << io::FormatNumber(y_sw[i] - o.ysw_true[i]) << "\n";
    }
  });
  std::vector<std::string> errors;
  if (!a.plots) return errors;
  std::vector<fs::path> scripts;
  scripts.push_back(
      WritePlotScript(out, Plot{"convergence",
                                "Best training RMS error vs evaluations",
                                "evaluations",
                                "RMS error [m]",
                                true,
                                {PlotSeries{"convergence.csv", 1, 2, "best so far", "lines"}}}));
  scripts.push_back(
      WritePlotScript(out, Plot{"test_multisine",
                                "Multisine test set: simulation of the identified model",
                                "t [s]",
                                "y [m]",
                                false,
                                {PlotSeries{"test_multisine.csv", 1, 2, "y test", "lines"},
                                 PlotSeries{"test_multisine.csv", 1, 3, "y model", "lines"},
                                 PlotSeries{"test_multisine.csv", 1, 4, "error", "lines"}}}));
  scripts.push_back(WritePlotScript(
      out,
      Plot{"test_sinesweep_error",
           "Sine-sweep test set: simulation error",
           "t [s]",
           "error [m]",
           false,
           {PlotSeries{"test_sinesweep.csv", 1, 5, "true model", "lines"},
            PlotSeries{"test_sinesweep.csv", 1, 4, "identified model (drawn on top)", "lines"}}}));
  if (GnuplotAvailable()) {
    RenderPlots(out, scripts, &errors);
  } else {
    errors.push_back("gnuplot not found; render with: cd " + out.string() + " && gnuplot *.gp");
  }
  return errors;
}

}  // namespace

void PrintBoucwenSummary(std::ostream& out, const BwOutcome& o) {
  const opt::SearchResult& result = o.result;
  out.precision(6);
  out << "best of " << o.options.repetitions << ": training RMS " << Sci(o.train_rms)
      << " m (repetition " << result.best_repetition << ", " << result.stop_reason << ")\n"
      << result.evaluations << " evaluations, " << result.iterations << " iterations, "
      << result.wall_time_s << " s (" << result.evaluations / result.wall_time_s
      << " evaluations/s); "
      << "within 1 % of the final cost after " << result.trace.evaluations[o.reach]
      << " evaluations, " << result.trace.wall_time_s[o.reach] << " s\n";
  for (size_t i = 0; i < o.box.size(); ++i) {
    out << "  " << o.box.names[i] << " = " << Sci(result.best[i], 6) << "  (true "
        << Sci(o.theta_true[i], 6) << ", " << std::showpos
        << 100 * (result.best[i] / o.theta_true[i] - 1) << std::noshowpos << " %)\n";
  }
  out << "test multisine: simulation RMS error " << Sci(o.rms_ms) << " m (true model "
      << Sci(o.rms_ms_true) << " m; best published black-box 7.53e-06 m)\n"
      << "test sine sweep: simulation RMS error " << Sci(o.rms_sw) << " m (true model "
      << Sci(o.rms_sw_true) << " m)\n";
}

std::vector<std::string> WriteBoucwenReport(const std::filesystem::path& out, const BoucwenRun& run,
                                            const BwOutcome& o) {
  std::filesystem::create_directories(out);
  io::WriteFileWith(out / "report.json", [&](std::ostream& os) {
    os << io::PrintJson(ReportOf(run, o), "report.json");
  });
  WriteReportMarkdown(out / "report.md", run, o);
  return WriteFigures(out, run, o);
}

}  // namespace pz::reports
