// The one effect library (model/effect_library.h): the registry, zero magnitude as the identity of
// every drive and output effect, the exact first-order hold of the low-pass, the delay's shift, and
// which stage has which form.
#include "model/effect_library.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "model/bimorph_ode.h"

namespace pz::model {
namespace {

DataScale Scale() {
  DataScale s;
  s.u_min = -100;
  s.u_max = 100;
  s.u_half = 100;
  s.y_half = 5;
  s.f_dom = 2;
  s.fs = 1000;
  s.duration = 4;
  return s;
}

std::vector<double> Ramp(size_t n) {
  std::vector<double> u(n);
  for (size_t k = 0; k < n; ++k) u[k] = 3.0 * std::sin(0.01 * static_cast<double>(k)) + 0.5;
  return u;
}

// The parameters of an effect with its magnitude zero and the others mid-range (the creep
// spectrum's weights are each the magnitude of their relaxation: all zero).
std::vector<double> ZeroMagnitude(const EffectDef& e) {
  std::vector<double> p;
  for (const ParamInfo& q : e.Params(Scale()))
    p.push_back(q.log_scale ? std::sqrt(q.lower * q.upper) : 0.5 * (q.lower + q.upper));
  p[0] = 0;
  if (std::string(e.name()) == "creep-spectrum") std::fill(p.begin(), p.end(), 0.0);
  return p;
}

TEST(EffectLibraryTest, RegistryNamesAreUniqueAndFound) {
  std::set<std::string> names;
  for (const EffectDef* e : Effects()) {
    EXPECT_TRUE(names.insert(e->name()).second) << e->name();
    EXPECT_EQ(FindEffect(e->name()), e);
    EXPECT_EQ(Effects()[EffectIndex(*e)], e);
    EXPECT_FALSE(std::string(e->title()).empty());
    EXPECT_FALSE(std::string(e->equation()).empty());
    const auto params = e->Params(Scale());
    ASSERT_FALSE(params.empty()) << e->name();
    for (const ParamInfo& p : params) {
      EXPECT_LT(p.lower, p.upper) << e->name() << "." << p.name;
      if (p.log_scale) {
        EXPECT_GT(p.lower, 0) << e->name() << "." << p.name;
      }
    }
  }
  EXPECT_EQ(FindEffect("hum"), nullptr);
  // Chain order: drive before beam before output.
  for (size_t i = 1; i < Effects().size(); ++i)
    EXPECT_LE(static_cast<int>(Effects()[i - 1]->stage()), static_cast<int>(Effects()[i]->stage()));
}

TEST(EffectLibraryTest, ZeroMagnitudeIsTheIdentityOfEveryDriveAndOutputEffect) {
  const std::vector<double> base = Ramp(500);
  const OutputFrame frame{1e-3, 100, Scale().y_half, Scale().duration};
  for (const EffectDef* e : Effects()) {
    std::vector<double> v = base;
    const std::vector<double> p = ZeroMagnitude(*e);
    if (e->stage() == EffectStage::kDrive) e->ApplyDrive(p, 1e-3, v);
    if (e->stage() == EffectStage::kOutput) e->ApplyOutput(p, frame, v);
    EXPECT_EQ(v, base) << e->name();
  }
}

TEST(EffectLibraryTest, EachStageHasItsForm) {
  for (const EffectDef* e : Effects()) {
    const std::vector<double> p = ZeroMagnitude(*e);
    std::vector<double> one = {1.0, 2.0};
    switch (e->stage()) {
      case EffectStage::kBeam:  // only a beam form; the drive and output stages leave data alone
        EXPECT_NE(e->MakeExtension(p), nullptr) << e->name();
        e->ApplyDrive(p, 1.0, one);
        e->ApplyOutput(p, OutputFrame{}, one);
        EXPECT_EQ(one, (std::vector<double>{1.0, 2.0})) << e->name();
        break;
      case EffectStage::kOutput:
        EXPECT_EQ(e->MakeExtension(p), nullptr) << e->name();
        break;
      case EffectStage::kDrive:  // the form the fin bench needs of its drive effects: checked
                                 // with its box (tests/records/stepper_test.cc, EveryEffect)
        break;
    }
  }
}

TEST(EffectLibraryTest, LowpassIsTheExactFirstOrderHoldOfARamp) {
  // τ ẋ = t − x from rest: x(t) = t − τ (1 − e^{−t/τ}); a ramp is linear between samples: exact.
  const double dt = 1e-3, tau = 0.02;
  std::vector<double> u(400);
  for (size_t k = 0; k < u.size(); ++k) u[k] = static_cast<double>(k) * dt;
  FindEffect("driver-lowpass")->ApplyDrive(std::vector<double>{tau}, dt, u);
  for (size_t k = 0; k < u.size(); ++k) {
    const double t = static_cast<double>(k) * dt;
    EXPECT_NEAR(u[k], t - tau * (1 - std::exp(-t / tau)), 1e-14) << k;
  }
}

TEST(EffectLibraryTest, CreepIsTheDrivePlusTheLowpassOfItsChangeBitForBit) {
  // u_e = u + lowpass_τ(k (u − u0)): the one-pass recursion against the low-pass effect on its own
  // buffer, including τ below the low-pass's floor (the low-pass then leaves its input as it is).
  const double dt = 1e-3;
  for (const double tau : {0.02, 0.7, 0.0}) {
    const std::vector<double> base = Ramp(300);
    const double k = -0.09;
    std::vector<double> x(base.size());
    for (size_t i = 0; i < base.size(); ++i) x[i] = k * (base[i] - base[0]);
    FindEffect("driver-lowpass")->ApplyDrive(std::vector<double>{tau}, dt, x);
    std::vector<double> u = base;
    FindEffect("creep")->ApplyDrive(std::vector<double>{k, tau}, dt, u);
    for (size_t i = 0; i < u.size(); ++i)
      EXPECT_EQ(u[i], base[i] + x[i]) << "tau " << tau << ", sample " << i;
  }
}

TEST(EffectLibraryTest, DelayOfWholeSamplesShiftsAndHoldsTheRest) {
  const std::vector<double> base = Ramp(50);
  std::vector<double> v = base;
  FindEffect("delay")->ApplyDrive(std::vector<double>{3e-3}, 1e-3, v);
  for (size_t k = 0; k < v.size(); ++k) EXPECT_NEAR(v[k], base[k < 3 ? 0 : k - 3], 1e-12) << k;
}

TEST(EffectLibraryTest, DriftCountsTimeFromTheWindowStart) {
  std::vector<double> y(10, 1.0);
  FindEffect("drift")->ApplyOutput(std::vector<double>{2.0}, OutputFrame{0.5, 4, 1}, y);
  for (size_t k = 0; k < y.size(); ++k)
    EXPECT_DOUBLE_EQ(y[k], 1.0 + 2.0 * (static_cast<double>(k) - 4) * 0.5);
}

}  // namespace
}  // namespace pz::model
