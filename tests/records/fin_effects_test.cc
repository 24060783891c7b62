// The fin bench's effects (records/fin_effects.h): every effect at zero magnitude is the identity,
// each changes the output the way its physics says, and the fast path (shaped drive as a sampled
// signal) agrees with the CVODE path (effects as BimorphExtensions) where both apply.
#include "records/fin_effects.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <thread>
#include <vector>

#include "model/residual_analysis.h"

namespace pz::records {
namespace {

using model::BimorphParams;
using model::BimorphPlant;
using model::ComputeLoop;
using model::EffectKind;
using model::FindEffect;
using model::LoopFeatures;
using model::SimStatus;
using model::SimulationSummary;
using model::Sinusoid;

// Sampled fast path vs the exact sinusoid path: the drive is linear between samples of a 400 Hz
// grid, error ≈ h²ü/8 of the drive; measured ≤ 1e-4 deg.
constexpr double kSampledPathTolDeg = 2e-4;
// Fast path vs CVODE (rtol 1e-7): measured ≤ 1e-4 deg on 750 V, 1 Hz.
constexpr double kCvodeTolDeg = 5e-4;

class EffectsTest : public ::testing::Test {
 protected:
  BimorphPlant plant_;
  EffectSimulator sim_{plant_};

  static BimorphParams Params(bool hysteresis = true) {
    BimorphParams p;  // the spec's nominal bench values
    p.b1 = 10.0;      // no saturation: θ visible
    p.b2 = -10.0;
    if (!hysteresis) p.alpha = 0.0;
    return p;
  }
  std::vector<double> Run(const BimorphParams& p, std::vector<Effect> e, const Sinusoid& d,
                          bool cvode = false, std::vector<double>* theta = nullptr) const {
    std::vector<double> y(d.NumSamples()), th(d.NumSamples());
    EffectSimOptions o;
    o.force_cvode = cvode;
    const SimulationSummary s = sim_.SimulateAngle(p, e, d, y, o, th);
    EXPECT_TRUE(s.ok()) << s.message;
    if (theta) *theta = th;
    return y;
  }
  static double MaxDiff(const std::vector<double>& a, const std::vector<double>& b) {
    double m = 0;
    for (size_t k = 0; k < a.size(); ++k) m = std::max(m, std::abs(a[k] - b[k]));
    return m;
  }
};

TEST_F(EffectsTest, LibraryNamesRoundTripAndEveryEffectHasUnitsAndRanges) {
  // The fin's order (the order of its boxes, records/fin_effects.cc kFinBoxes): its check draws
  // truths and lists rows in it.
  std::vector<std::string> names;
  for (const FinEffectInfo& e : FinEffects()) names.push_back(e.name);
  EXPECT_EQ(names, (std::vector<std::string>{"driver-lowpass", "creep", "hinge-friction", "delay",
                                             "cubic-stiffening", "quadratic-drive", "drift"}));
  for (const FinEffectInfo& e : FinEffects()) {
    ASSERT_TRUE(ParseEffectKind(e.name).has_value()) << e.name;
    EXPECT_EQ(*ParseEffectKind(e.name), e.kind);
    EXPECT_FALSE(e.params.empty());
    for (const EffectParamInfo& p : e.params) {
      EXPECT_FALSE(p.unit.empty()) << e.name << "." << p.name;
      EXPECT_LT(p.lower, p.upper) << e.name << "." << p.name;
      EXPECT_GT(p.scale, 0);
      if (p.log_scale) {
        EXPECT_GT(p.lower, 0);
      }
    }
    EXPECT_TRUE(Effect::Zero(e.kind).IsIdentity()) << e.name;
    EXPECT_TRUE(Effect::Zero(e.kind).Validate().ok()) << e.name;
  }
  EXPECT_EQ(*ParseEffectKind("none"), EffectKind());
  EXPECT_FALSE(ParseEffectKind("friction").has_value());
}

TEST_F(EffectsTest, FinOffersItsEffectsOfTheOneLibraryAndSaysWhyNotTheOthers) {
  for (const FinEffectInfo& e : FinEffects()) {
    ASSERT_NE(e.def, nullptr) << e.name;
    EXPECT_EQ(FindEffect(e.name), e.def);
    EXPECT_EQ(e.stage, e.def->stage());
  }
  EXPECT_EQ(*ParseEffectKind("drift"), EffectKind::Named("drift"));
  EXPECT_EQ(*ParseEffectKind("output-drift"), EffectKind::Named("drift"));  // its former name
  EXPECT_NE(FinEffectError("friction")
                .find("not an effect of the fin bench: 'friction' is the library's output-stage"),
            std::string::npos)
      << FinEffectError("friction");
  EXPECT_NE(FinEffectError("hum").find("not an effect of the library: 'hum' is unknown"),
            std::string::npos);
}

TEST_F(EffectsTest, ResultDoesNotDependOnWhatTheThreadRanBefore) {
  // The modal workspace is per thread: a run on a grid whose step differs from the previous run's
  // by less than the workspace's reuse tolerance (1e-10) is still discretised over its own step.
  // Without hysteresis every interval is one sub-step, so run a leaves its own step in the cache.
  Sinusoid a{500, 1.0, 2.0, 100.0};
  Sinusoid b = a;
  b.sample_rate_hz = 100.0 * (1 + 3e-11);
  const std::vector<Effect> e = {{EffectKind::Named("quadratic-drive"), {2e-4}}};
  std::vector<double> fresh, after;
  std::thread([&] { fresh = Run(Params(false), e, b); }).join();
  std::thread([&] {
    Run(Params(false), e, a);
    after = Run(Params(false), e, b);
  }).join();
  ASSERT_EQ(fresh.size(), after.size());
  for (size_t k = 0; k < fresh.size(); ++k) ASSERT_EQ(fresh[k], after[k]) << "sample " << k;
}

TEST_F(EffectsTest, ValidateNamesTheParameterAndTheRange) {
  Effect e{EffectKind::Named("driver-lowpass"), {0.5}};
  const Status s = e.Validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("driver-lowpass.tau_s"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("[0, 0.2]"), std::string::npos) << s.message();
  Effect wrong{EffectKind::Named("creep"), {0.1}};
  EXPECT_NE(wrong.Validate().message().find("creep.params.size()"), std::string::npos);
  std::vector<double> y(300);
  const std::vector<Effect> bad = {e};
  const SimulationSummary r = sim_.SimulateAngle(Params(), bad, Sinusoid{375, 1.0}, y);
  EXPECT_EQ(r.status, SimStatus::kInvalidInput);
}

TEST_F(EffectsTest, ZeroMagnitudeIsTheIdentityForEveryEffect) {
  const Sinusoid d{500, 0.5};
  const std::vector<double> base = Run(Params(), {}, d);
  for (const FinEffectInfo& e : FinEffects()) {
    const std::vector<double> y = Run(Params(), {Effect::Zero(e.kind)}, d);
    EXPECT_EQ(MaxDiff(base, y), 0.0) << e.name;
  }
}

TEST_F(EffectsTest, SampledFastPathMatchesTheSinusoidPath) {
  // A vanishing low-pass sends the drive through the sampled path: same output within its accuracy.
  const Sinusoid d{750, 1.0};
  const std::vector<double> base = Run(Params(), {}, d);
  const std::vector<double> y = Run(Params(), {{EffectKind::Named("driver-lowpass"), {1e-9}}}, d);
  EXPECT_LT(MaxDiff(base, y), kSampledPathTolDeg);
}

TEST_F(EffectsTest, DelayShiftsTheOutputBySamples) {
  const Sinusoid d{500, 1.0};
  const std::vector<double> base = Run(Params(), {}, d);
  const std::vector<double> y =
      Run(Params(), {{EffectKind::Named("delay"), {0.03}}}, d);  // 3 samples
  for (size_t k = 0; k < 3; ++k) EXPECT_EQ(y[k], 0.0);
  for (size_t k = 3; k < y.size(); ++k) ASSERT_NEAR(y[k], base[k - 3], kSampledPathTolDeg) << k;
}

TEST_F(EffectsTest, LowpassAddsPhaseLagAndAttenuatesAsAFirstOrderLag) {
  // Linear plant (α = 0): the low-pass multiplies the response by 1/(1 + iωτ).
  const Sinusoid d{500, 1.0};
  const double tau = 0.05, w = 2 * std::numbers::pi * d.frequency_hz;
  std::vector<double> th0, th1;
  Run(Params(false), {}, d, false, &th0);
  Run(Params(false), {{EffectKind::Named("driver-lowpass"), {tau}}}, d, false, &th1);
  const LoopFeatures l0 = ComputeLoop(th0, d.amplitude_v, d.frequency_hz, 100, 3, 0);
  const LoopFeatures l1 = ComputeLoop(th1, d.amplitude_v, d.frequency_hz, 100, 3, 0);
  EXPECT_NEAR(l1.phase_lag_deg - l0.phase_lag_deg, std::atan(w * tau) * 180 / std::numbers::pi,
              0.5);
  EXPECT_NEAR(l1.fundamental_deg / l0.fundamental_deg, 1 / std::hypot(1.0, w * tau), 0.01);
}

TEST_F(EffectsTest, CreepLeavesARelaxingOffsetAndAWiderLoop) {
  // On a sinusoid from rest the creep state k·LP_τ(u) carries a decaying offset k V ωτ/(1+ω²τ²)
  // e^{−t/τ}: the cycle means of the difference are positive and fall; its lag widens the loop.
  const Sinusoid d{500, 0.25};
  std::vector<double> th0, th1;
  Run(Params(false), {}, d, false, &th0);
  Run(Params(false), {{EffectKind::Named("creep"), {0.2, 3.0}}}, d, false, &th1);
  const size_t p = th0.size() / 3;
  double prev = INFINITY;
  for (int c = 0; c < 3; ++c) {
    double mean = 0;
    for (size_t k = c * p; k < (c + 1) * p; ++k) mean += (th1[k] - th0[k]) / p;
    EXPECT_GT(mean, 0.0) << "cycle " << c;
    EXPECT_LT(mean, prev) << "cycle " << c;
    prev = mean;
  }
  const LoopFeatures l0 = ComputeLoop(th0, d.amplitude_v, d.frequency_hz, 100, 3, 0);
  const LoopFeatures l1 = ComputeLoop(th1, d.amplitude_v, d.frequency_hz, 100, 3, 0);
  EXPECT_GT(l1.area_deg_v, l0.area_deg_v * 1.05);
}

TEST_F(EffectsTest, QuadraticDriveBreaksTheSymmetryOfTheLoop) {
  const Sinusoid d{750, 0.5};
  std::vector<double> th0, th1;
  Run(Params(false), {}, d, false, &th0);
  Run(Params(false), {{EffectKind::Named("quadratic-drive"), {2e-4}}}, d, false, &th1);
  const LoopFeatures l0 = ComputeLoop(th0, d.amplitude_v, d.frequency_hz, 100, 3, 0);
  const LoopFeatures l1 = ComputeLoop(th1, d.amplitude_v, d.frequency_hz, 100, 3, 0);
  EXPECT_NEAR(l0.offset_deg, 0.0, 1e-3);
  // u + c u² has mean c V²/2 = 56 V on 750 V: the offset is about 7.5 % of the amplitude.
  EXPECT_GT(l1.offset_deg, 0.05 * l0.peak_to_peak_deg / 2);
}

TEST_F(EffectsTest, OutputDriftAddsARamp) {
  const Sinusoid d{375, 0.5};
  const std::vector<double> base = Run(Params(), {}, d);
  const std::vector<double> y = Run(Params(), {{EffectKind::Named("drift"), {0.01}}}, d);
  for (size_t k = 0; k < y.size(); ++k) ASSERT_NEAR(y[k] - base[k], 0.01 * k / 100.0, 1e-12);
}

TEST_F(EffectsTest, CubicStiffeningShrinksLargeSwingsMoreThanSmallOnes) {
  auto shrink = [&](double v) {
    const Sinusoid d{v, 1.0};
    std::vector<double> th0, th1;
    Run(Params(false), {}, d, false, &th0);
    Run(Params(false), {{EffectKind::Named("cubic-stiffening"), {5e6}}}, d, false, &th1);
    double m0 = 0, m1 = 0;
    for (size_t k = 0; k < th0.size(); ++k) {
      m0 = std::max(m0, std::abs(th0[k]));
      m1 = std::max(m1, std::abs(th1[k]));
    }
    return 1.0 - m1 / m0;
  };
  const double small = shrink(375), large = shrink(750);
  EXPECT_GT(small, 0.0);
  EXPECT_GT(large, 2.0 * small);  // ∝ w²: about 4 × between 375 V and 750 V
}

TEST_F(EffectsTest, HingeFrictionOpensALoopAndResistsTheMotion) {
  // A nearly lag-free linear beam (small damping, α = 0) has a thin loop; Dahl friction opens one.
  BimorphParams p = Params(false);
  p.mu = 10;
  p.delta = 1e-3;
  const Sinusoid d{500, 0.5};
  std::vector<double> th0, th1;
  Run(p, {}, d, false, &th0);
  Run(p, {{EffectKind::Named("hinge-friction"), {0.2, 2000}}}, d, false, &th1);
  const LoopFeatures l0 = ComputeLoop(th0, d.amplitude_v, d.frequency_hz, 100, 3, 0);
  const LoopFeatures l1 = ComputeLoop(th1, d.amplitude_v, d.frequency_hz, 100, 3, 0);
  EXPECT_LT(std::abs(l0.width_deg), 0.03);
  EXPECT_GT(l1.width_deg, l0.width_deg + 0.05);  // the friction loop
  EXPECT_GT(l1.area_deg_v, l0.area_deg_v + 10.0);
  EXPECT_LT(l1.peak_to_peak_deg, l0.peak_to_peak_deg);  // a smaller swing
}

TEST_F(EffectsTest, CvodePathMatchesTheFastPathForDriveAndOutputEffects) {
  const Sinusoid d{750, 1.0};
  const std::vector<std::vector<Effect>> cases = {
      {{EffectKind::Named("driver-lowpass"), {0.02}}},
      {{EffectKind::Named("creep"), {0.1, 2.0}}},
      {{EffectKind::Named("quadratic-drive"), {1e-4}}},
      {{EffectKind::Named("delay"), {0.013}}},
      {{EffectKind::Named("drift"), {0.01}}},
      {{EffectKind::Named("driver-lowpass"), {0.02}},
       {EffectKind::Named("quadratic-drive"), {1e-4}},
       {EffectKind::Named("creep"), {0.1, 2.0}}},
  };
  for (const auto& e : cases) {
    const std::vector<double> fast = Run(Params(), e, d);
    const std::vector<double> cvode = Run(Params(), e, d, true);
    EXPECT_LT(MaxDiff(fast, cvode), kCvodeTolDeg) << e.front().Describe();
  }
}

TEST_F(EffectsTest, ShapedDriveOfALowpassIsTheAnalyticResponse) {
  // x(t) = V/(1+ω²τ²) (sin ωt − ωτ cos ωt + ωτ e^{−t/τ}) from rest.
  const Sinusoid d{100, 1.0};
  const double tau = 0.05, w = 2 * std::numbers::pi;
  std::vector<double> t;
  for (int k = 0; k < 300; ++k) t.push_back(k / 400.0);
  const std::vector<Effect> lp = {{EffectKind::Named("driver-lowpass"), {tau}}};
  const std::vector<double> u = ShapedDrive(lp, d, t);
  for (size_t k = 0; k < t.size(); ++k) {
    const double x =
        100 / (1 + w * w * tau * tau) *
        (std::sin(w * t[k]) - w * tau * std::cos(w * t[k]) + w * tau * std::exp(-t[k] / tau));
    ASSERT_NEAR(u[k], x, 1e-3) << k;  // 1e-5 of V
  }
}

}  // namespace
}  // namespace pz::records
