#include "diagnose/job_kind.h"

#include "io/bench_data.h"

#include <cmath>
#include <set>
#include <sstream>

#include "opt/inline_evaluator.h"
#include "model/effects.h"

namespace pz::diagnose {
namespace {

using job::FieldViolation;

std::string Num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

std::shared_ptr<const model::BimorphPlant> DefaultPlant() {
  static const std::shared_ptr<const model::BimorphPlant> plant =
      std::make_shared<const model::BimorphPlant>();
  return plant;
}

// The structure of the spec, or the violations of its names.
std::vector<model::EffectKind> Structure(const job::DiagnoseProblem& d,
                                         std::vector<FieldViolation>* v) {
  std::vector<model::EffectKind> kinds;
  std::set<model::EffectKind> seen;
  for (size_t i = 0; i < d.structure.size(); ++i) {
    const std::string f = "diagnose.structure[" + std::to_string(i) + "]";
    const auto k = model::ParseEffectKind(d.structure[i]);
    if (!k || k->none()) {
      v->push_back({f, f + " = " + d.structure[i] + ": " + model::FinEffectError(d.structure[i])});
    } else if (!seen.insert(*k).second) {
      v->push_back({f, f + " = " + d.structure[i] + ": appears twice"});
    } else {
      kinds.push_back(*k);
    }
  }
  return kinds;
}

model::EffectSimOptions SimOptions(const job::DiagnoseProblem& d) {
  model::EffectSimOptions o;
  o.oversample = d.oversample;
  o.rtol = d.rtol;
  o.atol = d.atol;
  o.max_steps = static_cast<long>(d.max_steps);
  o.force_cvode = d.force_cvode;
  return o;
}

std::vector<FieldViolation> Validate(const job::JobSpec& spec) {
  std::vector<FieldViolation> v;
  const auto& d = std::get<job::DiagnoseProblem>(spec.problem);
  auto add = [&](const std::string& field, const std::string& value, const std::string& rule) {
    v.push_back({field, field + " = " + value + ": " + rule});
  };
  if (d.cases.empty())
    v.push_back({"diagnose.cases", "diagnose.cases: at least one training case is needed"});
  if (d.cycles.size() != d.cases.size())
    add("diagnose.cycles", std::to_string(d.cycles.size()) + " values",
        "must have one per case (" + std::to_string(d.cases.size()) + ")");
  std::set<int> numbers;
  int train = 0;
  for (size_t i = 0; i < d.cases.size(); ++i) {
    const job::HgannCaseSpec& c = d.cases[i];
    const std::string f = "diagnose.cases[" + std::to_string(i) + "]";
    if (c.number <= 0) add(f + ".number", std::to_string(c.number), "must be > 0");
    if (!numbers.insert(c.number).second)
      add(f + ".number", std::to_string(c.number), "must be unique");
    if (!(std::isfinite(c.amplitude_v) && c.amplitude_v >= 0))
      add(f + ".amplitude_v", Num(c.amplitude_v), "must be finite and >= 0");
    if (!(std::isfinite(c.frequency_hz) && c.frequency_hz > 0))
      add(f + ".frequency_hz", Num(c.frequency_hz), "must be finite and > 0");
    if (!(std::isfinite(c.sample_rate_hz) && c.sample_rate_hz > 0))
      add(f + ".sample_rate_hz", Num(c.sample_rate_hz), "must be finite and > 0");
    if (c.role == job::CaseRole::kUnspecified)
      add(f + ".role", "CASE_ROLE_UNSPECIFIED", "must be set");
    train += c.role == job::CaseRole::kTrain;
    if (c.angle_deg.size() < 2)
      add(f + ".angle_deg", std::to_string(c.angle_deg.size()) + " samples", "needs >= 2");
    for (size_t k = 0; k < c.angle_deg.size(); ++k)
      if (!std::isfinite(c.angle_deg[k])) {
        add(f + ".angle_deg[" + std::to_string(k) + "]", Num(c.angle_deg[k]), "must be finite");
        break;
      }
    if (c.b1 || c.b2)
      add(f + ".b1", "set", "must be unset (the saturations come from the measured extremes)");
    if (i < d.cycles.size()) {
      const double cy = d.cycles[i];
      if (!(std::isfinite(cy) && cy > 0)) {
        add("diagnose.cycles[" + std::to_string(i) + "]", Num(cy), "must be finite and > 0");
      } else if (std::isfinite(c.frequency_hz) && c.frequency_hz > 0 &&
                 std::isfinite(c.sample_rate_hz) &&
                 std::lround(cy * c.sample_rate_hz / c.frequency_hz) !=
                     static_cast<long>(c.angle_deg.size())) {
        add("diagnose.cycles[" + std::to_string(i) + "]", Num(cy),
            "gives " + std::to_string(std::lround(cy * c.sample_rate_hz / c.frequency_hz)) +
                " samples at fs / f, the case has " + std::to_string(c.angle_deg.size()));
      }
    }
  }
  if (!d.cases.empty() && train == 0)
    v.push_back({"diagnose.cases", "diagnose.cases: no case with role CASE_ROLE_TRAIN to fit on"});
  const std::vector<model::EffectKind> kinds = Structure(d, &v);
  if (v.empty() || kinds.size() == d.structure.size()) {
    const ParameterLayout layout(kinds);
    if (d.params.size() != static_cast<size_t>(layout.size())) {
      add("diagnose.params", std::to_string(d.params.size()) + " boxes",
          "the structure '" + layout.Describe() + "' has " + std::to_string(layout.size()) +
              " parameters here");
    } else {
      for (int i = 0; i < layout.size(); ++i) {
        const ParamSpec& s = layout.specs()[i];
        const job::DiagnoseParamBox& b = d.params[i];
        if (b.name != s.name || b.lower != s.lower || b.upper != s.upper ||
            b.log_scale != s.log_scale || b.ratio != s.ratio)
          add("diagnose.params[" + std::to_string(i) + "]",
              b.name + " [" + Num(b.lower) + ", " + Num(b.upper) + "]",
              "differs from this effect library's " + s.name + " [" + Num(s.lower) + ", " +
                  Num(s.upper) + "] (client and service of different versions?)");
      }
    }
  }
  if (d.oversample < 1 || d.oversample > 64)
    add("diagnose.oversample", std::to_string(d.oversample), "must be in [1, 64]");
  if (Status s = SimOptions(d).Validate(); !s.ok() && d.oversample >= 1 && d.oversample <= 64)
    v.push_back({"diagnose", "diagnose: " + s.message()});
  if (d.source.size() > 1000)
    add("diagnose.source", std::to_string(d.source.size()) + " characters", "must be <= 1000");
  return v;
}

// Owns the model the fitness refers to.
class OwningFitness final : public opt::FitnessFunction {
 public:
  OwningFitness(std::unique_ptr<DiagnosisModel> model, ParameterLayout layout, bool residuals)
      : model_(std::move(model)), fitness_(*model_, std::move(layout), residuals) {}
  opt::FitnessResult Evaluate(const opt::Genome& g) const override { return fitness_.Evaluate(g); }

 private:
  std::unique_ptr<DiagnosisModel> model_;
  DiagnosisFitness fitness_;
};

}  // namespace

job::DiagnoseProblem DiagnoseProblemOf(const DiagnosisFitness& fitness) {
  const DiagnosisModel& m = fitness.model();
  job::DiagnoseProblem d;
  for (const DiagCase& c : m.cases()) {
    job::HgannCaseSpec s;
    s.number = c.number;
    s.amplitude_v = c.drive.amplitude_v;
    s.frequency_hz = c.drive.frequency_hz;
    s.sample_rate_hz = c.drive.sample_rate_hz;
    s.role = c.training ? job::CaseRole::kTrain : job::CaseRole::kTest;
    s.angle_deg = c.measured_deg;
    d.cases.push_back(std::move(s));
    d.cycles.push_back(c.drive.cycles);
  }
  for (model::EffectKind k : fitness.layout().structure())
    d.structure.push_back(model::EffectName(k));
  for (const ParamSpec& s : fitness.layout().specs())
    d.params.push_back({s.name, s.lower, s.upper, s.log_scale, s.ratio});
  d.residuals = fitness.residuals();
  const model::EffectSimOptions& o = m.sim_options();
  d.oversample = o.oversample;
  d.rtol = o.rtol;
  d.atol = o.atol;
  d.max_steps = o.max_steps;
  d.force_cvode = o.force_cvode;
  return d;
}

job::JobSpec DiagnoseJobSpec(const DiagnosisFitness& fitness, const std::string& name) {
  job::JobSpec spec;
  spec.name = name.substr(0, 200);
  spec.seed = 0;
  spec.problem = DiagnoseProblemOf(fitness);
  spec.limits.penalty_cost = opt::kDefaultErrorCost;
  return spec;
}

job::JobKind DiagnoseJobKind() {
  job::JobKind k;
  k.name = "diagnose";
  k.validate = [](const job::JobSpec& s) { return Validate(s); };
  k.layout = [](const job::JobSpec& s, job::GenomeLayout* l) {
    std::vector<FieldViolation> v;
    const auto kinds = Structure(std::get<job::DiagnoseProblem>(s.problem), &v);
    if (!v.empty()) return InvalidArgument(v.front().description);
    l->bits = 0;
    l->reals = ParameterLayout(kinds).size();
    return Status::Ok();
  };
  k.make_fitness = [](const job::JobSpec& s, std::unique_ptr<opt::FitnessFunction>* f) {
    const std::vector<FieldViolation> v = Validate(s);
    if (!v.empty()) return InvalidArgument(v.front().description);
    const auto& d = std::get<job::DiagnoseProblem>(s.problem);
    std::vector<FieldViolation> ignored;
    try {
      std::vector<DiagCase> cases;
      io::BenchReadOptions options;  // the stated cycles are checked; the drive is the stated one
      options.check_voltage = false;
      for (size_t i = 0; i < d.cases.size(); ++i) {
        io::BenchCaseSamples b = io::SamplesOfSpecCase(d.cases[i]);
        b.u.clear();  // the diagnosis simulates the stated drive
        b.cycles = d.cycles[i];
        const io::BenchCase bc = io::MakeBenchCase(
            std::move(b), options, io::SpecCaseWhere("diagnose.cases[" + std::to_string(i) + "]"));
        cases.push_back(
            MakeCase(bc.number, bc.Drive(), bc.angle_deg, bc.role == io::CaseRole::kTrain));
      }
      auto model =
          std::make_unique<DiagnosisModel>(DefaultPlant(), std::move(cases), SimOptions(d));
      *f = std::make_unique<OwningFitness>(std::move(model),
                                           ParameterLayout(Structure(d, &ignored)), d.residuals);
    } catch (const InputError& e) {
      return InvalidArgument(std::string("diagnose: ") + e.what());
    }
    return Status::Ok();
  };
  k.describe = [](const job::JobSpec& s, const opt::Genome& g) {
    std::vector<FieldViolation> ignored;
    const ParameterLayout layout(Structure(std::get<job::DiagnoseProblem>(s.problem), &ignored));
    if (g.reals.size() != static_cast<size_t>(layout.size())) return std::string();
    return layout.Describe();
  };
  return k;
}

}  // namespace pz::diagnose
