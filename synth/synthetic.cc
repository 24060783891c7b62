#include "synth/synthetic.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <utility>

#include "io/fin_records.h"
#include "model/saturation.h"
#include "records/excitation.h"
#include "records/registry.h"

namespace pz::synth {

double NormalDraw(opt::Rng& rng, NormalForm form) {
  const double u = rng.Uniform01(), v = rng.Uniform01();
  const double a = form == NormalForm::kComplement ? 1 - u : std::max(u, 1e-300);
  return std::sqrt(-2 * std::log(a)) * std::cos(2 * std::numbers::pi * v);
}

void Measure(std::span<double> y, const Measurement& m, opt::Rng& rng) {
  for (double& v : y) {
    v += m.offset + (m.noise_std > 0 ? m.noise_std * NormalDraw(rng, m.normal) : 0);
    v = Quantise(v, m.quantum);
  }
}

const char* WaveformName(Waveform w) {
  switch (w) {
    case Waveform::kSine:
      return "sine";
    case Waveform::kMultisine:
      return "multisine";
    case Waveform::kTriangle:
      return "triangle";
    case Waveform::kSquare:
      return "square";
    case Waveform::kSweep:
      return "sweep";
  }
  return "?";
}

std::vector<double> MakeDrive(const DriveShape& s) {
  if (!(s.fs_hz > 0) || !(s.duration_s > 0) || !(s.rest_s >= 0) || !(s.frequency_hz > 0) ||
      !(s.amplitude >= 0)) {
    throw InputError(
        "drive shape: fs, duration and frequency must be > 0, rest and amplitude >= 0");
  }
  const double pi2 = 2 * std::numbers::pi;
  const size_t rest = static_cast<size_t>(std::llround(s.rest_s * s.fs_hz));
  const size_t n = rest + static_cast<size_t>(std::llround(s.duration_s * s.fs_hz));
  std::vector<double> u(n + 1, s.bias);
  std::vector<double> freqs, phases;
  if (s.waveform == Waveform::kMultisine) {
    opt::Rng rng(s.seed);
    const int L = std::max(1, s.lines);
    for (int i = 0; i < L; ++i) {
      const double f = L == 1 ? s.frequency_hz
                              : s.frequency_hz * std::pow(s.frequency_end_hz / s.frequency_hz,
                                                          double(i) / (L - 1));
      freqs.push_back(f);
      phases.push_back(pi2 * rng.Uniform01());
    }
  }
  const double slew = std::max(s.slew_s, 1 / s.fs_hz);
  for (size_t k = rest; k <= n; ++k) {
    const double t = static_cast<double>(k - rest) / s.fs_hz;
    double v = 0;
    const double cyc = s.frequency_hz * t + s.phase_rad / pi2;
    switch (s.waveform) {
      case Waveform::kSine:
        v = std::sin(pi2 * cyc);
        break;
      case Waveform::kTriangle: {
        const double x = cyc + 0.25 - std::floor(cyc + 0.25);  // sin-aligned triangle
        v = x < 0.5 ? 4 * x - 1 : 3 - 4 * x;
        break;
      }
      case Waveform::kSquare: {
        // A square wave with linear edges of duration `slew`, aligned with the sine's sign.
        const double period = 1 / s.frequency_hz;
        const double x = (cyc - std::floor(cyc)) * period;
        const double half = period / 2;
        if (x < slew)
          v = -1 + 2 * x / slew;
        else if (x < half)
          v = 1;
        else if (x < half + slew)
          v = 1 - 2 * (x - half) / slew;
        else
          v = -1;
        break;
      }
      case Waveform::kSweep: {
        const double T = s.duration_s, f0 = s.frequency_hz, f1 = s.frequency_end_hz;
        v = std::sin(pi2 * (f0 * t + (f1 - f0) * t * t / (2 * T)) + s.phase_rad);
        break;
      }
      case Waveform::kMultisine: {
        double acc = 0, norm = 0;
        for (size_t i = 0; i < freqs.size(); ++i) {
          acc += std::sin(pi2 * freqs[i] * t + phases[i] + s.phase_rad);
          norm += 1;
        }
        v = acc / std::sqrt(2 * norm) * 1.0;  // RMS ≈ 1/2: peaks near ±1
        v = std::max(-1.0, std::min(1.0, v));
        break;
      }
    }
    u[k] = s.bias + s.amplitude * v;
  }
  return u;
}

records::DataScale SyntheticStackScale() {
  records::DataScale s;
  s.u_min = -100;
  s.u_max = 100;
  s.u_half = 100;
  s.y_half = 10;
  s.gain = 0.1;
  s.f_dom = 1;
  s.fs = 500;
  s.duration = 4;
  return s;
}

io::Record RecordOfDrive(const DriveShape& shape) {
  io::Record r;
  r.u = MakeDrive(shape);
  const size_t n = r.u.size();
  r.dt = 1 / shape.fs_hz;
  r.t.resize(n);
  for (size_t k = 0; k < n; ++k) r.t[k] = static_cast<double>(k) * r.dt;
  r.rest_samples = 1;
  while (r.rest_samples < n && r.u[r.rest_samples] == r.u[0]) ++r.rest_samples;
  return r;
}

io::Record SynthesizeRecord(const records::RecordModel& truth, std::span<const double> params,
                            std::span<const double> weights, const DriveShape& shape,
                            const Measurement& m, const std::string& name, model::CaseRole role,
                            double t0_s, double t1_s) {
  io::Record r = RecordOfDrive(shape);
  r.name = name;
  r.role = role;
  r.file = name + ".csv";
  const size_t n = r.u.size();
  r.first_scored = std::min(n - 1, r.rest_samples);
  r.end_scored = n;
  r.y.assign(n, 0);
  truth.Simulate(r, params, weights, n, r.y);
  opt::Rng rng(m.seed * 7919 + 17);
  Measure(r.y, m, rng);
  r.quantum = m.quantum;
  if (t1_s > t0_s) io::SetWindow(r, t0_s, t1_s, 20, "window of " + name);
  return r;
}

// ---- the trials of a calibration check -------------------------------------------------------

records::EffectKind DrawEffectKind(opt::Rng& rng, std::span<const records::EffectKind> kinds) {
  if (kinds.empty()) throw InputError("synthetic trial: no effect to draw from");
  return kinds[rng.UniformBelow(kinds.size())];
}

TruthDraw TruthDrawOf(opt::Rng& rng) {
  return TruthDraw([&rng] { return rng.Uniform01(); });
}

namespace {

// The paper's nine cases (V, f) and split (training 1, 5, 6, 7).
struct CaseDef {
  int number;
  double v, f;
  bool training;
};
constexpr CaseDef kCases[9] = {{1, 375, 0.25, true},  {2, 375, 0.5, false}, {3, 375, 1.0, false},
                               {4, 500, 0.25, false}, {5, 500, 0.5, true},  {6, 500, 1.0, true},
                               {7, 750, 0.25, true},  {8, 750, 0.5, false}, {9, 750, 1.0, false}};

std::string NoTruth(const char* check, records::EffectKind e, const char* draw) {
  return std::string(check) + ": effect '" + e.name() + "' draws no truth (its " + draw +
         " in synth/truth_draw.cc)";
}

}  // namespace

std::string FinTrialOptions::Validate() const {
  auto share = [](const char* field, double v) {
    return v >= 0 && v <= 1 ? std::string() : FieldError(field, v, "must be in [0, 1]");
  };
  if (!(quantum_deg >= 0 && std::isfinite(quantum_deg)))
    return FieldError("quantum_deg", quantum_deg, "must be finite and >= 0");
  if (!(jitter_rms_deg >= 0 && std::isfinite(jitter_rms_deg)))
    return FieldError("jitter_rms_deg", jitter_rms_deg, "must be finite and >= 0");
  if (std::string e = share("none_probability", none_probability); !e.empty()) return e;
  return share("other_form_probability", other_form_probability);
}

io::CaseSet SimulateBench(const model::BimorphPlant& plant, const model::BimorphParams& params,
                          const std::vector<records::Effect>& effects,
                          const std::vector<std::pair<double, double>>& saturations,
                          const FinTrialOptions& o, opt::Rng& rng) {
  if (saturations.size() != std::size(kCases))
    throw InputError("synthetic bench: " + std::to_string(saturations.size()) +
                     " saturation pairs for the " + std::to_string(std::size(kCases)) + " cases");
  const records::EffectSimulator sim(plant);
  const Measurement encoder{
      .noise_std = o.jitter_rms_deg, .quantum = o.quantum_deg, .normal = NormalForm::kDrawn};
  io::CaseSet set;
  set.dir = "bench";
  for (int c = 0; c < 9; ++c) {
    const CaseDef& def = kCases[c];
    const model::Sinusoid d{def.v, def.f};
    model::BimorphParams p = params;
    p.b1 = saturations[c].first;
    p.b2 = saturations[c].second;
    io::BenchCaseSamples b;
    b.number = def.number;
    b.amplitude_v = d.amplitude_v;
    b.frequency_hz = d.frequency_hz;
    b.role = def.training ? io::CaseRole::kTrain : io::CaseRole::kValidate;
    b.sample_rate_hz = d.sample_rate_hz;
    b.cycles = d.cycles;
    b.file = "case" + std::to_string(def.number);
    b.angle_deg.resize(static_cast<size_t>(d.NumSamples()));
    const model::SimulationSummary s = sim.SimulateAngle(p, effects, d, b.angle_deg);
    const std::string at = "synthetic bench, case " + std::to_string(def.number);
    if (!s.ok()) throw InputError(at + ": " + s.message);
    Measure(b.angle_deg, encoder, rng);
    set.cases.push_back(io::MakeBenchCase(
        std::move(b), {},
        [&](std::string_view field, size_t) { return at + " " + std::string(field); }, ""));
  }
  return set;
}

namespace {

SyntheticTrial DrawFinTrial(const model::BimorphPlant& plant, uint64_t seed,
                            const FinTrialOptions& o, std::span<const model::EffectKind> kinds) {
  opt::Rng rng(seed);
  SyntheticTrial t;
  t.seed = seed;
  // The bench plant, around the physical bench's values.
  model::BimorphParams p;
  p.mu = UniformDraw(rng, 60, 130);
  p.delta = UniformDraw(rng, 0.07, 0.13);
  p.alpha = UniformDraw(rng, 1.5e-3, 3.5e-3);
  p.beta = UniformDraw(rng, 4e-3, 8e-3);
  p.gamma = p.beta * UniformDraw(rng, 0.3, 0.8);
  p.a1 = UniformDraw(rng, 0.05, 0.15);
  p.a2 = UniformDraw(rng, 0.1, 0.2);
  // Saturations: the paper's regression with a ±4 % spread.
  const model::SaturationRegression reg = model::PaperSaturationRegression();
  std::vector<std::pair<double, double>> sat;
  for (const CaseDef& c : kCases) {
    const model::SaturationPair s = reg.Predict(c.v, c.f);
    sat.push_back({s.b1 * UniformDraw(rng, 0.96, 1.04), s.b2 * UniformDraw(rng, 0.96, 1.04)});
  }
  // The effect.
  const bool none = rng.Uniform01() < o.none_probability;
  const bool other_form = rng.Uniform01() < o.other_form_probability;
  if (!none) {
    t.truth = DrawEffectKind(rng, kinds);
    TruthDraw draw = TruthDrawOf(rng);
    FinTruth truth = DrawFinTruth(t.truth, draw, other_form);
    if (truth.parts.empty()) throw InputError(NoTruth("synthetic bench", t.truth, "DrawFinTruth"));
    t.form = std::move(truth.form);
    t.magnitude = truth.magnitude;
    for (std::vector<double>& part : truth.parts) t.effects.push_back({t.truth, std::move(part)});
  }
  std::ostringstream os;
  os << "seed " << seed << ": " << model::EffectName(t.truth);
  if (!t.form.empty()) os << " (" << t.form << ")";
  for (const records::Effect& e : t.effects) os << " " << e.Describe();
  t.description = os.str();
  try {
    t.set = io::RecordsFromCaseSet(SimulateBench(plant, p, t.effects, sat, o, rng));
  } catch (const InputError& e) {
    throw InputError(t.description + ": " + e.what());
  }
  return t;
}

}  // namespace

TrialDraw FinTrialDraw(const FinTrialOptions& o) {
  if (const std::string e = o.Validate(); !e.empty()) throw InputError("synthetic bench: " + e);
  std::vector<records::EffectKind> kinds = o.kinds;
  if (kinds.empty())
    for (const auto& e : records::FinEffects()) kinds.push_back(e.kind);
  auto plant = std::make_shared<const model::BimorphPlant>();
  return [plant, o, kinds](uint64_t seed) { return DrawFinTrial(*plant, seed, o, kinds); };
}

std::vector<records::EffectKind> RecordsTrialEffects(const records::Family& family) {
  std::vector<records::EffectKind> kinds;
  for (records::EffectKind k : records::RecordEffects())
    if (!family.Excludes(k.name()) && !records::NeedsRateCoverage(k)) kinds.push_back(k);
  return kinds;
}

namespace {

struct RecordsForm {
  RecordsTrialOptions options;
  records::DataScale scale;
  std::shared_ptr<const records::Family> family;
  std::vector<double> nominal;
  std::vector<records::EffectKind> kinds;
};

/// The truth's parameters (the family's, then the effect's; a linear family's in `weights`) and
/// the effect, drawn on rng.
void DrawTrialTruth(const RecordsForm& f, opt::Rng& rng, SyntheticTrial& t, std::vector<double>& p,
                    std::vector<double>& weights) {
  p = f.nominal;
  for (double& v : p) v *= UniformDraw(rng, 0.8, 1.25);
  if (f.family->linear()) weights = std::exchange(p, {});  // p: the effect's parameters
  if (rng.Uniform01() >= f.options.none_probability) {
    t.truth = DrawEffectKind(rng, f.kinds);
    TruthDraw draw = TruthDrawOf(rng);
    const std::vector<double> truth = DrawRecordsTruth(t.truth, draw, f.scale);
    if (truth.empty())
      throw InputError(NoTruth("diagnose-check --records", t.truth, "DrawRecordsTruth"));
    p.insert(p.end(), truth.begin(), truth.end());
    t.magnitude = p.back();
  }
}

SyntheticTrial DrawRecordsTrial(const RecordsForm& f, uint64_t seed) {
  SyntheticTrial t;
  t.seed = seed;
  opt::Rng rng(seed * 104729 + 7);
  std::vector<double> p, weights;
  DrawTrialTruth(f, rng, t, p, weights);
  std::ostringstream desc;
  if (t.truth.none())
    desc << "none";
  else
    desc << records::EffectName(t.truth) << " " << p.back();
  DriveShape d;
  d.amplitude = 100;
  d.frequency_hz = 1;
  d.frequency_end_hz = 6;
  d.phase_rad = UniformDraw(rng, 0, 2 * std::numbers::pi);
  d.rest_s = 0.5;
  d.duration_s = 6;
  d.fs_hz = 500;
  d.seed = seed;
  const double w = rng.Uniform01();
  d.waveform = w < 0.4 ? Waveform::kSine : w < 0.7 ? Waveform::kMultisine : Waveform::kTriangle;
  desc << ", " << WaveformName(d.waveform);
  t.description = desc.str();
  std::vector<records::EffectKind> effects;
  if (!t.truth.none()) effects.push_back(t.truth);
  const records::RecordModel truth(f.family, effects, f.scale);
  io::Record r =
      SynthesizeRecord(truth, p, weights, d, {UniformDraw(rng, -2, 2), 0.02, 0.005, seed}, "rec",
                       model::CaseRole::kTrain);
  const double t0 = r.t[r.rest_samples] + 0.2, t2 = r.t.back(), t1 = t0 + 0.6 * (t2 - t0);
  t.set.source = "synthetic";
  io::Record tr = r, wh = r;
  tr.name = "train";
  io::SetWindow(tr, t0, t1, 20, "train");
  wh.name = "withheld";
  wh.role = model::CaseRole::kValidate;
  io::SetWindow(wh, t1, t2, 20, "withheld");
  t.set.records = {std::move(tr), std::move(wh)};
  return t;
}

}  // namespace

std::vector<std::string> RecordsTrialFamilies() {
  std::vector<std::string> out;
  for (const std::string& name : records::FamilyNames())
    if (!records::MakeFamily(name, SyntheticStackScale())->CheckNominal().empty())
      out.push_back(name);
  return out;
}

TrialDraw RecordsTrialDraw(const RecordsTrialOptions& o) {
  if (!(o.none_probability >= 0 && o.none_probability <= 1))
    throw InputError(FieldError("none_probability", o.none_probability, "must be in [0, 1]"));
  auto f = std::make_shared<RecordsForm>();
  f->options = o;
  f->scale = SyntheticStackScale();
  f->family = records::MakeFamily(o.family, f->scale);
  f->nominal = f->family->CheckNominal();
  if (f->nominal.empty()) {
    std::string with;
    for (const std::string& name : RecordsTrialFamilies())
      with += (with.empty() ? "" : ", ") + name;
    throw InputError("diagnose-check --records-family: '" + o.family +
                     "' has no nominal parameter set for synthetic records (Family::CheckNominal; "
                     "families with one: " +
                     with + ")");
  }
  f->kinds = RecordsTrialEffects(*f->family);
  return [f](uint64_t seed) { return DrawRecordsTrial(*f, seed); };
}

namespace {

/// A flat comb of sines over [lo, hi] (spacing ≈ 1/(3 s) to at most 400 lines), random phases, RMS
/// `rms`, at t.
struct Comb {
  std::vector<double> f, phase;
  double gain = 0;
  Comb(double lo, double hi, double rms, opt::Rng& rng) {
    const double step = std::max((hi - lo) / 400, 1.0 / 3);
    for (double x = lo; x <= hi; x += step) {
      f.push_back(x);
      phase.push_back(UniformDraw(rng, 0, 2 * std::numbers::pi));
    }
    gain = rms * std::sqrt(2.0 / static_cast<double>(f.size()));
  }
  double operator()(double t) const {
    double v = 0;
    for (size_t i = 0; i < f.size(); ++i) v += std::sin(2 * std::numbers::pi * f[i] * t + phase[i]);
    return gain * v;
  }
};

/// One record of the mode bench: 50 ms at the range's middle, a step to the rest level at the
/// bottom, the rest, the drive (simulated from the middle so that the rest rings, then cut after
/// the step).
io::Record ModeRecord(const records::RecordModel& truth, const ModeBench& b,
                      const ModeBenchOptions& o, bool chatter, double seconds,
                      const std::string& name, uint64_t seed) {
  opt::Rng rng(seed * 6151 + 29);
  const Comb comb(o.band_lo_hz, o.band_hi_hz, o.band_rms_v, rng);
  const double dt = 1 / o.fs_hz, bottom = -o.sine_v;
  const size_t pre = static_cast<size_t>(std::round(0.05 / dt)),
               rest = static_cast<size_t>(std::round(o.rest_s / dt)),
               n = pre + rest + static_cast<size_t>(std::round(seconds / dt));
  io::Record full;
  double telegraph = o.chatter_v;
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    double u = k < pre ? 0 : bottom;
    if (k >= pre + rest) {
      const double te = static_cast<double>(k - pre - rest) * dt, ramp = std::min(1.0, te / 0.02);
      if (chatter) {
        const double ph = std::fmod(te * o.sine_hz, 1.0);  // a triangle from the bottom
        if (rng.Uniform01() < 0.2) telegraph = -telegraph;
        u = bottom + 2 * o.sine_v * (ph < 0.5 ? 2 * ph : 2 - 2 * ph) + ramp * telegraph;
      } else {
        u = -o.sine_v * std::cos(2 * std::numbers::pi * o.sine_hz * te) + ramp * comb(te);
      }
    }
    full.t.push_back(t);
    full.u.push_back(u);
  }
  full.dt = dt;
  full.rest_samples = pre;
  full.end_scored = n;
  full.y.assign(n, 0);
  truth.Simulate(full, b.params, b.weights, n, full.y);
  Measure(full.y, {.noise_std = o.noise_std}, rng);
  io::Record r;
  r.name = name;
  r.file = name + ".csv";
  r.dt = dt;
  for (size_t k = pre; k < n; ++k) {
    r.t.push_back(static_cast<double>(k - pre) * dt);
    r.u.push_back(full.u[k]);
    r.y.push_back(full.y[k]);
  }
  r.rest_samples = rest;
  r.first_scored = rest;
  r.end_scored = r.size();
  return r;
}

}  // namespace

ModeBench MakeModeBench(const ModeBenchOptions& o) {
  if (!(o.f_n_hz > 0 && o.f_n_hz < 0.45 * o.fs_hz))
    throw InputError(FieldError("f_n_hz", o.f_n_hz, "must be in (0, 0.45 fs)"));
  const records::DataScale scale = SyntheticStackScale();
  const std::shared_ptr<const records::Family> family = records::MakeFamily(o.family, scale);
  ModeBench b;
  b.params = family->CheckNominal();
  if (b.params.empty())
    throw InputError("mode bench: family '" + o.family + "' has no nominal parameter set");
  if (family->linear()) b.weights = std::exchange(b.params, {});
  b.params.insert(b.params.end(), {o.share, o.f_n_hz, o.zeta});
  const records::RecordModel truth(family, {records::EffectKind::Named("resonance")}, scale);
  std::ostringstream d;
  d << o.family << " + resonance (f_n " << o.f_n_hz << " Hz, zeta " << o.zeta << ", share "
    << o.share << "), " << o.fs_hz << " Hz, withheld " << (o.chatter_v > 0 ? "chatter" : "noise");
  b.description = d.str();
  b.set.source = "mode bench";
  b.set.records.push_back(ModeRecord(truth, b, o, false, o.train_s, "train", o.seed));
  b.set.records.push_back(
      ModeRecord(truth, b, o, o.chatter_v > 0, o.withheld_s, "withheld", o.seed + 1));
  b.set.records.back().role = model::CaseRole::kValidate;
  return b;
}

}  // namespace pz::synth
