#include "records/fin_effects.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "model/backlash.h"
#include "model/cvode.h"

namespace pz::records {

using model::ApplyBacklash;
using model::BimorphExtension;
using model::BimorphOde;
using model::BimorphParams;
using model::BimorphPlant;
using model::CvodeOptions;
using model::DataScale;
using model::DriveSignal;
using model::EffectDef;
using model::EffectIndex;
using model::EffectKind;
using model::EffectStage;
using model::FindEffect;
using model::IntegrateCvode;
using model::LinearSolverKind;
using model::ModalWorkspace;
using model::NonlinearIteration;
using model::OdeMethod;
using model::OdeSolution;
using model::OutputFrame;
using model::ParamInfo;
using model::SampledSignal;
using model::SimStatus;
using model::SimulationSummary;
using model::Sinusoid;
using model::StageName;

namespace {

// One parameter of the fin bench's box of an effect, in the library's order (EffectDef::Params):
// the physical range, a typical magnitude (search scaling, finite-difference steps, > 0), a doc
// line and, where the fin's output differs from the library's scale, the unit (null: the
// library's).
struct FinParam {
  double lower = 0, upper = 0, scale = 1;
  bool log_scale = false;
  const char* doc = "";
  const char* unit = nullptr;
};
// The fin bench's box of an effect it offers, keyed by the library's name, and the effect's place
// in the fin's order — the order the fin's diagnosis tries candidates, its check draws truths and
// its confusion matrix lists rows (the order of the fin's former enum, kept so seeded checks stay
// the same; a new effect takes the next number). At most 2 parameters today.
struct FinBox {
  const char* effect = "";
  int order = 0;
  FinParam params[2] = {};
  int count = 1;
};

// The boxes: an effect the fin bench offers has one line here; the library (model/) knows nothing
// of the bench.
const FinBox kFinBoxes[] = {
    {.effect = "driver-lowpass",
     .order = 1,
     .params = {{.upper = 0.2, .scale = 0.01, .doc = "time constant of the amplifier"}}},
    {.effect = "creep",
     .order = 2,
     .params = {{.upper = 1.0,
                 .scale = 0.05,
                 .doc = "creep gain: long-run extra share of the drive"},
                {.lower = 0.05,
                 .upper = 50.0,
                 .scale = 2.0,
                 .log_scale = true,
                 .doc = "creep relaxation time"}},
     .count = 2},
    {.effect = "hinge-friction",
     .order = 3,
     .params = {{.upper = 1.0, .scale = 0.05, .doc = "Coulomb level F_c of the friction force"},
                {.lower = 20.0,
                 .upper = 2e5,
                 .scale = 2000.0,
                 .log_scale = true,
                 .doc = "pre-sliding stiffness sigma"}},
     .count = 2},
    {.effect = "delay", .order = 4, .params = {{.upper = 0.1, .scale = 0.005, .doc = "delay"}}},
    {.effect = "cubic-stiffening",
     .order = 5,
     .params = {{.lower = -5e6,
                 .upper = 2e7,
                 .scale = 1e6,
                 .doc = "cubic tip stiffness (linear tip stiffness is about 500 N/m)"}}},
    {.effect = "quadratic-drive",
     .order = 6,
     .params =
         {{.lower = -5e-4, .upper = 5e-4, .scale = 2e-5, .doc = "quadratic drive coefficient"}}},
    {.effect = "drift",
     .order = 7,
     .params =
         {{.lower = -0.2, .upper = 0.2, .scale = 0.005, .doc = "drift rate", .unit = "deg/s"}}},
};

// The fin's effects: every library effect with a fin box, in the fin's order.
std::vector<FinEffectInfo> BuildLibrary() {
  std::vector<std::pair<int, FinEffectInfo>> lib;
  for (const FinBox& box : kFinBoxes) {
    const EffectDef* def = EffectKind::Named(box.effect).def();  // throws for a stale name
    const std::vector<ParamInfo> names = def->Params(DataScale{});
    if (names.size() != static_cast<size_t>(box.count))
      throw std::logic_error(std::string("fin box of '") + def->name() + "': parameter count");
    FinEffectInfo info{*def, def, def->name(), def->title(), def->stage(), def->equation(), 0, {}};
    for (size_t i = 0; i < names.size(); ++i) {
      const FinParam& p = box.params[i];
      info.params.push_back({names[i].name, p.unit ? p.unit : names[i].unit, p.lower, p.upper,
                             p.scale, p.log_scale, p.doc});
    }
    for (const auto& [order, other] : lib)
      if (order == box.order || other.def == def)
        throw std::logic_error(std::string("fin boxes of '") + other.name + "' and '" +
                               def->name() + "': same order or same effect");
    lib.push_back({box.order, std::move(info)});
  }
  std::sort(lib.begin(), lib.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<FinEffectInfo> out;
  for (auto& [order, info] : lib) out.push_back(std::move(info));
  return out;
}

const FinEffectInfo& NoneInfo() {
  static const FinEffectInfo none{EffectKind(),         nullptr, "none", "no unmodelled effect",
                                  EffectStage::kOutput, "",      -1,     {}};
  return none;
}

// One non-identity effect of a list with its library effect.
struct Link {
  const EffectDef* def;
  std::span<const double> p;
};

// The non-identity effects of a list of one stage (any stage: all), in the library's chain order
// (stable: effects of one kind keep their list order).
std::vector<Link> Chain(std::span<const Effect> effects, const EffectStage* stage = nullptr) {
  std::vector<std::pair<size_t, Link>> r;
  for (const Effect& e : effects) {
    if (e.IsIdentity()) continue;
    const FinEffectInfo& info = GetFinEffectInfo(e.kind);
    const EffectDef* def = info.def;
    if (def == nullptr ||
        e.params.size() != info.params.size())  // callers validate first; never read past
      throw std::invalid_argument("invalid effect: " + e.Describe() +
                                  " (Effect::Validate says why)");
    if (stage != nullptr && def->stage() != *stage) continue;
    r.push_back({EffectIndex(*def), Link{def, e.params}});
  }
  std::stable_sort(r.begin(), r.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Link> out;
  for (auto& [i, l] : r) out.push_back(l);
  return out;
}

// Per-thread scratch of the fast sampled path.
struct SampledScratch {
  DriveSignal signal = SampledSignal{};
  std::vector<double> t_fine, theta_fine, grid;
  ModalWorkspace ws;
};

SampledScratch& Scratch() {
  thread_local SampledScratch s;
  return s;
}

}  // namespace

const std::vector<FinEffectInfo>& FinEffects() {
  static const std::vector<FinEffectInfo> lib = BuildLibrary();
  return lib;
}

const FinEffectInfo& GetFinEffectInfo(EffectKind kind) {
  for (const FinEffectInfo& e : FinEffects())
    if (e.kind == kind) return e;
  return NoneInfo();
}

bool IsFinEffect(EffectKind kind) { return !kind.none() && GetFinEffectInfo(kind).kind == kind; }

int FinIndex(EffectKind kind) {
  if (kind.none()) return 0;
  const auto& lib = FinEffects();
  for (size_t i = 0; i < lib.size(); ++i)
    if (lib[i].kind == kind) return static_cast<int>(i) + 1;
  throw std::logic_error(std::string("effect '") + kind.name() +
                         "' is not an effect of the fin bench");
}

std::optional<EffectKind> ParseEffectKind(std::string_view name) {
  if (name == "none") return EffectKind();
  const EffectDef* def = FindEffect(name);
  if (def == nullptr || !IsFinEffect(*def)) return std::nullopt;
  return EffectKind(*def);
}

std::string FinEffectError(std::string_view name) {
  std::string known;
  for (const FinEffectInfo& e : FinEffects()) known += (known.empty() ? "" : ", ") + e.name;
  const EffectDef* def = FindEffect(name);
  if (def != nullptr)
    return "not an effect of the fin bench: '" + std::string(name) + "' is the library's " +
           StageName(def->stage()) +
           "-stage effect of the records families (fin effects: " + known + ")";
  return "not an effect of the library: '" + std::string(name) +
         "' is unknown (fin effects: " + known + ")";
}

Status Effect::Validate() const {
  const FinEffectInfo& info = GetFinEffectInfo(kind);
  if (!kind.none() && info.kind != kind)
    return InvalidArgument(
        FieldError("effect.kind", std::string(kind.name()), "not an effect of the fin bench"));
  if (params.size() != info.params.size())
    return InvalidArgument(FieldError(info.name + ".params.size()", params.size(),
                                      "must be " + std::to_string(info.params.size())));
  for (size_t i = 0; i < params.size(); ++i) {
    const EffectParamInfo& p = info.params[i];
    const double v = params[i];
    const std::string field = info.name + "." + p.name;
    if (!std::isfinite(v)) return InvalidArgument(FieldError(field, v, "must be finite"));
    if (v < p.lower || v > p.upper) {
      std::ostringstream r;
      r << "must be in [" << p.lower << ", " << p.upper << "] " << p.unit;
      return InvalidArgument(FieldError(field, v, r.str()));
    }
  }
  return Status::Ok();
}

bool Effect::IsIdentity() const {
  if (kind.none()) return true;
  const FinEffectInfo& info = GetFinEffectInfo(kind);
  return info.magnitude_param >= 0 && static_cast<size_t>(info.magnitude_param) < params.size() &&
         params[info.magnitude_param] == 0.0;
}

std::string Effect::Describe() const {
  const FinEffectInfo& info = GetFinEffectInfo(kind);
  std::ostringstream os;
  os.precision(4);
  os << info.name;
  if (info.params.empty()) return os.str();
  os << "(";
  for (size_t i = 0; i < info.params.size(); ++i) {
    os << (i ? ", " : "") << info.params[i].name << " = ";
    if (i < params.size())
      os << params[i];
    else
      os << "?";
    if (info.params[i].unit != "-") os << " " << info.params[i].unit;
  }
  os << ")";
  return os.str();
}

Effect Effect::Zero(EffectKind kind) {
  const FinEffectInfo& info = GetFinEffectInfo(kind);
  Effect e{kind, {}};
  for (size_t i = 0; i < info.params.size(); ++i) {
    const EffectParamInfo& p = info.params[i];
    double v = p.log_scale ? std::sqrt(p.lower * p.upper) : 0.5 * (p.lower + p.upper);
    if (static_cast<int>(i) == info.magnitude_param) v = 0.0;
    e.params.push_back(std::clamp(v, p.lower, p.upper));
  }
  return e;
}

bool NeedsCvode(std::span<const Effect> effects) {
  for (const Effect& e : effects)
    if (!e.IsIdentity() && GetFinEffectInfo(e.kind).stage == EffectStage::kBeam) return true;
  return false;
}

Status EffectSimOptions::Validate() const {
  if (oversample < 1 || oversample > 64)
    return InvalidArgument(FieldError("oversample", oversample, "must be in [1, 64]"));
  return model::ValidateCvodeSettings(rtol, atol, max_steps);
}

std::vector<double> ShapedDrive(std::span<const Effect> effects, const Sinusoid& drive,
                                std::span<const double> t) {
  std::vector<double> out(t.size(), 0.0);
  if (t.empty()) return out;
  const double V = drive.amplitude_v, om = 2 * std::numbers::pi * drive.frequency_hz;
  const EffectStage kDrive = EffectStage::kDrive;
  const std::vector<Link> chain = Chain(effects, &kDrive);
  double shift = 0;
  bool filters = false;
  for (const Link& l : chain) {
    const double s = l.def->TimeShift(l.p);
    shift += s;
    filters = filters || (!l.def->memoryless() && s == 0);
  }
  if (!filters) {
    // Pointwise: exact at every time (the delays as a shift of the sinusoid's time).
    for (size_t j = 0; j < t.size(); ++j) {
      const double te = t[j] - shift;
      if (te > 0) out[j] = V * std::sin(om * te);
    }
    for (const Link& l : chain)
      if (l.def->memoryless()) l.def->ApplyDrive(l.p, 0.0, out);
    return out;
  }
  // Internal grid 4 x finer than the spacing of t (its smallest step), from 0 to the last time; the
  // library's drive chain on it; then read at t by linear interpolation.
  double hmin = t.back() > 0 ? t.back() : 1.0;
  for (size_t j = 1; j < t.size(); ++j) hmin = std::min(hmin, t[j] - t[j - 1]);
  const double h = hmin / 4;
  const long n = static_cast<long>(std::ceil(std::max(t.back(), 0.0) / h)) + 2;
  std::vector<double> s(n);
  for (long j = 0; j < n; ++j) s[j] = V * std::sin(om * (j * h));
  for (const Link& l : chain) l.def->ApplyDrive(l.p, h, s);
  for (size_t j = 0; j < t.size(); ++j) {
    if (t[j] <= 0) continue;
    const double r = t[j] / h;
    const long i = std::min(static_cast<long>(r), n - 2);
    const double w = r - i;
    out[j] = (1 - w) * s[i] + w * s[i + 1];
  }
  return out;
}

std::vector<std::unique_ptr<BimorphExtension>> MakeExtensions(std::span<const Effect> effects) {
  std::vector<std::unique_ptr<BimorphExtension>> ext;
  for (const Link& l : Chain(effects))
    if (auto e = l.def->MakeExtension(l.p)) ext.push_back(std::move(e));
  return ext;
}

EffectSimulator::EffectSimulator(const BimorphPlant& plant) : plant_(&plant), modal_(plant) {}

SimulationSummary EffectSimulator::SimulateAngle(const BimorphParams& params,
                                                 std::span<const Effect> effects,
                                                 const Sinusoid& drive, std::span<double> angle_deg,
                                                 const EffectSimOptions& options,
                                                 std::span<double> theta_deg) const {
  const auto start = std::chrono::steady_clock::now();
  SimulationSummary summary;
  auto fail = [&](SimStatus st, std::string msg) {
    summary.status = st;
    summary.message = std::move(msg);
    summary.wall_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
  };
  if (auto s = params.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (auto s = drive.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (auto s = options.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  for (const Effect& e : effects)
    if (auto s = e.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  const size_t n_out = static_cast<size_t>(drive.NumSamples());
  if (angle_deg.size() != n_out || (!theta_deg.empty() && theta_deg.size() != n_out))
    return fail(SimStatus::kInvalidInput,
                "output buffers must have " + std::to_string(n_out) + " samples");
  if (!params.HysteresisBounded())
    return fail(SimStatus::kUnboundedHysteresis, "Bouc-Wen loop unbounded");

  const EffectStage kDrive = EffectStage::kDrive, kOutput = EffectStage::kOutput;
  const std::vector<Link> drive_chain = Chain(effects, &kDrive),
                          output_chain = Chain(effects, &kOutput);
  const bool any_drive = !drive_chain.empty();
  double delay = 0;
  for (const Link& l : drive_chain) delay += l.def->TimeShift(l.p);
  const double fs = drive.sample_rate_hz;
  // The linear angle θ on the record's grid goes into `theta` (caller's buffer or scratch).
  thread_local std::vector<double> theta_buf;
  std::span<double> theta = theta_deg;
  if (theta.empty()) {
    theta_buf.resize(n_out);
    theta = theta_buf;
  }
  BimorphParams lin = params;  // identity backlash: the simulators' angle output is θ
  lin.a1 = lin.a2 = 0.0;
  lin.b1 = 1e9;
  lin.b2 = -1e9;

  if (options.force_cvode || NeedsCvode(effects)) {
    auto ext = MakeExtensions(effects);
    std::vector<const BimorphExtension*> ptrs;
    for (auto& e : ext) ptrs.push_back(e.get());
    const DriveSignal sig = drive;
    BimorphOde ode(*plant_, lin, sig, ptrs);
    // Output times shifted by the delay (exact for a time-invariant plant from rest).
    std::vector<double> t_out;
    size_t first = 0;
    for (size_t k = 0; k < n_out; ++k) {
      const double te = static_cast<double>(k) / fs - delay;
      if (te < 0) {
        ++first;
        continue;
      }
      t_out.push_back(te);
    }
    std::fill(theta.begin(), theta.begin() + first, 0.0);
    if (!t_out.empty()) {
      CvodeOptions co;
      co.method = OdeMethod::kBdf;
      co.iteration = NonlinearIteration::kNewton;
      co.linear_solver = LinearSolverKind::kDense;
      co.rtol = options.rtol;
      co.atol = options.atol;
      co.max_steps = options.max_steps;
      co.breakpoints = ode.Breakpoints();
      std::vector<double> y0 = ode.InitialState();
      const OdeSolution sol = IntegrateCvode(ode, 0.0, y0, t_out, co);
      summary = sol.summary;
      if (!summary.ok()) return fail(summary.status, summary.message);
      for (size_t k = 0; k < t_out.size(); ++k)
        theta[first + k] = plant_->TipToDegrees(sol.at(k, ode.tip_index()));
    }
  } else if (any_drive) {
    SampledScratch& sc = Scratch();
    const int m = options.oversample;
    const size_t n_fine = (n_out - 1) * m + 1;
    sc.t_fine.resize(n_fine);
    for (size_t j = 0; j < n_fine; ++j) sc.t_fine[j] = static_cast<double>(j) / (fs * m);
    SampledSignal& sig = std::get<SampledSignal>(sc.signal);
    sig.t = sc.t_fine;
    sig.u = ShapedDrive(effects, drive, sc.t_fine);
    sc.theta_fine.resize(n_fine);
    const SimulationSummary s = modal_.SimulateAngle(lin, sc.signal, sc.theta_fine, sc.ws);
    summary = s;
    if (!summary.ok()) return fail(summary.status, summary.message);
    for (size_t k = 0; k < n_out; ++k) theta[k] = sc.theta_fine[k * m];
  } else {
    SampledScratch& sc = Scratch();
    const SimulationSummary s = modal_.SimulateAngle(lin, drive, theta, sc.ws);
    summary = s;
    if (!summary.ok()) return fail(summary.status, summary.message);
  }
  for (size_t k = 0; k < n_out; ++k)
    if (!std::isfinite(theta[k]))
      return fail(SimStatus::kNonFinite, "non-finite fin angle at sample " + std::to_string(k));
  ApplyBacklash(params.backlash(), theta, angle_deg);
  const OutputFrame frame{1.0 / fs, 0.0,
                          1.0};  // time from the record's start; the fin has no y scale
  for (const Link& l : output_chain) l.def->ApplyOutput(l.p, frame, angle_deg);
  summary.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace pz::records
