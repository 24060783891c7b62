#include "records/stepper.h"

#include <algorithm>
#include <cmath>

#include "io/csv.h"
#include "model/bimorph.h"
#include "model/modal_simulator.h"
#include "records/registry.h"

namespace pz::records {
namespace {

// The C step of a records effect (its class's kernel id, model/effect_library.cc).
int KernelOf(EffectKind e) {
  const int k = e.none() ? 0 : e->kernel();
  const bool drive = e.none() || e->stage() == model::EffectStage::kDrive;
  if (k <= 0 ||
      (drive ? k >= pzk::PZK_STACK_BOUC_WEN : k < pzk::PZK_FRICTION || k >= pzk::PZK_AFFINE))
    throw InputError(std::string("effect '") + e.name() +
                     "' has no step kernel of its stage (model/kernels/effects.h)");
  return k;
}

bool IsDriveEffect(EffectKind e) { return e->stage() == model::EffectStage::kDrive; }

void CheckFinite(const std::string& field, double v) {
  if (!std::isfinite(v)) throw InputError(FieldError(field, v, "must be finite"));
}

}  // namespace

bool HasStepKernel(const std::string& family) {
  const FamilyDef* f = FindFamily(family);
  return f != nullptr && f->kernel != 0;
}

FamilyOptions ModelSpec::family_options() const {
  FamilyOptions o;
  o.substeps = substeps;
  o.pi_operators = pi_operators;
  o.initial_state = initial_state;
  return o;
}

std::shared_ptr<RecordModel> ModelSpec::Model() const {
  return std::make_shared<RecordModel>(
      std::shared_ptr<const Family>(MakeFamily(family, scale, family_options())), effects, scale);
}

void ModelSpec::Validate() const {
  if (initial_state != model::InitialState::kCentred && !TakesInitialState(family)) {
    throw InputError("model.initial_state '" + std::string(model::InitialStateName(initial_state)) +
                     "': " + family + " starts centred (only " + FamilyList(true) +
                     " take an initial state)");
  }
  const auto model = Model();
  if (params.size() != model->params().size()) {
    throw InputError("model.params: " + std::to_string(params.size()) + " values for " +
                     model->Describe() + ", " + std::to_string(model->params().size()) +
                     " expected");
  }
  const size_t m = model->family().linear() ? model->family().regressors() : 0;
  if (weights.size() != m) {
    throw InputError("model.weights: " + std::to_string(weights.size()) + " values for " + family +
                     ", " + std::to_string(m) + " expected");
  }
  for (size_t i = 0; i < params.size(); ++i)
    CheckFinite("model.params[" + model->params()[i].name + "]", params[i]);
  for (size_t i = 0; i < weights.size(); ++i)
    CheckFinite("model.weights[" + std::to_string(i) + "]", weights[i]);
  if (polarity != 1 && polarity != -1)
    throw InputError(FieldError("model.polarity", polarity, "must be 1 or -1"));
  CheckFinite("model.offset", offset);
  if (!(std::isfinite(dt) && dt > 0))
    throw InputError(FieldError("model.sample_period_s", dt, "must be finite and > 0"));
  // The delay's kernel keeps its delay in samples (an int, and a ring of that many doubles): a
  // fit's is at most 500 samples (its range); a fit.json of a delay of years, or of a sample period
  // of 1e-300 s, is refused here (the kernel's cast overflowed: the fuzzer of issue 37).
  if (const auto [at, count] = model->EffectParams(EffectKind::Named("delay")); count > 0) {
    constexpr double kMaxDelaySamples = 1e6;
    if (!(params[at] / dt <= kMaxDelaySamples)) {
      throw InputError(FieldError(
          "model.params[" + model->params()[at].name + "]", params[at],
          "is " + io::FormatNumber(params[at] / dt) +
              " samples of model.sample_period_s = " + io::FormatNumber(dt) + " s; at most 1e6"));
    }
  }
  if (!(std::isfinite(drive_min) && std::isfinite(drive_max) && drive_min < drive_max)) {
    throw InputError("model.drive_min / drive_max = [" + io::FormatNumber(drive_min) + ", " +
                     io::FormatNumber(drive_max) + "]: must be finite with min < max");
  }
  // A fit writes the training drive's range; an amplifier's range may widen it, but a model is
  // meaningless 1000 half-ranges beyond its data (and the fin's sub-steps grow with the jump).
  constexpr double kMaxHalfRanges = 1e3;
  const double centre = 0.5 * (scale.u_min + scale.u_max);
  const double reach = kMaxHalfRanges * scale.u_half;
  if (!(std::abs(drive_min - centre) <= reach && std::abs(drive_max - centre) <= reach)) {
    throw InputError("model.drive_min / drive_max = [" + io::FormatNumber(drive_min) + ", " +
                     io::FormatNumber(drive_max) + "]: more than 1000 half-ranges (model.scale." +
                     "u_half = " + io::FormatNumber(scale.u_half) + ") from the training drive's " +
                     "centre " + io::FormatNumber(centre));
  }
}

Stepper::Stepper(const ModelSpec& spec) : spec_(spec) {
  if (!HasStepKernel(spec_.family)) {
    std::string known;
    for (const FamilyDef* f : Families())
      if (f->kernel != 0) known += (known.empty() ? "" : ", ") + std::string(f->name);
    throw InputError("family '" + spec_.family +
                     "' has no step kernel (exportable families: " + known + ")");
  }
  const FamilyDef& def = *FindFamily(spec_.family);
  spec_.Validate();
  std::sort(spec_.effects.begin(), spec_.effects.end());
  const auto model = spec_.Model();
  const size_t nf = model->family_param_count();
  auto block = [&](int kind, std::vector<double> p, std::vector<double> data = {}) {
    pzk::pzk_block b{};
    b.kind = kind;
    b.dt = spec_.dt;
    b.u_min = spec_.scale.u_min;
    b.u_max = spec_.scale.u_max;
    b.u_half = spec_.scale.u_half;
    b.y_half = spec_.scale.y_half;
    params_.push_back(std::move(p));
    kernel_data_.push_back(std::move(data));
    blocks_.push_back(b);
  };
  // The effects' parameters follow the family's, in effect order (RecordModel).
  std::vector<std::vector<double>> effect_params;
  size_t at = nf;
  for (EffectKind e : spec_.effects) {
    const size_t n = e->Params(spec_.scale).size();
    effect_params.emplace_back(spec_.params.begin() + static_cast<std::ptrdiff_t>(at),
                               spec_.params.begin() + static_cast<std::ptrdiff_t>(at + n));
    at += n;
  }
  for (size_t i = 0; i < spec_.effects.size(); ++i)
    if (IsDriveEffect(spec_.effects[i]))
      block(KernelOf(spec_.effects[i]), effect_params[i],
            spec_.effects[i]->KernelData(spec_.scale));
  block(def.kernel, std::vector<double>(spec_.params.begin(),
                                        spec_.params.begin() + static_cast<std::ptrdiff_t>(nf)));
  const size_t family_block = blocks_.size() - 1;
  // pzk PZK_CENTRED / DESCENDED / ASCENDED / AUTO: the family's own (backlash-like's auto is
  // centred)
  blocks_[family_block].init = static_cast<int>(model->family().initial_state());
  KernelShape shape = def.kernel_shape(spec_.family_options(), spec_.params);
  blocks_[family_block].n = shape.n;
  blocks_[family_block].m = shape.m;
  family_data_ = std::move(shape.data);
  for (size_t i = 0; i < spec_.effects.size(); ++i)
    if (!IsDriveEffect(spec_.effects[i]))
      block(KernelOf(spec_.effects[i]), effect_params[i],
            spec_.effects[i]->KernelData(spec_.scale));
  block(pzk::PZK_AFFINE, {static_cast<double>(spec_.polarity), spec_.offset});
  for (size_t i = 0; i < blocks_.size(); ++i) {
    blocks_[i].p = params_[i].data();
    blocks_[i].np = static_cast<int>(params_[i].size());
    if (!kernel_data_[i]
             .empty()) {  // an effect's constants (the creep spectrum's times: n of them)
      blocks_[i].w = kernel_data_[i].data();
      blocks_[i].nw = static_cast<int>(kernel_data_[i].size());
      blocks_[i].n = blocks_[i].nw;
    }
  }
  // The family's constants: its own (the fin's modal data), else a linear family's solved weights.
  const std::vector<double>& w = family_data_.empty() ? spec_.weights : family_data_;
  blocks_[family_block].w = w.data();
  blocks_[family_block].nw = static_cast<int>(w.size());
  if (pzk::pzk_layout(blocks_.data(), static_cast<int>(blocks_.size()), &nc_, &nd_) != 0) {
    throw InputError("stepper: a block without a kernel");
  }
  c_.assign(static_cast<size_t>(nc_), 0.0);
  d_.assign(static_cast<size_t>(nd_), 0.0);
  t_.assign(static_cast<size_t>(nd_), 0.0);
  Init(spec_.drive_min);
}

bool Stepper::has_delay() const {
  for (const auto& b : blocks_)
    if (b.kind == pzk::PZK_DELAY && b.p[0] > 0) return true;
  return false;
}

double Stepper::delay_fraction() const {
  for (const auto& b : blocks_)
    if (b.kind == pzk::PZK_DELAY && b.p[0] > 0) return pzk::pzk_delay_fraction(c_.data() + b.c_off);
  return 0;
}

int Stepper::delay_horizon() const {
  return pzk::pzk_chain_prime_samples(blocks_.data(), static_cast<int>(blocks_.size()), c_.data());
}

int Stepper::inverse_plan_samples() const {
  return 1 + pzk::pzk_chain_plans(blocks_.data(), static_cast<int>(blocks_.size()));
}

size_t Stepper::preview_samples() const {
  return static_cast<size_t>(
      pzk::pzk_chain_preview(blocks_.data(), static_cast<int>(blocks_.size()), c_.data()));
}

double Stepper::rate_dependence_inverse_gain() const {
  double gain = 0;
  for (const auto& b : blocks_) {
    if (b.kind != pzk::PZK_RATE_DEPENDENCE || !(b.p[0] > 0)) continue;
    const double a = b.p[1] / spec_.dt, lead = 1 - 1.5 * a;
    if (lead == 0) return INFINITY;
    // lead rho^2 + 2 a rho - a / 2 = 0: the discriminant 4 a^2 + 2 a lead = a (a + 2) >= 0.
    const double s = std::sqrt(a * (a + 2));
    const double g =
        std::max(std::abs((-2 * a + s) / (2 * lead)), std::abs((-2 * a - s) / (2 * lead)));
    gain = std::max(gain, g);
  }
  return gain;
}

double Stepper::Init(double u0) {
  ctl_.u_lo = spec_.drive_min;
  ctl_.u_hi = spec_.drive_max;
  return pzk::pzk_chain_init(blocks_.data(), static_cast<int>(blocks_.size()), c_.data(), d_.data(),
                             &ctl_, u0);
}

double Stepper::Step(double u) {
  return pzk::pzk_chain_step(blocks_.data(), static_cast<int>(blocks_.size()), c_.data(), d_.data(),
                             &ctl_, u);
}

double Stepper::InverseStep(double y_desired) {
  return pzk::pzk_chain_inverse(blocks_.data(), static_cast<int>(blocks_.size()), c_.data(),
                                d_.data(), t_.data(), &ctl_, y_desired);
}

bool Stepper::InversePrime(double y_desired) {
  return pzk::pzk_chain_inverse_prime(blocks_.data(), static_cast<int>(blocks_.size()), c_.data(),
                                      d_.data(), t_.data(), &ctl_, y_desired) == 0;
}

void Stepper::InversePrimeFrom(std::span<const double> y) {
  const size_t preview = preview_samples(), horizon = static_cast<size_t>(delay_horizon());
  if (horizon == 0 || y.empty()) return;
  for (size_t k = preview + 1 - horizon; k <= preview; ++k)
    InversePrime(y[std::min(k, y.size() - 1)]);
}

double Stepper::Trial(double u) {
  return pzk::pzk_chain_eval(blocks_.data(), static_cast<int>(blocks_.size()), c_.data(), d_.data(),
                             t_.data(), u, pzk::PZK_EVAL_UNDELAYED);
}

namespace {
void WidenToRecord(Stepper& st, const io::Record& r) {
  const auto [lo, hi] = std::minmax_element(r.u.begin(), r.u.end());
  st.ctl().u_lo = std::min(st.spec().drive_min, *lo);
  st.ctl().u_hi = std::max(st.spec().drive_max, *hi);
}
}  // namespace

std::vector<double> SimulateRecord(const ModelSpec& spec, const io::Record& r) {
  Stepper st(spec);
  std::vector<double> y(r.size());
  y[0] = st.Init(r.u[0]);
  WidenToRecord(st, r);
  for (size_t k = 1; k < r.size(); ++k) y[k] = st.Step(r.u[k]);
  return y;
}

ReplayError ReplayDrive(const ModelSpec& spec, const io::Record& r, std::span<const double> y) {
  if (y.size() != r.size()) {
    throw InputError(r.Label() + ": " + std::to_string(y.size()) + " responses to replay for " +
                     std::to_string(r.size()) + " samples");
  }
  Stepper inv(spec);
  inv.Init(r.u[0]);
  WidenToRecord(inv, r);
  const size_t preview = inv.preview_samples();
  inv.InversePrimeFrom(y);
  const double h = 1e-6 * spec.scale.u_half;
  ReplayError e;
  double sse_u = 0, sse_y = 0;
  for (size_t k = 1; k < r.end_scored && k + preview < r.size(); ++k) {
    // The local gain of the one-step map at the applied drive, before the step.
    const double g = (inv.Trial(r.u[k] + h) - inv.Trial(r.u[k] - h)) / (2 * h);
    const long saturated = inv.ctl().saturated;
    const double u = inv.InverseStep(y[k + preview]);
    if (k < r.first_scored) continue;
    if (inv.ctl().saturated != saturated) ++e.clipped;
    const double du = u - r.u[k], dy = g * du;
    sse_u += du * du;
    ++e.n;
    if (!std::isfinite(
            dy)) {  // no local gain here (issue 37: an oscillator at a clipped drive gave NaN)
      ++e.no_gain;
      continue;
    }
    sse_y += dy * dy;
    e.max_y = std::max(e.max_y, std::abs(dy));
  }
  if (e.n == 0) {
    throw InputError(r.Label() +
                     ": no scored sample has its response within the record (the inverse reads " +
                     std::to_string(preview) + " sample(s) ahead: the model's delay)");
  }
  e.rms_u = std::sqrt(sse_u / static_cast<double>(e.n));
  e.rms_y = e.n > e.no_gain ? std::sqrt(sse_y / static_cast<double>(e.n - e.no_gain)) : 0.0;
  return e;
}

}  // namespace pz::records
