// Complete-model optimisers (opt/param_search.h): PSO, real-coded GA, binary GA and DE reach the
// known minima of Rosenbrock and Rastrigin; the same seed gives the same result bit for bit inline
// and on a 2-thread pool; bad boxes and options are refused naming the field; Gray decoding. The
// line search of one parameter finds the minimum of known functions with local minima on its grid,
// the same on any thread count, and names its bad budgets.
#include "opt/param_search.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <numbers>

#include "opt/inline_evaluator.h"
#include "opt/thread_pool_evaluator.h"
#include "tests/testing/expect_error.h"

namespace pz::opt {
namespace {

class Rosenbrock final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome& g) const override {
    double f = 0;
    for (size_t i = 0; i + 1 < g.reals.size(); ++i) {
      const double a = g.reals[i + 1] - g.reals[i] * g.reals[i], b = 1 - g.reals[i];
      f += 100 * a * a + b * b;
    }
    return {f, FitnessStatus::kOk, {}};
  }
};

class Rastrigin final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome& g) const override {
    double f = 10.0 * g.reals.size();
    for (double x : g.reals) f += x * x - 10 * std::cos(2 * std::numbers::pi * x);
    return {f, FitnessStatus::kOk, {}};
  }
};

/// Sphere around 0.3 that returns NaN in a corner of the box and throws in another: the search
/// must sanitise both and still find the minimum.
class Awkward final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome& g) const override {
    if (g.reals[0] > 0.9 && g.reals[1] > 0.9) return {std::nan(""), FitnessStatus::kOk, {}};
    if (g.reals[0] < -0.9 && g.reals[1] < -0.9) throw std::runtime_error("solver blew up");
    double f = 0;
    for (double x : g.reals) f += (x - 0.3) * (x - 0.3);
    return {f, FitnessStatus::kOk, {}};
  }
};

ParamBox Box(int d, double lo, double hi) {
  ParamBox b;
  for (int i = 0; i < d; ++i) {
    b.names.push_back("x" + std::to_string(i));
    b.lower.push_back(lo);
    b.upper.push_back(hi);
  }
  return b;
}

SearchOptions Options(SearchAlgorithm a, int reps = 3) {
  SearchOptions o;
  o.algorithm = a;
  o.repetitions = reps;
  o.pso.particles = 30;
  o.pso.iterations = 400;
  o.pso.stall_iterations = 80;
  o.pso.tolerance = 1e-9;
  o.ga_real.population = 60;
  o.ga_real.generations = 400;
  o.ga_real.stall_generations = 80;
  o.ga_real.tolerance = 1e-9;
  o.ga_binary.bits_per_parameter = 20;
  o.ga_binary.ga.population_size = 80;
  o.ga_binary.ga.max_generations = 400;
  o.ga_binary.ga.stall_generations = 100;
  return o;
}

SearchResult RunSearch(const FitnessFunction& f, const ParamBox& box, const SearchOptions& o) {
  InlineEvaluator e(f);
  return Search(box, o, e);
}

TEST(ParamSearch, PsoRosenbrock2And4D) {
  Rosenbrock f;
  SearchResult r2 = RunSearch(f, Box(2, -2, 2), Options(SearchAlgorithm::kPso));
  EXPECT_LT(r2.best_cost, 1e-6);
  EXPECT_NEAR(r2.best[0], 1.0, 1e-3);
  EXPECT_NEAR(r2.best[1], 1.0, 2e-3);
  SearchOptions o = Options(SearchAlgorithm::kPso);
  o.pso.particles = 40;
  o.pso.iterations = 3000;
  o.pso.stall_iterations = 0;
  SearchResult r4 = RunSearch(f, Box(4, -2, 2), o);
  EXPECT_LT(r4.best_cost, 1e-4);
  for (double x : r4.best) EXPECT_NEAR(x, 1.0, 0.01);
}

TEST(ParamSearch, Rastrigin6D) {
  Rastrigin f;
  SearchOptions o = Options(SearchAlgorithm::kGaReal, 5);
  o.ga_real.population = 100;
  o.ga_real.generations = 600;
  o.ga_real.stall_generations = 150;
  SearchResult r = RunSearch(f, Box(6, -5.12, 5.12), o);
  EXPECT_LT(r.best_cost, 1e-4);  // the global minimum 0; the nearest local ones are ≥ 1
  for (double x : r.best) EXPECT_NEAR(x, 0.0, 1e-3);
  o.algorithm = SearchAlgorithm::kPso;
  o.pso.particles = 60;
  o.pso.iterations = 1000;
  o.pso.stall_iterations = 200;
  SearchResult p = RunSearch(f, Box(6, -5.12, 5.12), o);
  EXPECT_LT(p.best_cost, 1e-4);
}

TEST(ParamSearch, PsoRastrigin3D) {
  Rastrigin f;
  SearchOptions o = Options(SearchAlgorithm::kPso, 5);
  SearchResult r = RunSearch(f, Box(3, -5.12, 5.12), o);
  EXPECT_LT(r.best_cost, 1e-6);  // the global minimum 0 at the origin, not a local one (≥ 1)
  for (double x : r.best) EXPECT_NEAR(x, 0.0, 1e-4);
  EXPECT_EQ(r.repetition_costs.size(), 5u);
  for (double c : r.repetition_costs) EXPECT_GE(c, r.best_cost);
}

TEST(ParamSearch, RealGaRosenbrockAndRastrigin) {
  Rosenbrock rosen;
  SearchResult r = RunSearch(rosen, Box(2, -2, 2), Options(SearchAlgorithm::kGaReal));
  EXPECT_LT(r.best_cost, 1e-4);
  EXPECT_NEAR(r.best[0], 1.0, 0.02);
  Rastrigin rast;
  SearchResult q = RunSearch(rast, Box(4, -5.12, 5.12), Options(SearchAlgorithm::kGaReal, 5));
  EXPECT_LT(q.best_cost, 1e-4);
  SearchOptions decay = Options(SearchAlgorithm::kGaReal);
  decay.ga_real.mutation_sigma_end = 0.001;  // geometric decrease of the mutation step
  SearchResult d = RunSearch(rosen, Box(2, -2, 2), decay);
  EXPECT_LT(d.best_cost, 1e-4);
  EXPECT_NE(d.trace.best_cost, r.trace.best_cost);
  SearchOptions blx = Options(SearchAlgorithm::kGaReal);
  blx.ga_real.crossover = RealCrossover::kBlxAlpha;
  SearchResult b = RunSearch(rosen, Box(2, -2, 2), blx);
  EXPECT_LT(b.best_cost, 1e-3);
}

TEST(ParamSearch, BinaryGaRastrigin2D) {
  Rastrigin f;
  // 20 bits over [-5.12, 5.12]: the grid holds points within 1e-5 of the origin.
  SearchResult r = RunSearch(f, Box(2, -5.12, 5.12), Options(SearchAlgorithm::kGaBinary, 3));
  EXPECT_LT(r.best_cost, 1e-3);
  for (double x : r.best) EXPECT_NEAR(x, 0.0, 2e-3);
}

TEST(ParamSearch, LogScaleFindsSmallValue) {
  // Minimum at 3e-4 in a box spanning six decades: the log scale puts it mid-box.
  class LogTarget final : public FitnessFunction {
   public:
    FitnessResult Evaluate(const Genome& g) const override {
      const double a = std::log10(g.reals[0] / 3e-4), b = std::log10(g.reals[1] / 2e2);
      return {a * a + b * b, FitnessStatus::kOk, {}};
    }
  } f;
  ParamBox box{{"a", "b"}, {1e-6, 1}, {1, 1e6}, {true, true}};
  SearchResult r = RunSearch(f, box, Options(SearchAlgorithm::kPso, 1));
  EXPECT_NEAR(r.best[0], 3e-4, 3e-7);
  EXPECT_NEAR(r.best[1], 2e2, 0.2);
}

TEST(ParamSearch, SameSeedSameResultInlineAndThreadPool) {
  Rastrigin f;
  for (SearchAlgorithm a : {SearchAlgorithm::kPso, SearchAlgorithm::kGaReal,
                            SearchAlgorithm::kGaBinary, SearchAlgorithm::kDe}) {
    SearchOptions o = Options(a, 2);
    o.pso.iterations = o.ga_real.generations = o.ga_binary.ga.max_generations = o.de.generations =
        60;
    InlineEvaluator inl(f);
    ThreadPoolEvaluator pool(f, 2);
    SearchResult x = Search(Box(3, -5.12, 5.12), o, inl);
    SearchResult y = Search(Box(3, -5.12, 5.12), o, pool);
    SCOPED_TRACE(SearchAlgorithmName(a));
    EXPECT_EQ(x.best, y.best);
    EXPECT_EQ(x.best_cost, y.best_cost);
    EXPECT_EQ(x.evaluations, y.evaluations);
    EXPECT_EQ(x.iterations, y.iterations);
    EXPECT_EQ(x.repetition_costs, y.repetition_costs);
    EXPECT_EQ(x.trace.best_cost, y.trace.best_cost);
    EXPECT_EQ(x.trace.evaluations, y.trace.evaluations);
    // A different seed gives a different run.
    o.pso.seed = o.ga_real.seed = o.ga_binary.ga.seed = o.de.seed = 99;
    SearchResult z = Search(Box(3, -5.12, 5.12), o, inl);
    EXPECT_NE(x.trace.best_cost, z.trace.best_cost);
  }
}

TEST(ParamSearch, DifferentialEvolutionFindsTheMinimumFromItsSeeds) {
  // Sphere around (0.3, 0.4, 0.5, 0.6) in the unit box: the DE runs every generation (no stall),
  // and a seed at the minimum is kept from the initial population on.
  class Sphere final : public FitnessFunction {
   public:
    FitnessResult Evaluate(const Genome& g) const override {
      double s = 0;
      for (size_t i = 0; i < g.reals.size(); ++i)
        s += (g.reals[i] - 0.3 - 0.1 * i) * (g.reals[i] - 0.3 - 0.1 * i);
      return {s, FitnessStatus::kOk, {}};
    }
  } f;
  SearchOptions o;
  o.algorithm = SearchAlgorithm::kDe;
  o.repetitions = 1;
  o.de.population = 20;
  o.de.generations = 150;
  o.de.stall_generations = 0;
  o.de.seed = 7;
  const SearchResult a = RunSearch(f, Box(4, 0, 1), o);
  EXPECT_LT(a.best_cost, 1e-8);
  EXPECT_EQ(a.evaluations, 20 * 151);
  EXPECT_EQ(a.iterations, 150);
  PZ_EXPECT_HAS(a.stop_reason, "limit: 150 generations");
  o.de.generations = 3;
  o.seeds = {{0.3, 0.4, 0.5, 0.6}, {2.0, -1.0, 0.5, 0.5}};
  const SearchResult b = RunSearch(f, Box(4, 0, 1), o);
  EXPECT_LT(b.best_cost, 1e-30);
  EXPECT_EQ(b.trace.best_cost.front(), b.best_cost);
}

TEST(ParamSearch, TraceAndCountersConsistent) {
  Rosenbrock f;
  SearchOptions o = Options(SearchAlgorithm::kPso, 2);
  o.pso.particles = 10;
  o.pso.iterations = 20;
  o.pso.stall_iterations = 0;
  std::atomic<int> calls{0};
  o.on_progress = [&](const SearchProgress&) { ++calls; };
  SearchResult r = RunSearch(f, Box(2, -2, 2), o);
  EXPECT_EQ(r.evaluations, 2 * 10 * 21);
  EXPECT_EQ(r.iterations, 40);
  EXPECT_EQ(calls.load(), 42);
  ASSERT_EQ(r.trace.evaluations.size(), 42u);
  EXPECT_EQ(r.trace.evaluations.back(), r.evaluations);
  for (size_t i = 1; i < r.trace.best_cost.size(); ++i)
    EXPECT_LE(r.trace.best_cost[i], r.trace.best_cost[i - 1]);
  EXPECT_EQ(r.trace.best_cost.back(), r.best_cost);
  PZ_EXPECT_HAS(r.stop_reason, "limit: 20 iterations");
  // The reported best is what the fitness says of it.
  Genome g;
  g.reals = r.best;
  EXPECT_EQ(f.Evaluate(g).cost, r.best_cost);
}

TEST(ParamSearch, StallAndTargetStop) {
  Rosenbrock f;
  SearchOptions o = Options(SearchAlgorithm::kGaReal, 1);
  o.ga_real.generations = 100000;
  o.ga_real.stall_generations = 10;
  o.ga_real.tolerance = 0.5;  // only halvings count
  SearchResult r = RunSearch(f, Box(2, -2, 2), o);
  PZ_EXPECT_HAS(r.stop_reason, "stall");
  EXPECT_LT(r.iterations, 100000);
  o.target_cost = 1e-2;
  o.ga_real.stall_generations = 0;
  o.ga_real.tolerance = 0;
  SearchResult t = RunSearch(f, Box(2, -2, 2), o);
  PZ_EXPECT_HAS(t.stop_reason, "target");
  EXPECT_LE(t.best_cost, 1e-2);
}

TEST(ParamSearch, APsoSwarmThatHasConvergedStopsItsRepetition) {
  Rosenbrock f;
  SearchOptions o = Options(SearchAlgorithm::kPso, 2);
  o.pso.iterations = 2000;
  o.pso.stall_iterations = 0;
  o.pso.tolerance = 0;
  const SearchResult full = RunSearch(f, Box(2, -2, 2), o);
  PZ_EXPECT_HAS(full.stop_reason, "limit");
  o.pso.converged_spread = 1e-3;
  const SearchResult r = RunSearch(f, Box(2, -2, 2), o);
  PZ_EXPECT_HAS(r.stop_reason, "converged: every particle within 0.001 of the best");
  EXPECT_LT(r.iterations, full.iterations / 2);
  EXPECT_LT(r.best_cost, 1e-3);  // converged on the minimum, not stopped short
  // The same search, the same stop, bit for bit.
  const SearchResult again = RunSearch(f, Box(2, -2, 2), o);
  EXPECT_EQ(again.best, r.best);
  EXPECT_EQ(again.evaluations, r.evaluations);
  o.pso.converged_spread = 1;
  InlineEvaluator e(f);
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { Search(Box(2, -2, 2), o, e); }),
                "pso.converged_spread = 1");
}

TEST(ParamSearch, NanAndExceptionsAreSanitised) {
  Awkward f;
  for (SearchAlgorithm a : {SearchAlgorithm::kPso, SearchAlgorithm::kGaReal,
                            SearchAlgorithm::kGaBinary, SearchAlgorithm::kDe}) {
    SearchOptions o = Options(a, 1);
    o.pso.iterations = o.ga_real.generations = o.ga_binary.ga.max_generations = o.de.generations =
        100;
    SearchResult r = RunSearch(f, Box(2, -1, 1), o);
    SCOPED_TRACE(SearchAlgorithmName(a));
    EXPECT_TRUE(std::isfinite(r.best_cost));
    EXPECT_LT(r.best_cost, 1e-3);
  }
}

TEST(ParamSearch, BadBoxAndOptionsNamed) {
  using pz::testing::InputErrorOf;
  Rosenbrock f;
  InlineEvaluator e(f);
  auto search = [&](const ParamBox& b, const SearchOptions& o) {
    return InputErrorOf([&] { Search(b, o, e); });
  };
  SearchOptions ok = Options(SearchAlgorithm::kPso, 1);
  PZ_EXPECT_HAS(search(ParamBox{}, ok), "box.names");
  PZ_EXPECT_HAS(search(ParamBox{{"k", "c"}, {1, 2}, {5, 1}, {}}, ok), "box.upper[1] (c) = 1");
  PZ_EXPECT_HAS(search(ParamBox{{"k"}, {1, 2}, {5}, {}}, ok), "box.lower.size()");
  PZ_EXPECT_HAS(search(ParamBox{{"k", "k"}, {1, 2}, {5, 6}, {}}, ok), "duplicate");
  PZ_EXPECT_HAS(search(ParamBox{{"k"}, {-1}, {5}, {true}}, ok),
                "box.lower[0] (k) = -1: must be > 0");
  PZ_EXPECT_HAS(search(ParamBox{{"k"}, {std::nan("")}, {5}, {}}, ok), "box.lower[0]");
  const ParamBox box = Box(2, -1, 1);
  SearchOptions o = ok;
  o.pso.particles = 1;
  PZ_EXPECT_HAS(search(box, o), "pso.particles = 1");
  o = ok;
  o.pso.velocity_clamp = 0;
  PZ_EXPECT_HAS(search(box, o), "pso.velocity_clamp = 0");
  o = ok;
  o.pso.inertia_start = std::nan("");
  PZ_EXPECT_HAS(search(box, o), "pso.inertia_start");
  o = ok;
  o.repetitions = 0;
  PZ_EXPECT_HAS(search(box, o), "repetitions = 0");
  o = ok;
  o.target_cost = std::nan("");
  PZ_EXPECT_HAS(search(box, o), "target_cost");
  o = Options(SearchAlgorithm::kGaReal, 1);
  o.ga_real.tournament = 0;
  PZ_EXPECT_HAS(search(box, o), "ga_real.tournament = 0");
  o.ga_real.tournament = 2;
  o.ga_real.elite_fraction = 0.001;
  PZ_EXPECT_HAS(search(box, o), "ga_real.elite_fraction");
  o.ga_real.elite_fraction = 0.1;
  o.ga_real.mutation_probability = 1.5;
  PZ_EXPECT_HAS(search(box, o), "ga_real.mutation_probability = 1.5");
  o.ga_real.mutation_probability = 0.1;
  o.ga_real.mutation_sigma = -1;
  PZ_EXPECT_HAS(search(box, o), "ga_real.mutation_sigma = -1");
  o.ga_real.mutation_sigma = 0.1;
  o.ga_real.mutation_sigma_end = 0.2;
  PZ_EXPECT_HAS(search(box, o), "ga_real.mutation_sigma_end = 0.2");
  o = Options(SearchAlgorithm::kGaBinary, 1);
  o.ga_binary.bits_per_parameter = 60;
  PZ_EXPECT_HAS(search(box, o), "ga_binary.bits_per_parameter = 60");
  o.ga_binary.bits_per_parameter = 16;
  o.ga_binary.ga.population_size = 1;
  PZ_EXPECT_HAS(search(box, o), "ga_binary.ga.population_size = 1");
  o = Options(SearchAlgorithm::kDe, 1);
  o.de.population = 3;
  PZ_EXPECT_HAS(search(box, o), "de.population = 3: must be >= 4");
  o.de.population = 20;
  o.seeds = {{0.5}};
  PZ_EXPECT_HAS(search(box, o), "seeds[0].size() = 1: must be 2");
  o = ok;
  o.seeds = {{0.5, 0.5}};
  PZ_EXPECT_HAS(search(box, o), "only the de search takes seeds");
  PZ_EXPECT_HAS(InputErrorOf([] { ParseSearchAlgorithm("nelder-mead"); }),
                "algorithm = nelder-mead");
  EXPECT_EQ(ParseSearchAlgorithm("ga-binary"), SearchAlgorithm::kGaBinary);
  EXPECT_EQ(ParseSearchAlgorithm("de"), SearchAlgorithm::kDe);
}

/// Two basins on [0, 0.1] (a delay's range): a broad one at 0.023 (cost 0) that the grid sees best,
/// and a narrow, deeper one at 0.0771 (cost −1e-5) that falls between grid points, where the grid's
/// nearest point is only its second local minimum; counts its evaluations.
class TwoBasins final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome& g) const override {
    ++calls;
    const double x = g.reals[0];
    const double broad = (x - 0.023) * (x - 0.023),
                 narrow = 50 * (x - 0.0771) * (x - 0.0771) - 1e-5;
    return {std::min(broad, narrow), FitnessStatus::kOk, {}};
  }
  mutable std::atomic<int> calls{0};
};

SearchOptions LineOptionsOf(int grid, int brackets, double tolerance) {
  SearchOptions o;
  o.algorithm = SearchAlgorithm::kLine;
  o.repetitions = 1;
  o.line.grid = grid;
  o.line.brackets = brackets;
  o.line.tolerance = tolerance;
  return o;
}

TEST(ParamSearch, TheLineSearchRefinesTheGridsLowestLocalMinima) {
  TwoBasins f;
  const ParamBox box = Box(1, 0, 0.1);
  // Grid of 17 (step 0.00625): the broad basin's nearest point 0.025 costs 4e-6; the narrow basin's
  // 0.075 costs 50 · 2.1e-3² − 1e-5 ≈ 2.1e-4, a local minimum of the grid, but not its best.
  const SearchResult two = RunSearch(f, box, LineOptionsOf(17, 2, 1e-6));
  EXPECT_NEAR(two.best[0], 0.0771, 1e-6);
  EXPECT_NEAR(two.best_cost, -1e-5, 1e-11);
  EXPECT_EQ(two.evaluations, f.calls.load());
  EXPECT_LE(two.evaluations, 17 + 2 * 60);
  EXPECT_EQ(two.repetition_best.size(), 1u);
  PZ_EXPECT_HAS(two.stop_reason, "grid of 17, 2 local minima refined by Brent's method");
  // One bracket refines the grid's best alone: the broad basin's minimum, to the tolerance.
  const SearchResult one = RunSearch(f, box, LineOptionsOf(17, 1, 1e-6));
  EXPECT_NEAR(one.best[0], 0.023, 1e-6);
  EXPECT_NEAR(one.best_cost, 0, 1e-12);
  EXPECT_LT(one.evaluations, two.evaluations);
  // Brent's parabolas: a parabola's vertex within two or three steps of the grid.
  class Parabola final : public FitnessFunction {
   public:
    FitnessResult Evaluate(const Genome& g) const override {
      return {(g.reals[0] - 0.3141) * (g.reals[0] - 0.3141) + 2, FitnessStatus::kOk, {}};
    }
  } parabola;
  const SearchResult p = RunSearch(parabola, Box(1, -1, 1), LineOptionsOf(9, 2, 1e-8));
  EXPECT_NEAR(p.best[0], 0.3141, 1e-7);
  EXPECT_LE(p.evaluations,
            9 + 12);  // one local minimum on the grid: one bracket (golden steps alone: 37)
  // Ends of the range: a minimum at the bound is found there.
  class Slope final : public FitnessFunction {
   public:
    FitnessResult Evaluate(const Genome& g) const override {
      return {g.reals[0], FitnessStatus::kOk, {}};
    }
  } slope;
  const SearchResult end = RunSearch(slope, Box(1, 2, 3), LineOptionsOf(5, 2, 1e-6));
  EXPECT_NEAR(end.best[0], 2, 1e-5);
}

TEST(ParamSearch, TheLineSearchIsTheSameOnAnyThreadCount) {
  // Costs with local minima everywhere (Rastrigin in one dimension): the grid's minima, their
  // refinements and so the result and its trace are the same inline and on pools of 2 and 3
  // threads.
  Rastrigin f;
  const ParamBox box = Box(1, -5.12, 5.12);
  const SearchOptions o = LineOptionsOf(33, 3, 1e-7);
  InlineEvaluator inl(f);
  ThreadPoolEvaluator two(f, 2), three(f, 3);
  const SearchResult x = Search(box, o, inl), y = Search(box, o, two), z = Search(box, o, three);
  EXPECT_NEAR(x.best[0], 0, 1e-6);  // the global minimum among Rastrigin's 11 on the range
  for (const SearchResult* r : {&y, &z}) {
    EXPECT_EQ(x.best, r->best);
    EXPECT_EQ(x.best_cost, r->best_cost);
    EXPECT_EQ(x.evaluations, r->evaluations);
    EXPECT_EQ(x.iterations, r->iterations);
    EXPECT_EQ(x.trace.best_cost, r->trace.best_cost);
    EXPECT_EQ(x.trace.evaluations, r->trace.evaluations);
    EXPECT_EQ(x.stop_reason, r->stop_reason);
  }
}

TEST(ParamSearch, TheLineSearchsBadBudgetsAreNamed) {
  using pz::testing::InputErrorOf;
  Rosenbrock f;
  InlineEvaluator e(f);
  auto search = [&](const ParamBox& b, const SearchOptions& o) {
    return InputErrorOf([&] { Search(b, o, e); });
  };
  const ParamBox box = Box(1, 0, 1);
  PZ_EXPECT_HAS(search(box, LineOptionsOf(2, 2, 1e-4)), "line.grid = 2: must be >= 3");
  PZ_EXPECT_HAS(search(box, LineOptionsOf(17, 0, 1e-4)), "line.brackets = 0: must be >= 1");
  PZ_EXPECT_HAS(search(box, LineOptionsOf(17, 2, 0)), "line.tolerance = 0: must be in (0, 0.5)");
  PZ_EXPECT_HAS(search(box, LineOptionsOf(17, 2, 0.5)), "line.tolerance = 0.5");
  SearchOptions o = LineOptionsOf(17, 2, 1e-4);
  o.line.max_steps = 0;
  PZ_EXPECT_HAS(search(box, o), "line.max_steps = 0: must be >= 1");
  PZ_EXPECT_HAS(search(Box(2, 0, 1), LineOptionsOf(17, 2, 1e-4)),
                "algorithm = line: searches one parameter; the box has 2");
  o = LineOptionsOf(17, 2, 1e-4);
  o.repetitions = 3;
  PZ_EXPECT_HAS(search(box, o), "repetitions = 3: must be 1 for the line search");
  EXPECT_EQ(ParseSearchAlgorithm("line"), SearchAlgorithm::kLine);
  EXPECT_STREQ(SearchAlgorithmName(SearchAlgorithm::kLine), "line");
  PZ_EXPECT_HAS(LineOptions{}.Describe(),
                "a grid of 17 points, then the lowest 2 of its local minima refined by Brent's "
                "method to 0.0001 of the range");
}

TEST(ParamSearch, GrayAndPlainDecoding) {
  // 4-bit Gray 1101 = binary 1001 = 9; plain 1101 = 13; scale 15.
  const uint8_t bits[8] = {1, 1, 0, 1, 0, 0, 0, 1};
  double u[2];
  DecodeBits(bits, 2, 4, true, u);
  EXPECT_DOUBLE_EQ(u[0], 9.0 / 15);
  EXPECT_DOUBLE_EQ(u[1], 1.0 / 15);  // Gray 0001 = binary 0001
  DecodeBits(bits, 2, 4, false, u);
  EXPECT_DOUBLE_EQ(u[0], 13.0 / 15);
  // All ones: Gray 1111 = binary 1010 = 10.
  const uint8_t ones[4] = {1, 1, 1, 1};
  DecodeBits(ones, 1, 4, true, u);
  EXPECT_DOUBLE_EQ(u[0], 10.0 / 15);
  // Box mapping round trip, linear and log.
  ParamBox box{{"a", "b"}, {-2, 1e-3}, {2, 1e3}, {false, true}};
  const double x[2] = {0.25, 0.5};
  double p[2], back[2];
  box.ToPhysical(x, p);
  EXPECT_DOUBLE_EQ(p[0], -1.0);
  EXPECT_NEAR(p[1], 1.0, 1e-15);
  box.ToUnit(p, back);
  EXPECT_NEAR(back[0], 0.25, 1e-15);
  EXPECT_NEAR(back[1], 0.5, 1e-15);
}

}  // namespace
}  // namespace pz::opt
