#include "client/case_models.h"

#include "client/data_root.h"

#include <cstdlib>
#include <functional>
#include <memory>

namespace pz::client {

const char* SaturationModeName(SaturationMode m) {
  switch (m) {
    case SaturationMode::kAuto:
      return "auto";
    case SaturationMode::kFitted:
      return "fitted";
    case SaturationMode::kRegression:
      return "regression";
    case SaturationMode::kPaper:
      return "paper";
    case SaturationMode::kGiven:
      return "given";
  }
  return "unknown";
}

void ParamFlags::Register(CLI::App& cmd, const std::string& saturation_default_help) {
  std::vector<CLI::Option*> base;
  auto add = [&](const char* flag, double& field, const char* help) {
    base.push_back(
        cmd.add_option(flag, field, help)->capture_default_str()->group("Model parameters"));
  };
  add("--mu", global.mu, "Rayleigh mass coefficient mu [1/s], >= 0");
  add("--delta", global.delta, "Rayleigh stiffness coefficient delta [s], >= 0");
  add("--alpha", global.alpha, "Bouc-Wen input gain alpha [N/V]");
  add("--beta", global.beta, "Bouc-Wen beta [1/V]");
  add("--gamma", global.gamma, "Bouc-Wen gamma [1/V]");
  add("--a1", global.a1, "backlash rising threshold a1 [deg], >= 0");
  add("--a2", global.a2, "backlash falling threshold a2 [deg], >= 0");
  b1_opt = cmd.add_option("--b1", global.b1,
                          "upper saturation b1 [deg], > 0 (with --b2: used for every case)")
               ->capture_default_str()
               ->group("Model parameters");
  b2_opt = cmd.add_option("--b2", global.b2,
                          "lower saturation b2 [deg], < 0 (with --b1: used for every case)")
               ->capture_default_str()
               ->group("Model parameters");
  CLI::Option* params =
      cmd.add_option("--params", params_file,
                     "per-case parameter CSV: case,mu,delta,alpha,beta,gamma,a1,a2[,b1,b2] "
                     "(units as the flags); replaces --mu ... --a2")
          ->type_name("FILE")
          ->group("Model parameters");
  for (CLI::Option* o : base) params->excludes(o);
  cmd.add_option(
         "--saturation", saturation,
         "where b1, b2 [deg] come from: auto | fitted (max/min of the measured angle) | regression "
         "(OLS of the fitted extremes on V, f over the case set) | paper (eqs. B1, B2) | given "
         "(params file, else --b1/--b2). " +
             saturation_default_help)
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "fitted", "regression", "paper", "given"}))
      ->group("Model parameters");
  cmd.add_option("--solver", solver, "plant solver: modal (fast path) | cvode (SUNDIALS BDF)")
      ->capture_default_str()
      ->check(CLI::IsMember({"modal", "cvode"}));
}

bool ParamFlags::SaturationGiven() const {
  const bool b1 = b1_opt && b1_opt->count() > 0, b2 = b2_opt && b2_opt->count() > 0;
  if (b1 != b2)
    throw InputError(std::string("--") + (b1 ? "b1" : "b2") + " given without --" +
                     (b1 ? "b2" : "b1") + ": give both saturations or neither");
  return b1;
}

SaturationMode ParamFlags::Mode() const {
  for (SaturationMode m :
       {SaturationMode::kAuto, SaturationMode::kFitted, SaturationMode::kRegression,
        SaturationMode::kPaper, SaturationMode::kGiven})
    if (saturation == SaturationModeName(m)) return m;
  throw InputError(
      FieldError("--saturation", saturation, "expected auto, fitted, regression, paper or given"));
}

model::Solver ParamFlags::Solver() const {
  if (solver == "modal") return model::Solver::kModal;
  if (solver == "cvode") return model::Solver::kCvode;
  throw InputError(FieldError("--solver", solver, "expected modal or cvode"));
}

model::BimorphParams BaseParams(const ParamFlags& flags, const std::optional<io::ParamsFile>& file,
                                int case_number) {
  if (!file) return flags.global;
  const io::CaseParams* row = file->Find(case_number);
  if (!row) throw InputError(file->source + ": no row for case " + std::to_string(case_number));
  model::BimorphParams p = row->params;
  p.b1 = flags.global.b1;
  p.b2 = flags.global.b2;
  return p;
}

namespace {

std::optional<io::ParamsFile> LoadParamsFile(const ParamFlags& flags) {
  if (flags.params_file.empty()) return std::nullopt;
  return io::ReadParamsCsv(flags.params_file);
}

// b1, b2 that were given for this case: --b1/--b2 on the command line first, then the params file.
std::optional<std::pair<model::SaturationPair, std::string>> GivenSaturation(
    const ParamFlags& flags, const std::optional<io::ParamsFile>& file, int case_number) {
  if (flags.SaturationGiven())
    return std::pair{model::SaturationPair{flags.global.b1, flags.global.b2}, "given"};
  if (file)
    if (const io::CaseParams* row = file->Find(case_number); row && row->has_saturation)
      return std::pair{model::SaturationPair{row->params.b1, row->params.b2}, "params file"};
  return std::nullopt;
}

// Checks the resolved parameters, naming the case and where b1, b2 came from.
void CheckCase(const CaseModel& c) {
  if (Status s = c.params.Validate(); !s.ok())
    throw InputError("case " + std::to_string(c.case_number) + " (b1, b2 " + c.saturation_source +
                     "): " + s.message());
}

void SetSaturation(CaseModel& c, const model::SaturationPair& s, std::string source) {
  c.params.b1 = s.b1;
  c.params.b2 = s.b2;
  c.saturation_source = std::move(source);
}

/// A bench case's b1, b2 from its measured extremes: the fin case's one rule (io::MakeFinCase).
model::SaturationPair FittedSaturation(const io::BenchCase& bc) {
  const model::FinCase f = io::MakeFinCase(bc);
  return {f.b1, f.b2};
}

std::string NoMeasurement(const char* mode) {
  return std::string("--saturation ") + mode +
         " needs measured data: use it with a bench case set (--cases)";
}

}  // namespace

std::vector<CaseModel> ResolveBenchCases(const ParamFlags& flags, const io::CaseSet& set) {
  const auto file = LoadParamsFile(flags);
  const SaturationMode mode = flags.Mode();
  std::optional<model::SaturationRegression> regression;
  if (mode == SaturationMode::kRegression) {
    std::vector<model::SaturationSample> samples;
    for (const auto& c : set.cases) {
      const auto s = FittedSaturation(c);
      samples.push_back({c.amplitude_v, c.frequency_hz, s.b1, s.b2});
    }
    regression = model::FitSaturationRegression(samples);
  }
  std::vector<CaseModel> out;
  for (const auto& bc : set.cases) {
    CaseModel c;
    c.case_number = bc.number;
    c.drive = bc.Drive();
    c.amplitude_v = bc.amplitude_v;
    c.frequency_hz = bc.frequency_hz;
    c.params = BaseParams(flags, file, bc.number);
    auto fitted = [&] { return FittedSaturation(bc); };
    const auto given = GivenSaturation(flags, file, bc.number);
    switch (mode) {
      case SaturationMode::kAuto:
        if (given)
          SetSaturation(c, given->first, given->second);
        else
          SetSaturation(c, fitted(), "fitted");
        break;
      case SaturationMode::kFitted:
        SetSaturation(c, fitted(), "fitted");
        break;
      case SaturationMode::kRegression:
        SetSaturation(c, regression->Predict(bc.amplitude_v, bc.frequency_hz), "regression");
        break;
      case SaturationMode::kPaper:
        SetSaturation(c,
                      model::PaperSaturationRegression().Predict(bc.amplitude_v, bc.frequency_hz),
                      "paper");
        break;
      case SaturationMode::kGiven:
        if (given)
          SetSaturation(c, given->first, given->second);
        else
          SetSaturation(c, {flags.global.b1, flags.global.b2}, "default");
        break;
    }
    CheckCase(c);
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<CaseModel> ResolveSinusoidCases(const ParamFlags& flags,
                                            const std::vector<double>& amplitudes_v,
                                            const std::vector<double>& frequencies_hz,
                                            double cycles, double sample_rate_hz) {
  const auto file = LoadParamsFile(flags);
  const SaturationMode mode = flags.Mode();
  if (mode == SaturationMode::kFitted || mode == SaturationMode::kRegression)
    throw InputError(NoMeasurement(SaturationModeName(mode)));
  std::vector<CaseModel> out;
  for (double v : amplitudes_v)
    for (double f : frequencies_hz) {
      CaseModel c;
      c.case_number = static_cast<int>(out.size()) + 1;
      model::Sinusoid s{v, f, cycles, sample_rate_hz};
      if (Status st = s.Validate(); !st.ok())
        throw InputError("case " + std::to_string(c.case_number) + ": " + st.message());
      c.drive = s;
      c.amplitude_v = v;
      c.frequency_hz = f;
      c.params = BaseParams(flags, file, c.case_number);
      const auto given = GivenSaturation(flags, file, c.case_number);
      if (given && mode != SaturationMode::kPaper)
        SetSaturation(c, given->first, given->second);
      else if (mode == SaturationMode::kGiven)
        SetSaturation(c, {flags.global.b1, flags.global.b2}, "default");
      else
        SetSaturation(c, model::PaperSaturationRegression().Predict(v, f), "paper");
      CheckCase(c);
      out.push_back(std::move(c));
    }
  return out;
}

CaseModel ResolveInputCase(const ParamFlags& flags, model::SampledSignal input) {
  const auto file = LoadParamsFile(flags);
  const SaturationMode mode = flags.Mode();
  if (mode == SaturationMode::kFitted || mode == SaturationMode::kRegression ||
      mode == SaturationMode::kPaper)
    throw InputError(
        "--saturation " + std::string(SaturationModeName(mode)) +
        " is not available for an --input file (no stated V, f or measurement): give --b1 --b2");
  CaseModel c;
  c.case_number = 1;
  c.drive = std::move(input);
  c.params = BaseParams(flags, file, 1);
  const auto given = GivenSaturation(flags, file, 1);
  if (given)
    SetSaturation(c, given->first, given->second);
  else
    SetSaturation(c, {flags.global.b1, flags.global.b2}, "default");
  CheckCase(c);
  return c;
}

std::filesystem::path DefaultCaseSetDir() { return BundledData("bimorph-fin/nominal"); }

Simulator PlantSimulator(model::Solver solver) {
  auto plant = std::make_shared<const model::BimorphPlant>();
  model::SimulateOptions options;
  options.solver = solver;
  return [plant, options](const model::BimorphParams& p, const model::DriveSignal& d) {
    return model::Simulate(*plant, p, d, options);
  };
}

reports::PiReport ScoreCaseSet(const io::CaseSet& set, std::span<const CaseModel> models,
                               const Simulator& simulate) {
  if (models.size() != set.cases.size())
    throw InputError("scoring: " + std::to_string(models.size()) + " models for " +
                     std::to_string(set.cases.size()) + " cases");
  reports::PiReport report;
  report.case_set = set.dir.string();
  for (size_t i = 0; i < set.cases.size(); ++i) {
    const io::BenchCase& bc = set.cases[i];
    const CaseModel& m = models[i];
    if (m.case_number != bc.number)
      throw InputError("scoring: model " + std::to_string(i) + " is for case " +
                       std::to_string(m.case_number) + " but the case set's entry is case " +
                       std::to_string(bc.number));
    reports::CaseScore s;
    s.case_number = bc.number;
    s.amplitude_v = bc.amplitude_v;
    s.frequency_hz = bc.frequency_hz;
    s.role = bc.role;
    s.b1 = m.params.b1;
    s.b2 = m.params.b2;
    s.saturation_source = m.saturation_source;
    const model::BimorphTrace trace = simulate(m.params, m.drive);
    s.summary = trace.summary;
    if (trace.summary.ok()) {
      try {
        s.metrics = model::CompareTraces(bc.t, bc.angle_deg, trace.t, trace.angle_deg,
                                         1e-6 / bc.sample_rate_hz);
      } catch (const InputError& e) {
        throw InputError(bc.file.string() + " vs model trace: " + e.what());
      }
      s.scored = true;
      double* sum = bc.role == io::CaseRole::kTrain      ? &report.cf_train
                    : bc.role == io::CaseRole::kValidate ? &report.sum_validate
                                                         : &report.sum_test;
      *sum += s.metrics.pi;
    } else {
      ++report.failed;
    }
    report.cases.push_back(std::move(s));
  }
  return report;
}

}  // namespace pz::client
