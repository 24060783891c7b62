// What `piezoid simulate` and `piezoid pi` share: the parameter flags (--mu … --b2, --params), the
// saturation policy (--saturation), the solver flag, the default bench case set, and the resolution
// of one parameter set per case from all of those.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "io/bench_data.h"
#include "io/params_io.h"
#include "model/bimorph.h"
#include "model/saturation.h"
#include "reports/pi_report.h"

namespace pz::client {

/// Where each case's b1, b2 come from.
enum class SaturationMode : int {
  kAuto = 0,  ///< given where given (--b1/--b2, else the params file's b1,b2), else: bench case →
              ///< fitted, sinusoid → paper, input file → the --b1/--b2 defaults
  kFitted,    ///< max / min of the case's measured angle (bench cases only)
  kRegression,  ///< OLS of the fitted extremes of every case in the set on V, f; its prediction
  kPaper,       ///< the paper's eqs. (B1), (B2) at the case's V, f
  kGiven,       ///< the params file's b1,b2 for the case, else --b1/--b2 (explicit or default)
};
const char* SaturationModeName(SaturationMode m);

/// The flags that fix the model parameters. Register once per subcommand.
struct ParamFlags {
  model::BimorphParams global;  ///< --mu … --b2 (defaults: the spec's nominal bench values)
  std::string params_file;      ///< --params FILE (per-case CSV, io/params_io.h)
  std::string saturation = "auto";
  std::string solver = "modal";
  CLI::Option* b1_opt = nullptr;
  CLI::Option* b2_opt = nullptr;

  /// Adds --mu --delta --alpha --beta --gamma --a1 --a2 --b1 --b2 --params --saturation --solver.
  void Register(CLI::App& cmd, const std::string& saturation_default_help);
  /// True iff --b1 and --b2 were given on the command line (throws InputError if only one was).
  bool SaturationGiven() const;
  SaturationMode Mode() const;
  model::Solver Solver() const;
};

/// One case to run: its drive, its parameters and where b1, b2 came from.
struct CaseModel {
  int case_number = 0;
  model::DriveSignal drive;
  double amplitude_v = 0;   ///< V [V] (0 for an input file)
  double frequency_hz = 0;  ///< f [Hz] (0 for an input file)
  model::BimorphParams params;
  std::string
      saturation_source;  ///< "given", "params file", "fitted", "regression", "paper", "default"
};

/// The parameters (without b1, b2) for a case: the params file's row (an error naming the file if
/// the case has none) or the global flags.
model::BimorphParams BaseParams(const ParamFlags& flags, const std::optional<io::ParamsFile>& file,
                                int case_number);

/// One CaseModel per bench case, b1/b2 by the flags' saturation mode. Throws InputError.
std::vector<CaseModel> ResolveBenchCases(const ParamFlags& flags, const io::CaseSet& set);

/// One CaseModel per (V, f) of a sinusoid grid: amplitude-major, numbered from 1 (the paper's case
/// numbering for V = 375, 500, 750 and f = 0.25, 0.5, 1). Throws InputError.
std::vector<CaseModel> ResolveSinusoidCases(const ParamFlags& flags,
                                            const std::vector<double>& amplitudes_v,
                                            const std::vector<double>& frequencies_hz,
                                            double cycles, double sample_rate_hz);

/// One CaseModel (number 1) for a sampled input signal. Throws InputError.
CaseModel ResolveInputCase(const ParamFlags& flags, model::SampledSignal input);

/// The bundled nominal case set: DataRoot() / bimorph-fin/nominal (client/data_root.h).
std::filesystem::path DefaultCaseSetDir();

/// Runs the plant (throws nothing for a physical failure; see model::Simulate).
using Simulator =
    std::function<model::BimorphTrace(const model::BimorphParams&, const model::DriveSignal&)>;
/// The real plant with the given solver (one BimorphPlant shared by all calls).
Simulator PlantSimulator(model::Solver solver);

/// Simulates every case with models[i] (same order as set.cases) and scores it. A failed simulation
/// is a row with scored = false. Throws InputError if models and cases disagree or a model trace is
/// not on the case's time grid (tolerance 1e-6 / fs).
reports::PiReport ScoreCaseSet(const io::CaseSet& set, std::span<const CaseModel> models,
                               const Simulator& simulate);

}  // namespace pz::client
