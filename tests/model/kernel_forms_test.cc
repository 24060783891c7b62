// The library's C++ forms that run their step kernel (model/kernels/, issue 38 part 3), each
// against a frozen reference: a digest of the bits of its output on random drives and parameters,
// recorded from the arithmetic they replaced (the C++ loops of model/ before the move). A change of
// one bit of one sample changes the digest.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "model/bw_oscillator.h"
#include "model/effect_library.h"
#include "model/kernels/kernel_text.h"
#include "model/kernels/pzk.h"
#include "model/preisach.h"
#include "model/prandtl_ishlinskii.h"
#include "model/stack_models.h"
#include "tests/testing/pinned.h"

namespace pz::model {
namespace {

// FNV-1a over the bits of doubles, and their sum and absolute sum (what a frozen digest is held
// to on another arithmetic).
struct Digest {
  uint64_t h = 1469598103934665603ULL;
  double sum = 0, abs_sum = 0;
  void Add(double x) {
    uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    for (int i = 0; i < 8; ++i) {
      h ^= (b >> (8 * i)) & 0xff;
      h *= 1099511628211ULL;
    }
    // A diverging run's outputs (non-finite or beyond 1e6, chaotic in their last digits): in the
    // digest, not in the sums.
    if (!(std::abs(x) <= 1e6)) return;
    sum += x;
    abs_sum += std::abs(x);
  }
  void Add(std::span<const double> v) {
    for (double x : v) Add(x);
  }
};

// A frozen digest is the kernels' outputs bit for bit on the pins' arithmetic
// (tests/testing/pinned.h). Elsewhere the drives (std::sin) and the kernels' exp / pow / log follow
// the C library's variant, so the outputs move by a few ulps, amplified at most by a branch's
// switching (a hysteresis reversal at a tie, never met at 1e-13): the outputs' sum and absolute
// sum are held to 1e-9 of the absolute sum.
void ExpectFrozen(const Digest& dig, uint64_t frozen, double sum, double abs_sum) {
  const pz::testing::Pins pins(pz::testing::kPinnedArithmetic);
  if (pins.exact()) EXPECT_EQ(dig.h, frozen);
  EXPECT_TRUE(pins.Near(dig.sum, sum, 1e-9 * abs_sum)) << std::hexfloat << dig.sum;
  EXPECT_TRUE(pins.Near(dig.abs_sum, abs_sum, 1e-9 * abs_sum)) << std::hexfloat << dig.abs_sum;
}

// Uniform doubles from the raw 64-bit stream (the same on every standard library).
struct Draw {
  std::mt19937_64 g;
  explicit Draw(uint64_t seed) : g(seed) {}
  double U() { return static_cast<double>(g() >> 11) * 0x1.0p-53; }
  double U(double lo, double hi) { return lo + (hi - lo) * U(); }
  int I(int lo, int hi) { return lo + static_cast<int>(g() % static_cast<uint64_t>(hi - lo + 1)); }
  InitialState State() {
    const int s = I(0, 2);
    return s == 0   ? InitialState::kCentred
           : s == 1 ? InitialState::kDescended
                    : InitialState::kAscended;
  }
  // A drive of n samples in about [-1, 1]: sines, a random walk, holds (du = 0) and jumps.
  std::vector<double> Drive(size_t n) {
    std::vector<double> u(n);
    const double f1 = U(0.002, 0.05), f2 = U(0.01, 0.2), a2 = U(0, 0.4), ph = U(0, 6.28);
    double walk = 0;
    for (size_t k = 0; k < n; ++k) {
      walk += U(-0.02, 0.02);
      double v = 0.6 * std::sin(f1 * static_cast<double>(k) + ph) +
                 a2 * std::sin(f2 * static_cast<double>(k)) + walk;
      if (k > 0 && U() < 0.08) v = u[k - 1];  // a hold
      if (U() < 0.01) v += U(-0.5, 0.5);      // a jump
      u[k] = v;
    }
    return u;
  }
  std::vector<double> Increasing(int n, double lo, double hi) {
    std::vector<double> r(static_cast<size_t>(n));
    double x = lo;
    for (auto& e : r) e = x += U(0.05, 1.0) * (hi - lo) / n;
    return r;
  }
  std::vector<double> Values(int n, double lo, double hi) {
    std::vector<double> w(static_cast<size_t>(n));
    for (auto& e : w) e = U(lo, hi);
    return w;
  }
};

// The frozen digests' outputs' sums (ExpectFrozen), pinned with them.
const double kSum1 = 0x1.89cb7c43ce513p+9, kAbs1 = 0x1.8a75d0e9acf85p+17;
const double kSum2 = 0x1.2cb9d56945a14p+16, kAbs2 = 0x1.998fdc4acfec7p+17;
const double kSum3 = 0x1.1c43c79e356aap+13, kAbs3 = 0x1.8a33ace187acdp+16;
const double kSum4 = 0x1.39fcaac980b3fp+12, kAbs4 = 0x1.887d7af55b9c9p+14;
const double kSum5 = 0x1.605c0d1f4c8d5p+24, kAbs5 = 0x1.8dc5cffdeb2d1p+26;
const double kSum6 = 0x1.bc6b3cd328a95p+11, kAbs6 = 0x1.0440d2d6a8827p+19;
const double kSum7 = -0x1.1f172585f911ap+18, kAbs7 = 0x1.c4de67fa4642cp+18;

constexpr int kDrives = 300;
constexpr size_t kSamples = 400;

TEST(KernelForms, ApplyPiMatchesFrozenDigest) {
  Draw d(38001);
  Digest dig;
  for (int t = 0; t < kDrives; ++t) {
    const auto u = d.Drive(kSamples);
    PiOperator op;
    const int n = d.I(1, 24);
    op.w0 = d.U(-0.5, 2);
    op.thresholds = d.Increasing(n, 0.0, 1.2);
    op.weights = d.Values(n, -0.3, 1.0);
    op.start = d.State();
    std::vector<double> y(u.size());
    ApplyPi(op, u, y);
    dig.Add(y);
  }
  ExpectFrozen(dig, 15403657618052286110ULL, kSum1, kAbs1);
}

TEST(KernelForms, ApplyAsymmetricPiMatchesFrozenDigest) {
  Draw d(38002);
  Digest dig;
  for (int t = 0; t < kDrives; ++t) {
    const auto u = d.Drive(kSamples);
    AsymmetricPi op;
    const int n = d.I(0, 16), K = d.I(0, 8);
    op.w0 = d.U(-0.5, 2);
    op.thresholds = d.Increasing(n, 0.0, 1.2);
    op.weights = d.Values(n, -0.3, 1.0);
    op.knots = d.Increasing(K, -1.2, 1.2);
    op.up = d.Values(K, -0.2, 0.8);
    op.down = d.Values(K, -0.2, 0.8);
    op.start = d.State();
    std::vector<double> y(u.size());
    ApplyAsymmetricPi(op, u, y);
    dig.Add(y);
  }
  ExpectFrozen(dig, 4061216772735131495ULL, kSum2, kAbs2);
}

TEST(KernelForms, ApplyPreisachMatchesFrozenDigest) {
  Draw d(38003);
  Digest dig;
  for (int t = 0; t < kDrives; ++t) {
    const auto u = d.Drive(kSamples);
    PreisachGrid g;
    g.u_min = d.U(-1.5, -0.3);
    g.u_max = d.U(0.3, 1.5);
    g.levels = d.I(1, 16);
    const auto w = d.Values(static_cast<int>(g.cells()), -0.2, 1.0);
    std::vector<double> y(u.size());
    ApplyPreisach(g, w, u, y, d.State());
    dig.Add(y);
  }
  ExpectFrozen(dig, 14862316398584256949ULL, kSum3, kAbs3);
}

// The inverses solve the forward step (the kernel's) by bisection: their drives pin its bits too.
TEST(KernelForms, InversesMatchFrozenDigest) {
  Draw d(38007);
  Digest dig;
  for (int t = 0; t < 60; ++t) {
    const auto ref = d.Drive(200);
    PreisachGrid g;
    g.u_min = d.U(-1.5, -0.3);
    g.u_max = d.U(0.3, 1.5);
    g.levels = d.I(1, 10);
    const auto w = d.Values(static_cast<int>(g.cells()), 0, 0.3);
    std::vector<double> u(ref.size());
    const InverseReport rep = InvertPreisach(g, w, ref, -2, 2, u, d.State());
    dig.Add(u);
    dig.Add(static_cast<double>(rep.saturated));
    dig.Add(rep.max_shortfall);
    AsymmetricPi op;
    const int n = d.I(0, 10), K = d.I(0, 5);
    op.w0 = d.U(0.1, 2);
    op.thresholds = d.Increasing(n, 0.0, 1.2);
    op.weights = d.Values(n, 0, 1.0);
    op.knots = d.Increasing(K, -1.2, 1.2);
    op.up = d.Values(K, 0, 0.8);
    op.down = d.Values(K, 0, 0.8);
    op.start = d.State();
    InvertAsymmetricPi(op, ref, u);
    dig.Add(u);
  }
  ExpectFrozen(dig, 4286069997716778037ULL, kSum4, kAbs4);
}

TEST(KernelForms, StackBoucWenMatchesFrozenDigest) {
  Draw d(38004);
  Digest dig;
  for (int t = 0; t < kDrives; ++t) {
    const auto u = d.Drive(kSamples);
    StackBoucWenParams p{d.U(0, 2.5), d.U(-1, 3), d.U(-2, 2), d.U(0.2, 3), d.U(1, 400)};
    if (t % 17 == 0) p.alpha = 0;
    StackSimOptions o;
    o.substeps = d.I(1, 8);
    o.rest_state = t % 3 == 0 ? 0.0 : d.U(-0.5, 0.5);
    const double dt = d.U(1e-4, 5e-3);
    std::vector<double> y(u.size()), h(u.size());
    SimulateStackBoucWen(p, u, dt, y, o, h);
    dig.Add(y);
    dig.Add(h);
    const InitialState s = d.State();
    if (s != InitialState::kCentred) dig.Add(StackRestState(p, d.U(0.1, 2), s));
    BacklashLikeParams q{d.U(0, 3), d.U(-1, 2), d.U(-1, 2)};
    dig.Add(StackRestState(q, d.U(0.1, 2), d.State()));
    dig.Add(BoucWenStateStep(d.U(-1, 1), d.U(-1, 1), p.alpha, p.beta, p.gamma));
  }
  ExpectFrozen(dig, 3848101983860400004ULL, kSum5, kAbs5);
}

TEST(KernelForms, EffectsMatchFrozenDigest) {
  Draw d(38005);
  Digest dig;
  for (int t = 0; t < kDrives; ++t) {
    const auto u = d.Drive(kSamples);
    const double dt = d.U(1e-4, 5e-3);
    for (const EffectDef* e : Effects()) {
      // The effects the digest was recorded over (their old loops): a later effect (resonance,
      // issue 45, written as a kernel from the start: tests/records/resonance_test.cc) would
      // change its draws.
      if (std::string(e->name()) == "resonance") continue;
      std::vector<double> p;
      if (std::string(e->name()) == "creep-spectrum") {
        p = d.Values(12, 0, 0.05);
      } else {
        p = {d.U(0, 0.02), d.U(0.001, 0.5)};
        if (std::string(e->name()) == "creep") p = {d.U(-0.3, 0.3), d.U(1e-4, 2)};
        if (std::string(e->name()) == "delay") p = {d.U(0, 60) * dt};
        if (std::string(e->name()) == "rate-dependence") p = {d.U(0, 0.3), d.U(1e-4, 0.05)};
        if (std::string(e->name()) == "quadratic-drive") p = {d.U(-0.3, 0.3)};
        if (std::string(e->name()) == "friction") p = {d.U(-0.05, 0.3)};
        if (std::string(e->name()) == "stiffening") p = {d.U(-0.3, 0.3)};
        if (std::string(e->name()) == "drift") p = {d.U(-0.2, 0.2)};
      }
      std::vector<double> y = u;
      if (e->stage() == EffectStage::kDrive) {
        e->ApplyDrive(p, dt, y);
      } else if (e->stage() == EffectStage::kOutput) {
        OutputFrame f;
        f.dt = dt;
        f.origin = d.I(0, 50);
        f.y_half = d.U(0.3, 2);
        f.duration = 10.0 * d.U(0.5, 3);
        e->ApplyOutput(p, f, y);
      }
      dig.Add(y);
    }
  }
  ExpectFrozen(dig, 7983903807944421268ULL, kSum6, kAbs6);
}

TEST(KernelForms, BwOscillatorMatchesFrozenDigest) {
  Draw d(38006);
  Digest dig;
  const InputInterpolation kinds[] = {InputInterpolation::kLinear,
                                      InputInterpolation::kZeroOrderHold,
                                      InputInterpolation::kCubicSpline};
  for (int t = 0; t < 60; ++t) {
    std::vector<double> u = d.Drive(kSamples);
    for (double& v : u) v *= 60;  // volts
    BwInputOptions io;
    io.sample_rate_hz = d.U(300, 2000);
    io.substeps = d.I(1, 12);
    io.interpolation = kinds[t % 3];
    const BwInput in(u, io);
    const int lanes = d.I(1, 7);
    std::vector<BwParams> ps(static_cast<size_t>(lanes));
    for (auto& p : ps) {
      p.m = d.U(1, 3);
      p.c = d.U(5, 40);
      p.k = d.U(3e4, 8e4);
      p.alpha = d.U(2e4, 8e4);
      p.beta = d.U(500, 2000);
      p.gamma = d.U(-1, 1);
      p.delta = d.U(-1.5, 0.5);
      p.nu = t % 10 == 9 ? d.U(1, 1.5) : 1.0;
    }
    std::vector<std::vector<double>> ys(ps.size(), std::vector<double>(u.size()));
    std::vector<std::span<double>> spans(ys.begin(), ys.end());
    std::vector<const BwInput*> ins(ps.size(), &in);
    std::vector<BwState> st(ps.size());
    const std::vector<Status> ok = SimulateBwMany(ps, ins, spans, st);
    for (size_t l = 0; l < ps.size(); ++l) {
      dig.Add(ys[l]);
      dig.Add(st[l].y);
      dig.Add(st[l].v);
      dig.Add(st[l].z);
      dig.Add(ok[l].ok() ? 1.0 : 0.0);
      std::vector<double> y1(u.size());
      BwState s1;
      const Status one = SimulateBw(ps[l], in, y1, &s1);
      dig.Add(y1);
      dig.Add(s1.z);
      dig.Add(one.ok() ? 1.0 : 0.0);
    }
  }
  ExpectFrozen(dig, 12762309032596268373ULL, kSum7, kAbs7);
}

// The kinds of model/kernels/common.h's enum, read from its text: `NAME` or `NAME = N`, in order.
std::map<int, std::string> EnumKinds() {
  const std::string common = pzk::KernelSource();
  const size_t at = common.find("enum {") + 6;
  std::string body = common.substr(at, common.find("};", at) - at);
  for (size_t c = body.find("/*"); c != std::string::npos; c = body.find("/*"))
    body.erase(c, body.find("*/", c) + 2 - c);
  std::map<int, std::string> kinds;
  std::istringstream items(body);
  int next = 0;
  for (std::string item; std::getline(items, item, ',');) {
    std::istringstream is(item);
    std::string name, eq;
    if (!(is >> name)) continue;
    if (is >> eq && eq == "=") is >> next;
    kinds[next++] = name;
  }
  return kinds;
}

// The table of kind operations (model/kernels/chain.h pzk_kinds): one entry per kind of the enum,
// in increasing order (pzk_kind_of searches it by halves), named as the enum names it, each with a
// step; an unknown kind has none.
TEST(KernelForms, KindTableNamesEveryKindInOrder) {
  const std::map<int, std::string> kinds = EnumKinds();
  ASSERT_GE(kinds.size(), 19u);
  ASSERT_EQ(static_cast<size_t>(pzk::pzk_num_kinds()), kinds.size());
  auto it = kinds.begin();
  for (int i = 0; i < pzk::pzk_num_kinds(); ++i, ++it) {
    const pzk::pzk_kind_ops& k = pzk::pzk_kinds[i];
    EXPECT_EQ(k.kind, it->first) << it->second;
    EXPECT_EQ(std::string(k.name), it->second);
    EXPECT_NE(k.step, nullptr) << k.name;
    if (i > 0) {
      EXPECT_LT(pzk::pzk_kinds[i - 1].kind, k.kind);
    }
    EXPECT_EQ(pzk::pzk_kind_of(k.kind), &k);
    EXPECT_EQ(pzk::KindName(k.kind), it->second);
  }
  // Every id up to the last: its entry through pzk_kind_slots exactly when the enum has it.
  for (int id = -1; id <= kinds.rbegin()->first + 1; ++id) {
    const pzk::pzk_kind_ops* k = pzk::pzk_kind_of(id);
    EXPECT_EQ(k != nullptr, kinds.count(id) == 1) << id;
    if (k) {
      EXPECT_EQ(k->kind, id);
    }
  }
  for (int kind : {0, 6, 9, 18, 29, 35, 39, 41, -1}) {
    EXPECT_EQ(pzk::pzk_kind_of(kind), nullptr) << kind;
    EXPECT_EQ(pzk::KindName(kind), "0");
    pzk::pzk_block b{};
    b.kind = kind;
    int nc = 0, nd = 0;
    EXPECT_EQ(pzk::pzk_block_sizes(&b, &nc, &nd), -1);
  }
}

}  // namespace
}  // namespace pz::model
