// Where the network extrapolates (hgann/extrapolation.h, issue 36): on the paper's split the
// withheld cases 2, 3, 8 and 9 lie outside the training cases' hull and case 4 on its edge; an
// output beyond the training cases' range at such a case is named, one within it is not.
#include "hgann/extrapolation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace pz::hgann {
namespace {

TEST(InsideConvexHull, PaperSplit) {
  // The training cases 1, 5, 6, 7 in normalised (V, f): (375, 0.25), (500, 0.5), (500, 1),
  // (750, 0.25) over V ∈ [375, 750], f ∈ [0.25, 1].
  const std::vector<std::pair<double, double>> train = {
      {0, 0}, {1.0 / 3, 1.0 / 3}, {1.0 / 3, 1}, {1, 0}};
  EXPECT_TRUE(InsideConvexHull(train, 1.0 / 3, 0));        // case 4: on the edge 1–7
  EXPECT_TRUE(InsideConvexHull(train, 0.4, 0.3));          // inside
  EXPECT_TRUE(InsideConvexHull(train, 1.0 / 3, 1.0 / 3));  // case 5 itself
  EXPECT_FALSE(InsideConvexHull(train, 0, 1.0 / 3));       // case 2
  EXPECT_FALSE(InsideConvexHull(train, 0, 1));             // case 3
  EXPECT_FALSE(InsideConvexHull(train, 1, 1.0 / 3));       // case 8
  EXPECT_FALSE(InsideConvexHull(train, 1, 1));             // case 9
  EXPECT_FALSE(InsideConvexHull(train, 0.5, -1e-6));       // just below the edge 1–7
  // Degenerate hulls: a segment, a point, nothing.
  const std::vector<std::pair<double, double>> line = {{0, 0}, {0.5, 0.5}, {1, 1}};
  EXPECT_TRUE(InsideConvexHull(line, 0.25, 0.25));
  EXPECT_FALSE(InsideConvexHull(line, 0.25, 0.3));
  EXPECT_FALSE(InsideConvexHull(line, 1.1, 1.1));
  EXPECT_TRUE(InsideConvexHull({{0.2, 0.3}}, 0.2, 0.3));
  EXPECT_FALSE(InsideConvexHull({{0.2, 0.3}}, 0.2, 0.4));
  EXPECT_FALSE(InsideConvexHull({}, 0, 0));
}

/// The paper's nine operating points and split (no records: the search is not run).
HgannFitnessConfig NineCases() {
  HgannFitnessConfig cfg;
  const double vs[] = {375, 500, 750}, fs[] = {0.25, 0.5, 1.0};
  int n = 0;
  for (double v : vs)
    for (double f : fs) {
      HgannCase c;
      c.number = ++n;
      c.drive = model::Sinusoid{v, f, 3.0, 100.0};
      c.training = n == 1 || n == 5 || n == 6 || n == 7;
      cfg.cases.push_back(std::move(c));
    }
  cfg.normalization = cfg.FromTrainingCases();
  return cfg;
}

TEST(FindExtrapolations, NamesTheOutputsBeyondTheTrainingRange) {
  const HgannFitnessConfig cfg = NineCases();
  // The network: constant but for a2, which rises with V and f to 0.30 deg at case 9 while the
  // training cases span 0.10 … 0.16; at case 8 it is 0.14, within that range.
  std::vector<HgannCaseResult> cases;
  const double a2[] = {0.10, 0.11, 0.12, 0.12, 0.13, 0.16, 0.12, 0.14, 0.30};
  for (int n = 1; n <= 9; ++n) {
    HgannCaseResult r;
    r.number = n;
    r.training = cfg.cases[n - 1].training;
    r.params.mu = 95;
    r.params.delta = 0.1;
    r.params.alpha = 2.5e-3;
    r.params.beta = 6e-3;
    r.params.gamma = 4e-3;
    r.params.a1 = 0.1;
    r.params.a2 = a2[n - 1];
    cases.push_back(r);
  }
  const auto found = FindExtrapolations(cfg, cases, {});
  ASSERT_EQ(found.size(), 4u);  // cases 2, 3, 8, 9; not 4 (on the hull's edge)
  EXPECT_EQ(found[0].number, 2);
  EXPECT_EQ(found[1].number, 3);
  EXPECT_EQ(found[2].number, 8);
  EXPECT_EQ(found[3].number, 9);
  EXPECT_TRUE(found[0].outputs.empty());
  EXPECT_TRUE(found[2].outputs.empty());
  ASSERT_EQ(found[3].outputs.size(), 1u);
  EXPECT_EQ(found[3].outputs[0], 6);  // a2
  EXPECT_DOUBLE_EQ(found[3].value[6], 0.30);
  const double tol = 0.01 * (cfg.ranges[6].upper - cfg.ranges[6].lower);
  EXPECT_NEAR(found[3].lo[6], 0.10 - tol, 1e-12);
  EXPECT_NEAR(found[3].hi[6], 0.16 + tol, 1e-12);

  // A training case whose own fit says a2 = 0.25 ± 0.03 (pinned down) widens the supported range
  // to 0.31 deg: case 9's 0.30 is then supported. One it does not pin down (σ = +inf) does not.
  std::vector<CaseEstimate> estimates(cfg.cases.size());
  estimates[5].ok = true;
  estimates[5].sigma.fill(std::numeric_limits<double>::infinity());
  estimates[5].value[6] = 0.25;
  estimates[5].sigma[6] = 0.03;
  const auto widened = FindExtrapolations(cfg, cases, estimates);
  ASSERT_EQ(widened.size(), 4u);
  EXPECT_TRUE(widened[3].outputs.empty());
  EXPECT_NEAR(widened[3].hi[6], 0.31 + tol, 1e-12);
  estimates[5].sigma[6] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(FindExtrapolations(cfg, cases, estimates)[3].outputs.size(), 1u);

  // Every case a training case: nothing is extrapolated.
  HgannFitnessConfig all = cfg;
  for (HgannCase& c : all.cases) c.training = true;
  EXPECT_TRUE(FindExtrapolations(all, cases, {}).empty());
}

TEST(UnsettledOutputs, WhereTheShapesThatFitAlikePartByMoreThanTheCaseWouldAllow) {
  const HgannFitnessConfig cfg = NineCases();
  TrendSeeds seeds;
  EXPECT_TRUE(UnsettledOutputs(cfg, seeds, 0, {}, nullptr).empty());  // no trend seeds
  std::array<double, model::kNetworkOutputs> lo{}, hi{}, net{};
  for (int k = 0; k < model::kNetworkOutputs; ++k) {
    lo[k] = hi[k] = net[k] =
        cfg.ranges[k].lower + 0.5 * (cfg.ranges[k].upper - cfg.ranges[k].lower);
  }
  const double w_delta = cfg.ranges[1].upper - cfg.ranges[1].lower;
  const double w_a2 = cfg.ranges[6].upper - cfg.ranges[6].lower;
  hi[1] += 0.05 * w_delta;  // δ: the shapes part by 5 % of its range
  net[6] += 0.03 * w_a2;    // a2: the network's own value 3 % off the shapes' (agreeing) one
  lo[6] -= 0.005 * w_a2;  // a2's shapes part by 0.5 %, under the 1 %: only the network's 3 % counts
  lo[2] -= 0.5 * (cfg.ranges[2].upper - cfg.ranges[2].lower);  // α: never named (the valley)
  seeds.supported_lo.assign(9, lo);
  seeds.supported_hi.assign(9, hi);
  EXPECT_EQ(UnsettledOutputs(cfg, seeds, 8, net, nullptr), (std::vector<int>{1, 6}));
  EXPECT_TRUE(UnsettledOutputs(cfg, seeds, 9, net, nullptr).empty());  // no such case

  // The case's own fit: δ pinned down to ± 4 % (2 σ = 8 % > 5 %): within what the case allows;
  // a2 not pinned down (σ infinite): the case does not see it.
  CaseEstimate e;
  e.ok = true;
  e.sigma.fill(1e-9);
  e.sigma[1] = 0.04 * w_delta;
  e.sigma[6] = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(UnsettledOutputs(cfg, seeds, 8, net, &e).empty());
  e.sigma[1] = 0.01 * w_delta;  // 2 σ = 2 % < 5 %
  EXPECT_EQ(UnsettledOutputs(cfg, seeds, 8, net, &e), (std::vector<int>{1}));

  // With the prediction's move: δ at the far end of the range (hi) moves case 9's prediction by
  // 1.5 × its own PI (under the 2 × that would make the network's PI 3 × the floor): not named;
  // by 2.5 ×: named. NaN (no simulation): named.
  e.pi = 0.2;
  double asked = 0;
  const auto move_by = [&](double d) {
    return [&asked, d](int k, double value) {
      EXPECT_EQ(k, 1);
      asked = value;
      return d;
    };
  };
  EXPECT_TRUE(UnsettledOutputs(cfg, seeds, 8, net, &e, move_by(0.3)).empty());
  EXPECT_DOUBLE_EQ(asked, hi[1]);
  EXPECT_EQ(UnsettledOutputs(cfg, seeds, 8, net, &e, move_by(0.5)), (std::vector<int>{1}));
  EXPECT_EQ(UnsettledOutputs(cfg, seeds, 8, net, &e, move_by(std::nan(""))), (std::vector<int>{1}));
}

}  // namespace
}  // namespace pz::hgann
