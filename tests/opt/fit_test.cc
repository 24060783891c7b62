// The one fit (opt/fit.h): search + Levenberg–Marquardt + uncertainty on a straight line with
// known least-squares answers (estimates, standard errors, residual σ), whatever the residual
// weight; a parameter without effect; a custom map whose evaluators get unit coordinates; the same
// result inline and on a thread pool; the choice between the search's best and the polish; the
// errors of a problem or options that cannot run.
#include "opt/fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "opt/inline_evaluator.h"
#include "opt/thread_pool_evaluator.h"
#include "tests/testing/expect_error.h"

namespace pz::opt {
namespace {

/// y_k = 1.5 + 0.8 t_k + noise, t_k = k / 10, k < 40 (a fixed pseudo-random noise).
struct Line {
  std::vector<double> t, y;
  Line() {
    for (int k = 0; k < 40; ++k) {
      t.push_back(k / 10.0);
      y.push_back(1.5 + 0.8 * t.back() + 0.05 * std::sin(12.9898 * k + 78.233 * k * k));
    }
  }
  /// Residuals × w of (a, b[, c]) at physical values; c has no effect.
  bool Residuals(std::span<const double> x, std::vector<double>& r, double w) const {
    r.resize(t.size());
    for (size_t k = 0; k < t.size(); ++k) r[k] = (y[k] - x[0] - x[1] * t[k]) * w;
    return true;
  }
};

class LineFitness final : public FitnessFunction {
 public:
  LineFitness(const Line& line, double w, bool residuals, const ParameterMap* unit_map = nullptr)
      : line_(line), w_(w), residuals_(residuals), unit_map_(unit_map) {}
  FitnessResult Evaluate(const Genome& g) const override {
    const std::vector<double> x = unit_map_ ? unit_map_->ToPhysical(g.reals) : g.reals;
    FitnessResult out;
    line_.Residuals(x, out.residuals, w_);
    for (double e : out.residuals) out.cost += e * e;
    if (!residuals_) out.residuals.clear();
    return out;
  }

 private:
  const Line& line_;
  double w_;
  bool residuals_;
  const ParameterMap* unit_map_;
};

ParamBox LineBox(int n) {
  ParamBox b{{"a", "b"}, {-5, -5}, {5, 5}, {}};
  if (n == 3) {
    b.names.push_back("c");
    b.lower.push_back(0.1);
    b.upper.push_back(10);
    b.log_scale = {false, false, true};
  }
  return b;
}

FitOptions QuickOptions() {
  FitOptions o;
  o.search_options.algorithm = SearchAlgorithm::kPso;
  o.search_options.repetitions = 1;
  o.search_options.pso.particles = 12;
  o.search_options.pso.iterations = 30;
  o.lm.fd_step = 1e-6;
  o.search_cost_is_sum_of_squares = true;
  o.threads = 1;
  return o;
}

struct LineFit {
  std::unique_ptr<LineFitness> cost, residuals;
  FitProblem problem;
};

LineFit MakeProblem(const Line& line, const ParameterMap& map, double w, int threads) {
  LineFit f;
  const ParameterMap* unit_map = map.physical_genomes() ? nullptr : &map;
  f.cost = std::make_unique<LineFitness>(line, w, false, unit_map);
  f.residuals = std::make_unique<LineFitness>(line, w, true, unit_map);
  f.problem.map = &map;
  f.problem.cost_evaluator = [c = f.cost.get(), threads]() -> std::unique_ptr<BatchEvaluator> {
    if (threads > 1) return std::make_unique<ThreadPoolEvaluator>(*c, threads);
    return std::make_unique<InlineEvaluator>(*c);
  };
  f.problem.residual_evaluator = [r = f.residuals.get(),
                                  threads]() -> std::unique_ptr<BatchEvaluator> {
    if (threads > 1) return std::make_unique<ThreadPoolEvaluator>(*r, threads);
    return std::make_unique<InlineEvaluator>(*r);
  };
  f.problem.physical_residuals = [&line, w](std::span<const double> x, std::vector<double>& r) {
    return line.Residuals(x, r, w);
  };
  f.problem.residual_weight = w;
  return f;
}

TEST(Fit, StraightLineEstimatesAndStandardErrorsAreTheLeastSquaresOnesWhateverTheWeight) {
  const Line line;
  // Ordinary least squares by hand.
  const double n = static_cast<double>(line.t.size());
  double st = 0, sy = 0, stt = 0, sty = 0;
  for (size_t k = 0; k < line.t.size(); ++k) {
    st += line.t[k];
    sy += line.y[k];
    stt += line.t[k] * line.t[k];
    sty += line.t[k] * line.y[k];
  }
  const double det = n * stt - st * st;
  const double b = (n * sty - st * sy) / det, a = (sy - b * st) / n;
  double sse = 0;
  for (size_t k = 0; k < line.t.size(); ++k) sse += std::pow(line.y[k] - a - b * line.t[k], 2);
  const double s2 = sse / (n - 2);
  const double se_a = std::sqrt(s2 * stt / det), se_b = std::sqrt(s2 * n / det);

  const BoxMap map(LineBox(2), {"V", "V/s"});
  for (double w : {1.0, 1 / std::sqrt(40.0)}) {
    SCOPED_TRACE(w);
    LineFit p = MakeProblem(line, map, w, 1);
    const FitResult r = Fit(p.problem, QuickOptions());
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_NEAR(r.x[0], a, 1e-7);
    EXPECT_NEAR(r.x[1], b, 1e-7);
    EXPECT_NEAR(r.cost, sse * w * w, 1e-9 * sse);
    ASSERT_EQ(r.uncertainty.params.size(), 2u);
    EXPECT_NEAR(r.uncertainty.residual_sigma, std::sqrt(s2), 1e-6 * std::sqrt(s2));
    EXPECT_NEAR(r.uncertainty.params[0].std_error, se_a, 1e-4 * se_a);
    EXPECT_NEAR(r.uncertainty.params[1].std_error, se_b, 1e-4 * se_b);
    EXPECT_EQ(r.uncertainty.params[1].unit, "V/s");
    EXPECT_EQ(r.uncertainty.params[0].identifiability, Identifiability::kWell);
    // Sensitivity: RMS output change per step of the unit range (10) of a: exactly 10.
    EXPECT_NEAR(r.uncertainty.params[0].sensitivity, 10.0, 1e-6);
    EXPECT_EQ(r.uncertainty.singular_values.size(), 2u);
    EXPECT_GT(r.uncertainty.evaluations, 0);
    EXPECT_NE(r.message.find("refinement:"), std::string::npos) << r.message;
  }
}

TEST(Fit, AParameterWithoutEffectIsNamedAndTheOthersStillHaveTheirErrors) {
  const Line line;
  const BoxMap map(LineBox(3));
  LineFit p = MakeProblem(line, map, 1, 1);
  const FitResult r = Fit(p.problem, QuickOptions());
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_EQ(r.uncertainty.params.size(), 3u);
  EXPECT_EQ(r.uncertainty.params[2].identifiability, Identifiability::kNoEffect);
  EXPECT_TRUE(std::isinf(r.uncertainty.params[2].std_error));
  EXPECT_TRUE(std::isfinite(r.uncertainty.params[0].std_error));
  EXPECT_NE(r.uncertainty.weakest_direction.find("c"), std::string::npos)
      << r.uncertainty.weakest_direction;
  // A log-scaled parameter's scale is ∂x/∂u = x ln(upper / lower).
  EXPECT_NEAR(r.uncertainty.params[2].scale, r.x[2] * std::log(100.0), 1e-12);
}

/// b searched as the ratio b/a ∈ [0, 1] of a ∈ [0.5, 5]: a custom map whose evaluators get unit
/// coordinates (the fin's γ/β).
class RatioMap final : public ParameterMap {
 public:
  int size() const override { return 2; }
  std::string name(int i) const override { return i ? "b" : "a"; }
  std::string unit(int) const override { return ""; }
  std::vector<double> ToPhysical(std::span<const double> u) const override {
    const double a = 0.5 + 4.5 * std::clamp(u[0], 0.0, 1.0);
    return {a, std::clamp(u[1], 0.0, 1.0) * a};
  }
  std::vector<double> ToUnit(std::span<const double> x) const override {
    return {std::clamp((x[0] - 0.5) / 4.5, 0.0, 1.0), std::clamp(x[1] / x[0], 0.0, 1.0)};
  }
  void Bounds(std::span<const double> x, int i, double* lo, double* hi) const override {
    *lo = i ? 0.0 : 0.5;
    *hi = i ? x[0] : 5.0;
  }
  double Scale(std::span<const double>, int) const override { return 1.0; }
  bool physical_genomes() const override { return false; }
  ParamBox SearchBox() const override { return UnitBox(*this); }
};

TEST(Fit, ACustomMapGetsUnitCoordinatesAndTheResultIsTheSameOnAThreadPool) {
  const Line line;
  const RatioMap map;
  LineFit one = MakeProblem(line, map, 1, 1), pool = MakeProblem(line, map, 1, 2);
  FitOptions o = QuickOptions();
  o.search_options.algorithm = SearchAlgorithm::kDe;
  o.search_options.de.population = 10;
  o.search_options.de.generations = 20;
  o.search_options.seeds = {{0.2, 0.5}};
  const FitResult a = Fit(one.problem, o);
  o.threads = 2;
  const FitResult b = Fit(pool.problem, o);
  ASSERT_TRUE(a.ok) << a.message;
  EXPECT_NEAR(a.x[0], 1.5, 0.05);
  EXPECT_NEAR(a.x[1] / a.x[0], 0.8 / 1.5, 0.05);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.cost, b.cost);
  EXPECT_EQ(a.evaluations, b.evaluations);
  ASSERT_EQ(a.uncertainty.params.size(), 2u);
  EXPECT_EQ(a.uncertainty.params[1].std_error, b.uncertainty.params[1].std_error);
}

TEST(Fit, ThePolishIsKeptOnlyWhereItLowersAComparableSearchCost) {
  const Line line;
  const BoxMap map(LineBox(2));
  LineFit p = MakeProblem(line, map, 1, 1);
  // A residual evaluator that always fails: the search's best stands (comparable cost) or the fit
  // fails (not comparable).
  class Failing final : public FitnessFunction {
   public:
    FitnessResult Evaluate(const Genome&) const override {
      return {1e30, FitnessStatus::kPenalized, "no"};
    }
  };
  static const Failing failing;
  p.problem.residual_evaluator = [] { return std::make_unique<InlineEvaluator>(failing); };
  FitOptions o = QuickOptions();
  const FitResult kept = Fit(p.problem, o);
  EXPECT_TRUE(kept.ok);
  EXPECT_EQ(kept.x, kept.search.best);
  EXPECT_EQ(kept.cost, kept.search.best_cost);
  EXPECT_EQ(kept.best_polish, -1);
  EXPECT_NE(kept.message.find("no polish lowered"), std::string::npos) << kept.message;
  o.search_cost_is_sum_of_squares = false;
  const FitResult failed = Fit(p.problem, o);
  EXPECT_FALSE(failed.ok);
  EXPECT_NE(failed.message.find("refinement failed"), std::string::npos) << failed.message;
  EXPECT_TRUE(failed.uncertainty.params.empty());
}

TEST(Fit, EachRepetitionsBestIsPolishedAndTheDeeperBasinKept) {
  // Two basins of the residuals, r = (4 (x − 0.25)(x − 0.75), 0.3 x): Σ r² ≈ 0.0056 near 0.25 and
  // 0.051 near 0.75. The search's cost prefers x near 0.9, and its repetitions (two random
  // particles, no update) land on both sides of 0.5: the search's best polishes into the shallow
  // basin.
  const BoxMap map(ParamBox{{"x"}, {0.0}, {1.0}, {}});
  const FunctionFitness search_cost([](std::span<const double> x) {
    return FitnessResult{(x[0] - 0.9) * (x[0] - 0.9), FitnessStatus::kOk, ""};
  });
  auto residuals = [](std::span<const double> x, std::vector<double>& r) {
    r = {4 * (x[0] - 0.25) * (x[0] - 0.75), 0.3 * x[0]};
    return true;
  };
  const FunctionFitness residual_cost([&](std::span<const double> x) {
    FitnessResult out;
    residuals(x, out.residuals);
    for (double e : out.residuals) out.cost += e * e;
    return out;
  });
  FitProblem problem;
  problem.map = &map;
  problem.cost_evaluator = [&] { return std::make_unique<InlineEvaluator>(search_cost); };
  problem.residual_evaluator = [&] { return std::make_unique<InlineEvaluator>(residual_cost); };
  problem.physical_residuals = residuals;
  FitOptions o = QuickOptions();
  o.search_cost_is_sum_of_squares = false;
  o.search_options.repetitions = 8;
  o.search_options.pso.particles = 2;
  o.search_options.pso.iterations = 0;
  const FitResult one = Fit(problem, o);
  ASSERT_TRUE(one.ok);
  EXPECT_GT(one.search.best[0], 0.5);
  EXPECT_NEAR(one.x[0], 0.75, 0.05);
  EXPECT_EQ(one.polishes, 1);
  bool left = false;  // a repetition's best in the deep basin
  for (const auto& b : one.search.repetition_best) left = left || b[0] < 0.5;
  ASSERT_TRUE(left) << "the seeds no longer put a repetition's best below 0.5";
  o.polish_repetitions = 7;
  const FitResult all = Fit(problem, o);
  ASSERT_TRUE(all.ok);
  EXPECT_NEAR(all.x[0], 0.25, 0.05);
  EXPECT_LT(all.cost, 0.5 * one.cost);
  EXPECT_GT(all.polishes, 1);
  EXPECT_LE(all.polishes, 8);
  ASSERT_GE(all.best_polish_repetition, 0);
  EXPECT_NE(all.best_polish_repetition, all.search.best_repetition);
  EXPECT_LT(all.search.repetition_best[static_cast<size_t>(all.best_polish_repetition)][0], 0.5);
  PZ_EXPECT_HAS(all.message, "from repetition");
  // The polishes side by side (each its own evaluator) give the same fit, bit for bit; an error in
  // one of them reaches the caller (not std::terminate).
  o.threads = 2;
  o.concurrent_polishes = true;
  const FitResult side = Fit(problem, o);
  EXPECT_EQ(side.x, all.x);
  EXPECT_EQ(side.cost, all.cost);
  EXPECT_EQ(side.polishes, all.polishes);
  EXPECT_EQ(side.best_polish, all.best_polish);
  EXPECT_EQ(side.evaluations, all.evaluations);
  EXPECT_EQ(side.lm_iterations, all.lm_iterations);
  EXPECT_EQ(side.message, all.message);
  FitProblem failing = problem;
  failing.residual_evaluator = []() -> std::unique_ptr<BatchEvaluator> {
    throw InputError("no residuals here");
  };
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { Fit(failing, o); }), "no residuals here");
  o.concurrent_polishes = false;
  // A margin larger than the gain keeps the search's best's polish.
  o.basin_margin = 0.99;
  const FitResult kept = Fit(problem, o);
  EXPECT_EQ(kept.x, one.x);
  o.basin_margin = -1;
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { Fit(problem, o); }), "basin_margin = -1");
}

TEST(Fit, AProblemOrOptionsThatCannotRunAreRefusedNamingWhy) {
  using pz::testing::InputErrorOf;
  const Line line;
  const BoxMap map(LineBox(2));
  LineFit p = MakeProblem(line, map, 1, 1);
  FitOptions o = QuickOptions();
  o.search = false;
  PZ_EXPECT_HAS(InputErrorOf([&] { Fit(p.problem, o); }), "no global search and no starting point");
  o.starts = {{0.5}};
  PZ_EXPECT_HAS(InputErrorOf([&] { Fit(p.problem, o); }), "starts[0].size() = 1: must be 2");
  o = QuickOptions();
  o.threads = 0;
  PZ_EXPECT_HAS(InputErrorOf([&] { Fit(p.problem, o); }), "threads = 0");
  o = QuickOptions();
  FitProblem bare;
  bare.map = &map;
  PZ_EXPECT_HAS(InputErrorOf([&] { Fit(bare, o); }), "needs a cost evaluator");
  PZ_EXPECT_HAS(InputErrorOf([&] { BoxMap(LineBox(2), {"V"}); }), "units.size() = 1");
}

// Forward differences (p + 1 evaluations a Jacobian) stop where their O(step) error balances the
// gradient; `central_to_finish` goes on from there with central ones: the central polish's minimum
// for fewer evaluations. y = a e^{-b t} in unit coordinates (a = 4 x0, b = 3 x1), a coarse step.
TEST(LevenbergMarquardt, ForwardDifferencesFinishedCentrallyReachTheCentralMinimumForLess) {
  std::vector<double> t, y;
  for (int k = 0; k < 30; ++k) {
    t.push_back(k / 10.0);
    y.push_back(2.0 * std::exp(-1.3 * t.back()) + 0.01 * std::sin(12.9898 * k + 78.233 * k * k));
  }
  const ResidualFunction f = [&](std::span<const double> x, std::vector<double>& r) {
    r.resize(t.size());
    for (size_t k = 0; k < t.size(); ++k) r[k] = y[k] - 4 * x[0] * std::exp(-3 * x[1] * t[k]);
    return true;
  };
  const std::vector<double> lo = {0, 0}, hi = {1, 1};
  auto run = [&](bool central, bool finish) {
    LmOptions o;
    o.fd_step = 2e-2;
    o.central = central;
    o.central_to_finish = finish;
    o.threads = 1;
    return LevenbergMarquardt(f, {0.2, 0.2}, lo, hi, o);
  };
  const LmResult c = run(true, false), fw = run(false, false), fc = run(false, true);
  ASSERT_TRUE(c.converged) << c.message;
  ASSERT_TRUE(fc.converged) << fc.message;
  // Each stops by its relative-decrease rule (ftol 1e-7): forward alone ~3e-7 above the central
  // polish's cost here, finished centrally within 1e-6 of it and below forward alone.
  EXPECT_GT(fw.cost, fc.cost);
  EXPECT_LE(fc.cost, c.cost * (1 + 1e-6));
  EXPECT_LT(fc.evaluations, c.evaluations);
  EXPECT_LT(fw.evaluations, fc.evaluations);
}

}  // namespace
}  // namespace pz::opt
