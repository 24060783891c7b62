// The resonance effect (issue 45, model/effect_library.cc `resonance`): its step kernel is the
// mode's exact response to a drive linear between samples (the closed-form ramp response and a fine
// RK4 of the ODE, an arithmetic of its own), it is linear with unit gain at DC, a fit places f_n
// and ζ from the residual's band (records/resonance.h) on records of a band-limited-noise drive,
// and the compensator's inverse of it stays bounded and rings no more than its reference low-pass.
#include "records/resonance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "model/effect_library.h"
#include "model/effect_library_resonance.h"
#include "records/fit.h"
#include "records/model.h"
#include "records/registry.h"
#include "records/stepper.h"

namespace pz::records {
namespace {

const model::EffectDef& Mode() { return *EffectKind::Named("resonance").def(); }

/// y = (1 − a) v + a q, q̈ + 2ζω q̇ + ω² q = ω² v, v linear between samples: classical RK4 with
/// `sub` steps a sample, from rest at v[0].
std::vector<double> Rk4Mode(const std::vector<double>& v, double dt, double a, double f_n,
                            double zeta, int sub) {
  const double w = 2 * std::numbers::pi * f_n, h = dt / sub;
  double q = v[0], qd = 0;
  std::vector<double> y = {v[0]};
  for (size_t k = 1; k < v.size(); ++k) {
    const double r = (v[k] - v[k - 1]) / dt;
    for (int j = 0; j < sub; ++j) {
      const double t0 = j * h;
      auto acc = [&](double t, double x, double xd) {
        return w * w * (v[k - 1] + r * t - x) - 2 * zeta * w * xd;
      };
      const double k1 = qd, l1 = acc(t0, q, qd);
      const double k2 = qd + h / 2 * l1, l2 = acc(t0 + h / 2, q + h / 2 * k1, k2);
      const double k3 = qd + h / 2 * l2, l3 = acc(t0 + h / 2, q + h / 2 * k2, k3);
      const double k4 = qd + h * l3, l4 = acc(t0 + h, q + h * k3, k4);
      q += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      qd += h / 6 * (l1 + 2 * l2 + 2 * l3 + l4);
    }
    y.push_back((1 - a) * v[k] + a * q);
  }
  return y;
}

std::vector<double> Apply(std::vector<double> y, double dt, double a, double f_n, double zeta) {
  const double p[3] = {a, f_n, zeta};
  model::OutputFrame f;
  f.dt = dt;
  Mode().ApplyOutput(p, f, y);
  return y;
}

double MaxAbsDiff(const std::vector<double>& x, const std::vector<double>& y) {
  double m = 0;
  for (size_t k = 0; k < x.size(); ++k) m = std::max(m, std::abs(x[k] - y[k]));
  return m;
}

TEST(Resonance, StepIsTheModesExactResponseToARamp) {
  // The textbook ramp response of an underdamped mode from rest: q(t) = r [t − 2ζ/ω +
  // e^{−ζωt} (2ζ/ω cos ω_d t + (2ζ² − 1)/ω_d sin ω_d t)].
  const double dt = 1e-4, r = 3.0, a = 0.8;
  for (double fdt : {0.002, 0.05, 0.3, 0.45}) {
    for (double zeta : {0.005, 0.1, 0.6}) {
      const double f_n = fdt / dt, w = 2 * std::numbers::pi * f_n,
                   wd = w * std::sqrt(1 - zeta * zeta);
      std::vector<double> v, exact;
      for (int k = 0; k < 400; ++k) {
        const double t = k * dt;
        v.push_back(r * t);
        const double q =
            r * (t - 2 * zeta / w +
                 std::exp(-zeta * w * t) * (2 * zeta / w * std::cos(wd * t) +
                                            (2 * zeta * zeta - 1) / wd * std::sin(wd * t)));
        exact.push_back((1 - a) * r * t + a * q);
      }
      const std::vector<double> y = Apply(v, dt, a, f_n, zeta);
      EXPECT_LE(MaxAbsDiff(y, exact), 1e-12 * r * 400 * dt) << "f_n dt " << fdt << " zeta " << zeta;
    }
  }
}

TEST(Resonance, StepMatchesAFineIntegrationOfAnyPiecewiseLinearDrive) {
  // Over- and critically damped too, and near Nyquist: no sampling error anywhere.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> v(300, 0.2);
  for (size_t k = 20; k < v.size(); ++k) v[k] = k % 37 < 5 ? v[k - 1] : u(rng);
  const double dt = 1e-3;
  for (double fdt : {0.01, 0.2, 0.45}) {
    for (double zeta : {0.003, 0.3, 1.0, 2.5}) {
      const double f_n = fdt / dt;
      const auto y = Apply(v, dt, 1.0, f_n, zeta), ref = Rk4Mode(v, dt, 1.0, f_n, zeta, 2000);
      EXPECT_LE(MaxAbsDiff(y, ref), 1e-9) << "f_n dt " << fdt << " zeta " << zeta;
    }
  }
}

TEST(Resonance, IsLinearWithUnitGainAtDcAndZeroShareIsTheIdentity) {
  std::vector<double> y1(2000, -1.0), y2(2000, 4.0);
  for (size_t k = 100; k < y1.size(); ++k) {
    y1[k] = 2.0;  // a step: settles at it (unit gain at DC)
    y2[k] = 4.0 + std::sin(0.05 * static_cast<double>(k));
  }
  const double dt = 1e-3;
  const auto z1 = Apply(y1, dt, 1.0, 40, 0.05);
  EXPECT_GT(*std::max_element(z1.begin(), z1.end()), 2.5);  // it rings
  EXPECT_NEAR(z1.back(), 2.0, 1e-9);
  std::vector<double> mix(y1.size());
  for (size_t k = 0; k < mix.size(); ++k) mix[k] = 0.3 * y1[k] - 1.7 * y2[k];
  const auto z2 = Apply(y2, dt, 1.0, 40, 0.05), zm = Apply(mix, dt, 1.0, 40, 0.05);
  for (size_t k = 0; k < mix.size(); ++k) ASSERT_NEAR(zm[k], 0.3 * z1[k] - 1.7 * z2[k], 1e-11);
  EXPECT_EQ(Apply(y2, dt, 0.0, 40, 0.05), y2);
  EXPECT_TRUE(Mode().linear_output());
}

TEST(Resonance, DominantBandFindsAModeAndNotWhiteNoise) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0, 1);
  const double fs = 10000;
  std::vector<double> white(20000), ringing(20000);
  for (double& x : white) x = n(rng);
  const auto mode = Apply(white, 1 / fs, 1.0, 740, 0.03);
  for (size_t k = 0; k < white.size(); ++k) ringing[k] = mode[k] - white[k] + 0.1 * n(rng);
  const model::SpectralBand none = model::DominantBand(model::WelchSpectrum(white, fs), 50);
  EXPECT_FALSE(none.dominant()) << none.f_peak << " " << none.share << " " << none.contrast;
  const model::SpectralBand b = model::DominantBand(model::WelchSpectrum(ringing, fs), 50);
  ASSERT_TRUE(b.dominant()) << b.share << " " << b.contrast;
  EXPECT_NEAR(b.f_peak, 740, 15);
  EXPECT_GT(b.zeta, 0.03 / 3);  // a start for the polish, from a scattered estimate: within 3 ×
  EXPECT_LT(b.zeta, 0.03 * 3);
}

/// A stack-like record at 5 kHz: a rest at the bottom after a step (it rings), then a 5 Hz sine of
/// 80 V with band-limited noise (40–900 Hz, 12 V RMS) riding on it; the truth a backlash-like stack
/// with a mode at f_n, ζ, share a; sensor noise 0.005.
io::Record ModeRecord(double f_n, double zeta, double a, uint64_t seed) {
  const double fs = 5000;
  const size_t n = 12500;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ph(0, 2 * std::numbers::pi);
  std::vector<double> freqs, phases;
  for (double f = 40; f <= 900; f += 7.3) {
    freqs.push_back(f);
    phases.push_back(ph(rng));
  }
  io::Record r;
  r.name = "noise";
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs, ts = t - 0.2;
    double u = -80;
    if (ts > 0) {
      double noise = 0;
      for (size_t i = 0; i < freqs.size(); ++i)
        noise += std::sin(2 * std::numbers::pi * freqs[i] * ts + phases[i]);
      u = -80 * std::cos(2 * std::numbers::pi * 5 * ts) +
          std::min(1.0, ts / 0.05) * 12 * std::sqrt(2.0 / static_cast<double>(freqs.size())) *
              noise;
    }
    r.t.push_back(t);
    r.u.push_back(u);
  }
  r.dt = 1 / fs;
  r.first_scored = 0;
  r.end_scored = n;
  r.rest_samples = 1000;
  r.offset_mode = io::OffsetMode::kFit;
  for (double u : r.u) r.y.push_back(0.1 * u);  // the scale's proxy until simulated
  const DataScale scale = MeasureScale({&r});
  const RecordModel truth(MakeFamily("backlash-like", scale), {EffectKind::Named("resonance")},
                          scale);
  std::vector<double> p = truth.family().CheckNominal();
  p.insert(p.end(), {a, f_n, zeta});
  std::vector<double> y(n);
  truth.Simulate(r, p, {}, n, y);
  std::normal_distribution<double> noise(0, 0.005);
  r.y.resize(n);
  for (size_t k = 0; k < n; ++k) r.y[k] = y[k] + noise(rng);
  return r;
}

TEST(Resonance, FitPlacesTheModeFromTheResidualsBand) {
  const io::Record r = ModeRecord(330, 0.025, 0.9, 11);
  io::RecordSet set;
  set.source = "mode";
  io::Record tr = r, wh = r;
  tr.name = "train";
  io::SetWindow(tr, 0.0, 1.7, 20, "train");
  wh.name = "withheld";
  wh.role = model::CaseRole::kValidate;
  io::SetWindow(wh, 1.7, 2.49, 20, "withheld");
  set.records = {tr, wh};
  FitOptions o;
  o.family = "backlash-like";
  o.effects = {EffectKind::Named("resonance")};
  o.uncertainty = false;
  o.search.repetitions = 1;
  o.search.pso.particles = 16;
  o.search.pso.iterations = 30;
  o.lm.max_iterations = 40;
  const FitResult f = FitRecords(set, o);
  const auto [first, count] = f.model->EffectParams(EffectKind::Named("resonance"));
  ASSERT_EQ(count, 3u);
  EXPECT_NE(f.mode_start.find("from the residual of 'train'"), std::string::npos) << f.mode_start;
  // The mode is identified to the noise: f_n to 0.5 %, ζ and the share to 10 %.
  EXPECT_NEAR(f.params[first + 1], 330, 330 * 0.005) << f.mode_start;
  EXPECT_NEAR(f.params[first + 2], 0.025, 0.0025);
  EXPECT_NEAR(f.params[first], 0.9, 0.09);
  EXPECT_LT(f.metrics[1].rmse, 0.01) << "withheld";
}

/// The inverse stays bounded (records/stepper.h; model/kernels/effects.h the virtual plant): a step
/// of the reference gives a drive that settles, whatever the mode, and the model then follows the
/// reference through its reference low-pass (overshoot ≈ 4.3 % for ζ_r = 1/√2; at most 10 % here,
/// 5.5 % measured on this grid).
TEST(Resonance, CompensatorIsBoundedAndDoesNotRing) {
  io::Record r;
  const double fs = 2000;
  for (size_t k = 0; k < 400; ++k) {
    r.t.push_back(static_cast<double>(k) / fs);
    r.u.push_back(100 * std::sin(static_cast<double>(k) / 30));
    r.y.push_back(0.01 * r.u.back());
  }
  r.dt = 1 / fs;
  r.end_scored = r.size();
  r.rest_samples = 1;
  for (double fdt : {0.012, 0.05, 0.15, 0.3, 0.45}) {
    for (double zeta : {0.003, 0.05, 0.7}) {
      for (double share : {0.2, 0.7, 1.0}) {
        ModelSpec s;
        s.family = "prandtl-ishlinskii";
        s.pi_operators = 4;
        s.scale = MeasureScale({&r});
        s.dt = r.dt;
        s.effects = {EffectKind::Named("resonance")};
        s.params = {share, fdt * fs, zeta};
        s.weights = {0.05, 0.03, 0.02, 0.01, 0.01};
        s.drive_min = -100;
        s.drive_max = 100;
        Stepper fwd(s), inv(s);
        const double y0 = inv.Init(0), u0 = 0;
        fwd.Init(u0);
        const double y1 = y0 + 0.5;  // a step of the reference, then a hold
        double u_max = 0, y_over = -1e300, u_last = 0, y_last = 0;
        const size_t n = 3000;
        for (size_t k = 1; k < n; ++k) {
          const double u = inv.InverseStep(k < 10 ? y0 : y1);
          const double y = fwd.Step(u);
          u_max = std::max(u_max, std::abs(u));
          if (k > 10) y_over = std::max(y_over, y);
          u_last = u;
          y_last = y;
        }
        const std::string what = "f_n dt " + std::to_string(fdt) + " zeta " + std::to_string(zeta) +
                                 " share " + std::to_string(share);
        EXPECT_EQ(inv.ctl().saturated, 0) << what;
        EXPECT_TRUE(std::isfinite(u_last)) << what;
        // Well inside the limits (±100 V, never reached: nothing clipped): the mode's input peaks
        // at most 1/q_c ≤ 4 × its step, 31 V of drive at most here.
        EXPECT_LT(u_max, 40) << what;
        EXPECT_NEAR(y_last, y1, 1e-6) << what;      // settled: unit gain at DC
        EXPECT_LT(y_over - y1, 0.1 * 0.5) << what;  // no ringing of the mode
      }
    }
  }
}

}  // namespace
}  // namespace pz::records
