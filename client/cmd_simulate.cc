// `piezoid simulate`: run the bimorph plant for given parameters on sinusoid cases, a bench case
// set or an input file, and write the traces as CSV.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "client/case_models.h"
#include "client/commands.h"
#include "io/trace_io.h"

namespace pz::client {
namespace {

struct SimulateArgs {
  ParamFlags flags;
  std::vector<double> amplitudes_v;
  std::vector<double> frequencies_hz;
  double cycles = 3.0;
  double rate_hz = 100.0;
  std::string cases_dir;
  std::string input_file;
  std::string out_dir;
};

int RunSimulate(const SimulateArgs& a) {
  std::vector<CaseModel> cases;
  std::string source;
  if (!a.cases_dir.empty()) {
    const io::CaseSet set = io::LoadCaseSet(a.cases_dir);
    cases = ResolveBenchCases(a.flags, set);
    source = "case set " + a.cases_dir;
  } else if (!a.input_file.empty()) {
    cases.push_back(ResolveInputCase(a.flags, io::ReadInputSignalCsv(a.input_file)));
    source = "input " + a.input_file;
  } else {
    const std::vector<double> v = a.amplitudes_v.empty()
                                      ? std::vector<double>{model::Sinusoid{}.amplitude_v}
                                      : a.amplitudes_v;
    const std::vector<double> f = a.frequencies_hz.empty()
                                      ? std::vector<double>{model::Sinusoid{}.frequency_hz}
                                      : a.frequencies_hz;
    cases = ResolveSinusoidCases(a.flags, v, f, a.cycles, a.rate_hz);
    source = "sinusoids";
  }
  const bool to_stdout = a.out_dir.empty();
  if (to_stdout && cases.size() > 1)
    throw InputError(std::to_string(cases.size()) + " cases from " + source +
                     ": give --out DIR to write one CSV per case (stdout takes a single case)");
  if (!to_stdout) {
    std::error_code ec;
    std::filesystem::create_directories(a.out_dir, ec);
    if (!std::filesystem::is_directory(a.out_dir))
      throw InputError("--out " + a.out_dir + ": cannot create the directory" +
                       (ec ? " (" + ec.message() + ")" : ""));
  }
  // Summaries go to stderr when the trace itself goes to stdout.
  std::FILE* log = to_stdout ? stderr : stdout;
  const Simulator simulate = PlantSimulator(a.flags.Solver());
  int failures = 0;
  for (const CaseModel& c : cases) {
    const model::BimorphTrace trace = simulate(c.params, c.drive);
    std::string dest = "-";
    if (trace.summary.ok()) {
      if (to_stdout) {
        io::WriteTraceCsv(std::cout, trace);
        std::cout.flush();
        dest = "stdout";
      } else {
        const std::filesystem::path file =
            std::filesystem::path(a.out_dir) / ("case" + std::to_string(c.case_number) + ".csv");
        io::WriteColumnsCsvFile(file, io::TraceColumns(trace));
        dest = file.string();
      }
    } else {
      ++failures;
    }
    std::fprintf(log, "case %d: %s, b1 %.6g b2 %.6g deg (%s), solver %s: %s -> %s\n", c.case_number,
                 model::Describe(c.drive).c_str(), c.params.b1, c.params.b2,
                 c.saturation_source.c_str(), a.flags.solver.c_str(),
                 trace.summary.BriefReport().c_str(), dest.c_str());
  }
  std::fflush(log);
  return failures ? 1 : 0;
}

}  // namespace

void RegisterSimulate(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Run the bimorph plant for given parameters on sinusoid cases (--amplitude x --frequency "
      "grid), a "
      "bench case set (--cases) or an input file (--input); write CSV t_s,voltage_V,z_N,w_tip_m,"
      "theta_linear_deg,angle_deg per case to --out DIR (or stdout for a single case) and print a "
      "one-line summary per case (status, steps, wall time).");
  args->flags.Register(
      *cmd,
      "auto: --b1/--b2 or the params file if given; else fitted (--cases), the paper's "
      "regression (sinusoids), or the --b1/--b2 defaults (--input).");
  auto* amp = cmd->add_option("--amplitude", args->amplitudes_v,
                              "drive amplitude(s) V [V], >= 0; comma-separated list (default 375)")
                  ->delimiter(',')
                  ->group("Drive");
  auto* freq =
      cmd->add_option("--frequency", args->frequencies_hz,
                      "drive frequency(ies) f [Hz], > 0; comma-separated (default 0.25). Cases are "
                      "the V x f grid, amplitude-major, numbered from 1")
          ->delimiter(',')
          ->group("Drive");
  cmd->add_option("--cycles", args->cycles, "number of drive cycles, > 0")
      ->capture_default_str()
      ->group("Drive");
  cmd->add_option("--rate", args->rate_hz, "sample rate fs [Hz], > 0")
      ->capture_default_str()
      ->group("Drive");
  auto* cases =
      cmd->add_option(
             "--cases", args->cases_dir,
             "bench case set folder (cases.csv + one CSV per case): each case's V, f and grid")
          ->type_name("DIR")
          ->group("Drive");
  auto* input =
      cmd->add_option(
             "--input", args->input_file,
             "drive input CSV with columns t_s [s], voltage_V [V] (a sampled signal, linear "
             "between samples)")
          ->type_name("FILE")
          ->group("Drive");
  cases->excludes(amp)->excludes(freq)->excludes(input);
  input->excludes(amp)->excludes(freq);
  cmd->add_option("--out", args->out_dir,
                  "output folder for case<N>.csv (created if missing); default stdout")
      ->type_name("DIR");
  cmd->callback([args, &exit_code] { exit_code = RunSimulate(*args); });
}

}  // namespace pz::client
