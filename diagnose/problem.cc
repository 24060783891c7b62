#include "diagnose/problem.h"

#include <algorithm>
#include <cmath>

#include "io/bench_data.h"
#include "model/saturation.h"
#include "records/fit.h"

namespace pz::diagnose {
namespace {

constexpr double kRatioLower = -0.98;  // γ/β: β + γ > 0 with margin
constexpr double kRatioUpper = 1.0;    // β − γ ≥ 0

std::vector<ParamSpec> BaseSpecs() {
  return {
      {"mu", "1/s", 0.0, 400.0, 50.0, false, false},
      {"delta", "s", 0.0, 1.0, 0.05, false, false},
      {"alpha", "N/V", 0.0, 0.02, 1e-3, false, false},
      {"beta", "1/V", 1e-5, 0.05, 2e-3, true, false},
      {"gamma", "1/V", kRatioLower, kRatioUpper, 2e-3, false, true},
      {"a1", "deg", 0.0, 1.0, 0.05, false, false},
      {"a2", "deg", 0.0, 1.0, 0.05, false, false},
  };
}

double ToUnitOne(const ParamSpec& s, double x) {
  return records::UnitCoordinate(s.lower, s.upper, s.log_scale, x);
}

double FromUnitOne(const ParamSpec& s, double u) {
  return records::PhysicalCoordinate(s.lower, s.upper, s.log_scale, u);
}

}  // namespace

// ---- cases
// ---------------------------------------------------------------------------------------

DiagCase MakeCase(int number, const model::Sinusoid& drive, std::vector<double> measured,
                  bool training) {
  model::FinCase f = model::MakeFinCase(number, drive, std::move(measured), training);
  records::CaseNoise noise = records::EstimateCaseNoise(
      f.measured_deg, std::max(1, static_cast<int>(std::lround(drive.cycles))));
  return DiagCase{std::move(f), std::move(noise)};
}

std::vector<DiagCase> CasesFromCaseSet(const io::CaseSet& set) {
  std::vector<DiagCase> cases;
  int train = 0;
  for (const io::BenchCase& bc : set.cases) {
    const bool training = bc.role == io::CaseRole::kTrain;
    train += training;
    cases.push_back(MakeCase(bc.number, bc.Drive(), bc.angle_deg, training));
  }
  if (train == 0)
    throw InputError(set.dir.string() + ": no training case (role train) to identify on");
  if (train == static_cast<int>(cases.size()))
    throw InputError(set.dir.string() + ": no withheld case (role validate/test) to score on");
  return cases;
}

// ---- layout
// --------------------------------------------------------------------------------------

ParameterLayout::ParameterLayout(std::vector<model::EffectKind> structure)
    : structure_(std::move(structure)) {
  specs_ = BaseSpecs();
  for (size_t e = 0; e < structure_.size(); ++e) {
    const model::EffectInfo& info = model::GetEffectInfo(structure_[e]);
    for (size_t i = 0; i < info.params.size(); ++i) {
      const model::EffectParamInfo& p = info.params[i];
      ParamSpec s{info.name + "." + p.name, p.unit, p.lower, p.upper, p.scale, p.log_scale, false};
      s.effect = static_cast<int>(e);
      s.effect_param = static_cast<int>(i);
      specs_.push_back(s);
    }
  }
}

std::vector<double> ParameterLayout::FromUnit(std::span<const double> unit) const {
  PZ_CHECK(unit.size() == specs_.size());
  std::vector<double> x(specs_.size());
  for (size_t i = 0; i < specs_.size(); ++i) x[i] = FromUnitOne(specs_[i], unit[i]);
  x[4] = x[4] * x[3];  // γ = g β
  return x;
}

std::vector<double> ParameterLayout::ToUnit(std::span<const double> physical) const {
  PZ_CHECK(physical.size() == specs_.size());
  std::vector<double> u(specs_.size());
  for (size_t i = 0; i < specs_.size(); ++i) {
    double x = physical[i];
    if (specs_[i].ratio) x = physical[3] > 0 ? physical[4] / physical[3] : 0.0;
    u[i] = ToUnitOne(specs_[i], x);
  }
  return u;
}

std::vector<double> ParameterLayout::UnitJacobian(std::span<const double> unit) const {
  const int n = size();
  std::vector<double> t(static_cast<size_t>(n) * n, 0.0);  // column-major: t[j*n + i] = ∂x_i/∂u_j
  std::vector<double> plain(n);
  for (int i = 0; i < n; ++i) {
    const ParamSpec& s = specs_[i];
    const double xi = FromUnitOne(s, unit[i]);
    plain[i] = xi;
    t[static_cast<size_t>(i) * n + i] =
        s.log_scale ? xi * std::log(s.upper / s.lower) : (s.upper - s.lower);
  }
  // γ = g β: ∂γ/∂u_g = β ∂g/∂u_g, ∂γ/∂u_β = g ∂β/∂u_β.
  const double dg = t[4 * n + 4], db = t[3 * n + 3];
  t[4 * n + 4] = plain[3] * dg;
  t[3 * n + 4] = plain[4] * db;
  return t;
}

void ParameterLayout::Decode(std::span<const double> x, model::BimorphParams* p,
                             std::vector<model::Effect>* effects) const {
  PZ_CHECK(x.size() == specs_.size());
  p->mu = x[0];
  p->delta = x[1];
  p->alpha = x[2];
  p->beta = x[3];
  p->gamma = x[4];
  p->a1 = x[5];
  p->a2 = x[6];
  effects->clear();
  for (model::EffectKind k : structure_) {
    model::Effect e;
    e.kind = k;
    e.params.assign(model::GetEffectInfo(k).params.size(), 0.0);
    effects->push_back(std::move(e));
  }
  for (size_t i = kBase; i < specs_.size(); ++i)
    (*effects)[specs_[i].effect].params[specs_[i].effect_param] = x[i];
}

std::vector<double> ParameterLayout::Encode(const model::BimorphParams& p,
                                            std::span<const model::Effect> effects) const {
  std::vector<double> x = {p.mu, p.delta, p.alpha, p.beta, p.gamma, p.a1, p.a2};
  for (size_t i = kBase; i < specs_.size(); ++i) {
    const ParamSpec& s = specs_[i];
    PZ_CHECK(static_cast<size_t>(s.effect) < effects.size());
    x.push_back(effects[s.effect].params[s.effect_param]);
  }
  return x;
}

std::vector<double> ParameterLayout::Extend(std::span<const double> from_x,
                                            const ParameterLayout& from) const {
  std::vector<double> x(specs_.size());
  for (int i = 0; i < kBase; ++i) x[i] = from_x[i];
  for (size_t e = 0; e < structure_.size(); ++e) {
    // Same kind in `from` (first unused occurrence): copy its values; else the identity.
    int src = -1;
    for (size_t f = 0; f < from.structure_.size(); ++f)
      if (from.structure_[f] == structure_[e]) {
        src = static_cast<int>(f);
        break;
      }
    const model::Effect zero = model::Effect::Zero(structure_[e]);
    for (size_t i = kBase; i < specs_.size(); ++i) {
      if (specs_[i].effect != static_cast<int>(e)) continue;
      double v = zero.params[specs_[i].effect_param];
      if (src >= 0)
        for (size_t j = kBase; j < from.specs_.size(); ++j)
          if (from.specs_[j].effect == src && from.specs_[j].effect_param == specs_[i].effect_param)
            v = from_x[j];
      x[i] = v;
    }
  }
  return x;
}

std::string ParameterLayout::Describe() const {
  std::string s = "base";
  for (model::EffectKind k : structure_) s += std::string(" + ") + model::EffectName(k);
  return s;
}

// ---- model
// ---------------------------------------------------------------------------------------

DiagnosisModel::DiagnosisModel(std::shared_ptr<const model::BimorphPlant> plant,
                               std::vector<DiagCase> cases, model::EffectSimOptions sim)
    : plant_(std::move(plant)), cases_(std::move(cases)), sim_options_(sim) {
  PZ_CHECK(plant_ != nullptr);
  ThrowIfError(sim_options_.Validate());
  sim_ = std::make_unique<model::EffectSimulator>(*plant_);
  for (const DiagCase& c : cases_)
    (c.training ? n_train_ : n_withheld_) += static_cast<int>(c.measured_deg.size());
}

model::SimulationSummary DiagnosisModel::Simulate(const ParameterLayout& layout,
                                                  std::span<const double> x, size_t c,
                                                  std::vector<double>& angle) const {
  model::BimorphParams p;
  std::vector<model::Effect> effects;
  layout.Decode(x, &p, &effects);
  const DiagCase& dc = cases_[c];
  p.b1 = dc.b1;
  p.b2 = dc.b2;
  angle.resize(dc.measured_deg.size());
  return sim_->SimulateAngle(p, effects, dc.drive, angle, sim_options_);
}

bool DiagnosisModel::Residuals(const ParameterLayout& layout, std::span<const double> x,
                               bool training, std::vector<double>& r) const {
  r.clear();
  thread_local std::vector<double> y;
  bool ok = true;
  for (size_t c = 0; c < cases_.size(); ++c) {
    if (cases_[c].training != training) continue;
    const auto& m = cases_[c].measured_deg;
    const model::SimulationSummary s = Simulate(layout, x, c, y);
    for (size_t k = 0; k < m.size(); ++k) {
      const double e = s.ok() ? m[k] - y[k] : std::abs(m[k]) + 10.0;
      r.push_back(e);
    }
    ok = ok && s.ok();
  }
  return ok;
}

std::vector<double> DiagnosisModel::CasePi(const ParameterLayout& layout,
                                           std::span<const double> x) const {
  std::vector<double> pi(cases_.size());
  std::vector<double> y;
  for (size_t c = 0; c < cases_.size(); ++c) {
    const model::SimulationSummary s = Simulate(layout, x, c, y);
    if (!s.ok()) {
      pi[c] = NAN;
      continue;
    }
    double sum = 0;
    for (size_t k = 0; k < y.size(); ++k) {
      const double e = cases_[c].measured_deg[k] - y[k];
      sum += e * e;
    }
    pi[c] = sum;
  }
  return pi;
}

// ---- fitness
// -------------------------------------------------------------------------------------

DiagnosisFitness::DiagnosisFitness(const DiagnosisModel& model, ParameterLayout layout,
                                   bool residuals)
    : model_(model), layout_(std::move(layout)), residuals_(residuals) {
  // Strictly above any valid cost: every residual bounded by |y| + max(b1, −b2) per sample.
  for (const DiagCase& c : model_.cases()) {
    if (!c.training) continue;
    const double b = std::max(c.b1, -c.b2);
    for (double y : c.measured_deg)
      penalty_ += 2.0 * (std::abs(y) + b + 10.0) * (std::abs(y) + b + 10.0);
  }
}

opt::FitnessResult DiagnosisFitness::Evaluate(const opt::Genome& genome) const {
  opt::FitnessResult r;
  if (genome.reals.size() != static_cast<size_t>(layout_.size())) {
    r.cost = penalty_;
    r.status = opt::FitnessStatus::kError;
    r.reason = "genome has " + std::to_string(genome.reals.size()) + " reals, expected " +
               std::to_string(layout_.size());
    return r;
  }
  for (double v : genome.reals) {
    if (!std::isfinite(v)) {
      r.cost = penalty_;
      r.status = opt::FitnessStatus::kError;
      r.reason = "non-finite gene";
      return r;
    }
  }
  const std::vector<double> x = layout_.FromUnit(genome.reals);
  thread_local std::vector<double> res;
  if (!model_.Residuals(layout_, x, true, res)) {
    r.cost = penalty_;
    r.status = opt::FitnessStatus::kPenalized;
    r.reason = "simulation failed";
    return r;
  }
  double cost = 0;
  for (double e : res) cost += e * e;
  r.cost = std::min(cost, penalty_);
  if (residuals_) r.residuals = res;
  return r;
}

}  // namespace pz::diagnose
