// The binary GA: options validation, the generator (MT19937-64 and its portable mappings),
// determinism across evaluators and thread counts and checkpoint/restore, elitism, termination
// (stall, max generations, target, cancel), failure accounting without NaN, and two toy problems
// that must converge (OneMax on 1415 bits; fitting a target HGANN network through the codec).
#include "opt/ga.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

#include "opt/inline_evaluator.h"
#include "opt/random.h"
#include "opt/thread_pool_evaluator.h"
#include "model/chromosome.h"

namespace pz::opt {
namespace {

// ------------------------------------------------------------------------------------------
// Fitness functions

/// Weighted Hamming distance to a hashed target, with failure modes keyed on the first bits:
/// "111…" penalised (finite 1e6), "0000…" returns NaN (the GA must sanitise it), "10101…" throws.
class HashFitness final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome& g) const override {
    const auto& b = g.bits;
    if (b[0] && b[1] && b[2]) return {1e6, FitnessStatus::kPenalized, "unbounded hysteresis"};
    if (!b[0] && !b[1] && !b[2] && !b[3]) return {std::nan(""), FitnessStatus::kOk, ""};
    if (b[0] && !b[1] && b[2] && !b[3] && b[4]) throw std::runtime_error("solver blew up");
    double cost = 0;
    for (size_t i = 0; i < b.size(); ++i) {
      uint64_t h = (i + 1) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 31;
      h *= 0xBF58476D1CE4E5B9ull;
      h ^= h >> 29;
      if (b[i] != ((h >> 7) & 1)) cost += 0.5 + static_cast<double>(h >> 11) * 0x1.0p-53;
    }
    return {cost, FitnessStatus::kOk, ""};
  }
};

class OneMax final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome& g) const override {
    return {static_cast<double>(std::count(g.bits.begin(), g.bits.end(), 0)), FitnessStatus::kOk,
            ""};
  }
};

class ConstantFitness final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome&) const override { return {}; }
};

/// Evaluates a batch through `inner` in a shuffled order and in uneven pieces, then puts the
/// results back in place: arrival order must not matter.
class ShuffledEvaluator final : public BatchEvaluator {
 public:
  explicit ShuffledEvaluator(BatchEvaluator* inner) : inner_(inner) {}
  void Evaluate(const EvalBatch& batch, std::span<FitnessResult> out) override {
    const size_t n = batch.genomes.size();
    std::vector<size_t> perm(n);
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(),
                 std::mt19937(static_cast<unsigned>(batch.generation * 7919 + 1)));
    std::vector<Genome> genomes;
    std::vector<int> indices;
    for (size_t p : perm) {
      genomes.push_back(batch.genomes[p]);
      indices.push_back(batch.indices[p]);
    }
    std::vector<FitnessResult> results(n);
    for (size_t start = 0, piece = 1; start < n; start += piece, piece = piece * 2 + 1) {
      const size_t len = std::min(piece, n - start);
      inner_->Evaluate({batch.generation, std::span(genomes).subspan(start, len),
                        std::span(indices).subspan(start, len)},
                       std::span(results).subspan(start, len));
    }
    for (size_t i = 0; i < n; ++i) out[perm[i]] = results[i];
  }

 private:
  BatchEvaluator* inner_;
};

GaOptions SmallOptions(uint64_t seed = 42) {
  GaOptions o;
  o.population_size = 60;
  o.max_generations = 25;
  o.seed = seed;
  return o;
}

// ------------------------------------------------------------------------------------------
// Generator

// A fitness with lanes (FitnessFunction::lanes / EvaluateMany): the thread pool hands its threads
// that many genomes at a time, with the one-by-one results; an exception in EvaluateMany falls back
// to EvaluateGuarded for each genome of the group.
class LaneFitness final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome& g) const override {
    if (g.reals[0] < 0) throw std::runtime_error("negative");
    return {g.reals[0] * g.reals[0], FitnessStatus::kOk, ""};
  }
  int lanes() const override { return 3; }
  void EvaluateMany(std::span<const Genome* const> gs,
                    std::span<FitnessResult> out) const override {
    groups.fetch_add(1);
    largest.store(std::max<int>(largest.load(), static_cast<int>(gs.size())));
    FitnessFunction::EvaluateMany(gs, out);
  }
  mutable std::atomic<int> groups{0}, largest{0};
};

TEST(ThreadPoolEvaluator, AFitnessWithLanesGetsGroupsWithTheSameResults) {
  LaneFitness fitness;
  std::vector<Genome> g(11);
  for (size_t i = 0; i < g.size(); ++i) g[i].reals = {i == 4 ? -1.0 : 0.5 * static_cast<double>(i)};
  std::vector<int> idx(g.size());
  std::vector<FitnessResult> pooled(g.size());
  ThreadPoolEvaluator pool(fitness, 2);
  pool.Evaluate({0, g, idx}, pooled);
  EXPECT_GE(fitness.groups.load(), 3);
  EXPECT_EQ(fitness.largest.load(), 3);
  for (size_t i = 0; i < g.size(); ++i) {
    const FitnessResult want = EvaluateGuarded(fitness, g[i]);
    EXPECT_EQ(pooled[i].cost, want.cost) << i;
    EXPECT_EQ(pooled[i].status, want.status) << i;
  }
  EXPECT_EQ(pooled[4].status, FitnessStatus::kError);
  EXPECT_EQ(pooled[4].reason, "exception: negative");
}

TEST(Rng, MatchesStdMt19937_64) {
  for (uint64_t seed : {5489ull, 0ull, 42ull, 0xFFFFFFFFFFFFFFFFull}) {
    Rng r(seed);
    std::mt19937_64 ref(seed);
    for (int i = 0; i < 20000; ++i)
      ASSERT_EQ(r.NextU64(), ref()) << "seed " << seed << " draw " << i;
  }
  // The standard's check value: the 10000th output of a default-constructed engine.
  Rng r;
  for (int i = 1; i < 10000; ++i) r.NextU64();
  EXPECT_EQ(r.NextU64(), 9981545732273789042ull);
}

TEST(Rng, StateSavesAndRestores) {
  Rng a(7);
  for (int i = 0; i < 500; ++i) a.NextU64();
  const RngState saved = a.state();
  Rng b(saved);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(a.NextU64(), b.NextU64());
  RngState bad = saved;
  bad.position = 313;
  EXPECT_THROW(Rng{bad}, InputError);
  bad = saved;
  bad.words.fill(0);
  EXPECT_THROW(Rng{bad}, InputError);
}

TEST(Rng, PortableMappings) {
  Rng r(1);
  // UniformBelow covers the range and stays in it.
  std::vector<int> hits(7, 0);
  for (int i = 0; i < 7000; ++i) ++hits[r.UniformBelow(7)];
  for (int h : hits) EXPECT_GT(h, 800);
  EXPECT_EQ(r.UniformBelow(1), 0u);
  // Uniform01 is (x >> 11) 2^-53 of the same draw.
  Rng a(3), b(3);
  EXPECT_EQ(a.Uniform01(), static_cast<double>(b.NextU64() >> 11) * 0x1.0p-53);
  // Bernoulli: exact at the ends, about p in between, one draw each time.
  Rng c(9), d(9);
  for (int i = 0; i < 1000; ++i) {
    EXPECT_FALSE(c.Bernoulli(0.0));
    EXPECT_TRUE(c.Bernoulli(1.0));
    d.NextU64();
    d.NextU64();
  }
  EXPECT_EQ(c, d);
  int ones = 0;
  for (int i = 0; i < 100000; ++i) ones += c.Bernoulli(0.01);
  EXPECT_NEAR(ones, 1000, 150);
  EXPECT_EQ(BernoulliThreshold(0.5).threshold, 1ull << 63);
}

// ------------------------------------------------------------------------------------------
// Mutation: positions of flipped bits drawn as geometric gaps

// z-score of a chi-square statistic with `dof` degrees of freedom (normal approximation).
double ChiSquareZ(double chi2, double dof) { return (chi2 - dof) / std::sqrt(2 * dof); }

// The gap of one draw x by the definition, scanning k = 1, 2, …: G ≥ k iff x < ⌊(1 − p)^k 2⁶⁴⌋.
int GapByDefinition(uint64_t x, double p, int max_gap) {
  double qk = 1;
  int g = 0;
  for (int k = 1; k <= max_gap; ++k) {
    qk *= 1 - p;
    const double t = std::ldexp(qk, 64);
    const uint64_t threshold = t >= 0x1.0p64 ? ~uint64_t{0} : static_cast<uint64_t>(t);
    if (!(x < threshold)) break;
    g = k;
  }
  return g;
}

TEST(GeometricGaps, EachDrawGivesTheGapOfItsDefinition) {
  for (double p : {0.01, 0.3, 0.9, 1e-4}) {
    const int max_gap = 1415;
    const GeometricGaps gaps(p, max_gap);
    Rng r(17);
    std::mt19937_64 ref(17);
    for (int i = 0; i < 3000; ++i) {
      const uint64_t x = ref();
      ASSERT_EQ(r.Gap(gaps), GapByDefinition(x, p, max_gap)) << "p " << p << " draw " << i;
    }
  }
  // The ends consume nothing: p = 0 never succeeds within the block, p = 1 always at once.
  Rng a(5), b(5);
  const GeometricGaps never(0.0, 100), always(1.0, 100);
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(a.Gap(never), 100);
    EXPECT_EQ(a.Gap(always), 0);
  }
  EXPECT_EQ(a, b);
  // A probability below 2⁻⁵³ (1 − p rounds to 1) stays defined: practically never.
  const GeometricGaps tiny(1e-300, 50);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.Gap(tiny), 50);
}

TEST(GeometricGaps, GapsFollowTheTruncatedGeometricLaw) {
  for (double p : {0.01, 0.2}) {
    const int max_gap = 300;
    const GeometricGaps gaps(p, max_gap);
    Rng r(23);
    const int n = 400000;
    std::vector<double> count(max_gap + 1, 0);
    for (int i = 0; i < n; ++i) ++count[r.Gap(gaps)];
    // Pool k into bins of expected count ≥ 50; P(G = k) = (1 − p)^k p, P(G = max) = (1 − p)^max.
    double chi2 = 0, expected_bin = 0, observed_bin = 0;
    int bins = 0;
    for (int k = 0; k <= max_gap; ++k) {
      const double pk = k < max_gap ? std::pow(1 - p, k) * p : std::pow(1 - p, max_gap);
      expected_bin += n * pk;
      observed_bin += count[k];
      if (expected_bin >= 50 || k == max_gap) {
        chi2 += (observed_bin - expected_bin) * (observed_bin - expected_bin) / expected_bin;
        ++bins;
        expected_bin = observed_bin = 0;
      }
    }
    EXPECT_LT(std::abs(ChiSquareZ(chi2, bins - 1)), 4)
        << "p " << p << ": chi2 " << chi2 << " over " << bins << " bins";
  }
}

// Generation 1 of a GA whose population is all zeros and whose crossover is off: every offspring is
// a zero genome with the mutation applied, so its ones are the flipped positions.
std::vector<Genome> MutatedZeros(double p, uint64_t seed, int population = 400, int bits = 1415) {
  const ConstantFitness fitness;
  InlineEvaluator ev(fitness);
  GaOptions o;
  o.population_size = population;
  o.genome_bits = bits;
  o.crossover_probability = 0;
  o.mutation_probability = p;
  o.seed = seed;
  GeneticAlgorithm ga(o, &ev);
  Genome zeros;
  zeros.bits.assign(bits, 0);
  ga.Initialize(std::vector<Genome>(population, zeros));
  ga.Step();
  // Equal costs rank by index: the elite (zeros) first, then the offspring in order.
  const auto& pop = ga.state().islands[0].population;
  return {pop.begin() + o.elite_count(), pop.end()};
}

TEST(GaMutation, FlipsAreIndependentBitsWithTheRateAndPositionsOfTheOptions) {
  const double p = 0.01;
  const int bits = 1415;
  std::vector<double> per_position(bits, 0);
  std::vector<double> per_genome_hist(60, 0);
  double total = 0, adjacent = 0, genomes = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    for (const Genome& g : MutatedZeros(p, seed)) {
      int ones = 0;
      for (int b = 0; b < bits; ++b) {
        per_position[b] += g.bits[b];
        ones += g.bits[b];
        if (b > 0) adjacent += g.bits[b] & g.bits[b - 1];
      }
      ++per_genome_hist[std::min(ones, 59)];
      total += ones;
      ++genomes;
    }
  }
  const double n_bits = genomes * bits;  // 40 × 200 × 1415 = 11.3 M bits
  // The rate: the total is Binomial(n_bits, p).
  EXPECT_LT(std::abs(total - n_bits * p) / std::sqrt(n_bits * p * (1 - p)), 4) << total << " flips";
  // The positions: uniform over the genome (chi-square over 1415 positions).
  const double e = genomes * p;
  double chi2 = 0;
  for (double c : per_position) chi2 += (c - e) * (c - e) / (e * (1 - p));
  EXPECT_LT(std::abs(ChiSquareZ(chi2, bits)), 4) << "positions chi2 " << chi2;
  // The count per genome: Binomial(1415, p), binned where the expectation is ≥ 20.
  double binom_chi2 = 0, eb = 0, ob = 0;
  int bins = 0;
  for (int k = 0; k < 60; ++k) {
    const double pk =
        std::exp(std::lgamma(bits + 1.0) - std::lgamma(k + 1.0) - std::lgamma(bits - k + 1.0) +
                 k * std::log(p) + (bits - k) * std::log1p(-p));
    eb += genomes * pk;
    ob += per_genome_hist[k];
    if (eb >= 20 || k == 59) {
      binom_chi2 += (ob - eb) * (ob - eb) / eb;
      ++bins;
      eb = ob = 0;
    }
  }
  EXPECT_LT(std::abs(ChiSquareZ(binom_chi2, bins - 1)), 4)
      << "flips per genome chi2 " << binom_chi2;
  // Independence of neighbours: adjacent pairs both flipped ≈ p² per pair.
  const double pairs = genomes * (bits - 1), ea = pairs * p * p;
  EXPECT_LT(std::abs(adjacent - ea) / std::sqrt(ea), 4)
      << adjacent << " adjacent pairs, expected " << ea;
}

TEST(GaMutation, ProbabilityZeroKeepsAndOneFlipsEveryBit) {
  for (const Genome& g : MutatedZeros(0.0, 3, 20, 100))
    EXPECT_EQ(std::count(g.bits.begin(), g.bits.end(), 1), 0);
  for (const Genome& g : MutatedZeros(1.0, 3, 20, 100))
    EXPECT_EQ(std::count(g.bits.begin(), g.bits.end(), 1), 100);
  // A higher rate too (the gaps' table is not only for small p).
  double ones = 0, n = 0;
  for (const Genome& g : MutatedZeros(0.37, 4, 200, 333)) {
    ones += std::count(g.bits.begin(), g.bits.end(), 1);
    n += g.bits.size();
  }
  EXPECT_LT(std::abs(ones - 0.37 * n) / std::sqrt(n * 0.37 * 0.63), 4);
}

// ------------------------------------------------------------------------------------------
// Options

TEST(GaOptions, DefaultsArePaperTable2) {
  const GaOptions o;
  EXPECT_EQ(o.population_size, 400);
  EXPECT_EQ(o.genome_bits, 1415);
  EXPECT_EQ(o.elite_count(), 200);
  EXPECT_EQ(o.tournament_size, 2);
  EXPECT_EQ(o.crossover_probability, 1.0);
  EXPECT_EQ(o.mutation_probability, 0.01);
  EXPECT_EQ(o.max_generations, 1000);
  EXPECT_EQ(o.stall_generations, 200);
  // One island (the paper's GA); the migration defaults chosen by measurement (docs/performance.md,
  // "Islands"): 4 migrants every 25 generations, fully connected, gated by a margin of 0.2, the
  // islands' rates on the ladder 1, 2, 3, 5 × the paper's.
  EXPECT_EQ(o.islands, 1);
  EXPECT_EQ(o.migration_interval, 25);
  EXPECT_EQ(o.migrants, 4);
  EXPECT_EQ(o.topology, MigrationTopology::kFullyConnected);
  EXPECT_EQ(o.migration_margin, 0.2);
  EXPECT_EQ(o.island_stall_generations, 0);
  EXPECT_EQ(o.broadcast_interval, 0);
  EXPECT_TRUE(o.island_mutation.empty());
  EXPECT_EQ(o.MutationProbability(0), 0.01) << "one island: the paper's rate";
  EXPECT_TRUE(o.Validate().ok());
}

TEST(GaOptions, SeveralIslandsMutateOnTheLadderUnlessGivenTheirRates) {
  GaOptions o;
  o.islands = 6;
  const double ladder[] = {0.01, 0.02, 0.03, 0.05, 0.01, 0.02};
  for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(o.MutationProbability(i), ladder[i]) << i;
  EXPECT_EQ(o.MutationProbability(0), o.mutation_probability)
      << "island 0 is the one-island run's rate";
  o.mutation_probability = 0.3;  // 0.3 · 5 is capped at 1
  EXPECT_DOUBLE_EQ(o.MutationProbability(2), 0.9);
  EXPECT_EQ(o.MutationProbability(3), 1.0);
  o.island_mutation = {0.1, 0.1, 0.1, 0.1, 0.1, 0.1};
  for (int i = 0; i < 6; ++i) EXPECT_EQ(o.MutationProbability(i), 0.1) << "given rates win";
}

TEST(GaOptions, ValidateNamesTheField) {
  auto error = [](auto mutate) {
    GaOptions o;
    mutate(o);
    const Status s = o.Validate();
    EXPECT_FALSE(s.ok());
    return s.message();
  };
  EXPECT_EQ(error([](GaOptions& o) { o.population_size = 1; }).rfind("population_size = 1", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.genome_bits = 2; }).rfind("genome_bits = 2", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.elite_fraction = 1; }).rfind("elite_fraction = 1", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.elite_fraction = 0.001; }).rfind("elite_fraction", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.tournament_size = 0; }).rfind("tournament_size", 0), 0u);
  EXPECT_EQ(
      error([](GaOptions& o) { o.mutation_probability = 1.5; }).rfind("mutation_probability", 0),
      0u);
  EXPECT_EQ(
      error([](GaOptions& o) { o.crossover_probability = -1; }).rfind("crossover_probability", 0),
      0u);
  EXPECT_EQ(error([](GaOptions& o) { o.max_generations = -1; }).rfind("max_generations", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.stall_generations = -1; }).rfind("stall_generations", 0),
            0u);
  EXPECT_EQ(error([](GaOptions& o) { o.target_cost = std::nan(""); }).rfind("target_cost", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.error_cost = INFINITY; }).rfind("error_cost", 0), 0u);
  const ConstantFitness fitness;
  InlineEvaluator ev(fitness);
  GaOptions bad;
  bad.population_size = 0;
  EXPECT_THROW(GeneticAlgorithm(bad, &ev), InputError);
}

// ------------------------------------------------------------------------------------------
// Determinism

struct RunRecord {
  GaState state;
  GaSummary summary;
};

RunRecord RunWith(BatchEvaluator* evaluator, const GaOptions& options) {
  GeneticAlgorithm ga(options, evaluator);
  RunRecord r;
  r.summary = ga.Run();
  r.state = ga.state();
  return r;
}

void ExpectSameRun(const RunRecord& a, const RunRecord& b) {
  ASSERT_EQ(a.state.islands.size(), b.state.islands.size());
  for (size_t k = 0; k < a.state.islands.size(); ++k) {
    const IslandState &x = a.state.islands[k], &y = b.state.islands[k];
    ASSERT_EQ(x.population.size(), y.population.size());
    for (size_t i = 0; i < x.population.size(); ++i) {
      ASSERT_EQ(x.population[i], y.population[i]) << "island " << k << " individual " << i;
      ASSERT_EQ(x.fitness[i].cost, y.fitness[i].cost) << "island " << k << " individual " << i;
      ASSERT_EQ(x.fitness[i].status, y.fitness[i].status);
      ASSERT_EQ(x.fitness[i].reason, y.fitness[i].reason);
    }
    EXPECT_EQ(x.rng, y.rng) << "island " << k;
    EXPECT_EQ(x.stall, y.stall) << "island " << k;
    EXPECT_EQ(x.best_cost, y.best_cost) << "island " << k;
    EXPECT_EQ(x.restarts, y.restarts) << "island " << k;
  }
  EXPECT_EQ(a.state.best_island, b.state.best_island);
  EXPECT_EQ(a.state.best, b.state.best);
  EXPECT_EQ(a.state.best_fitness.cost, b.state.best_fitness.cost);
  EXPECT_EQ(a.state.generation, b.state.generation);
  EXPECT_EQ(a.state.stall, b.state.stall);
  EXPECT_EQ(a.state.evaluations, b.state.evaluations);
  EXPECT_EQ(a.state.failures, b.state.failures);
  ASSERT_EQ(a.state.log.size(), b.state.log.size());
  for (size_t g = 0; g < a.state.log.size(); ++g) {
    EXPECT_TRUE(a.state.log[g].SameOutcome(b.state.log[g])) << a.state.log[g].BriefReport() << "\n"
                                                            << b.state.log[g].BriefReport();
  }
  EXPECT_EQ(a.summary.termination, b.summary.termination);
  EXPECT_EQ(a.summary.message, b.summary.message);
}

TEST(GaDeterminism, SameSeedSameRunWhateverTheEvaluator) {
  const HashFitness fitness;
  const GaOptions options = SmallOptions();
  InlineEvaluator inline_ev(fitness);
  const RunRecord reference = RunWith(&inline_ev, options);
  ASSERT_GT(reference.state.failures, 0) << "the run should exercise the failure paths";

  ThreadPoolEvaluator pool1(fitness, 1), pool2(fitness, 2), pool4(fitness, 4);
  ShuffledEvaluator shuffled4(&pool4);
  for (BatchEvaluator* ev : std::initializer_list<BatchEvaluator*>{&pool1, &pool2, &shuffled4}) {
    SCOPED_TRACE(ev == &pool1 ? "1 thread" : ev == &pool2 ? "2 threads" : "4 threads, shuffled");
    ExpectSameRun(reference, RunWith(ev, options));
  }
  EXPECT_EQ(pool4.concurrency(), 4);

  // A different seed gives a different run.
  const RunRecord other = RunWith(&inline_ev, SmallOptions(43));
  EXPECT_NE(other.state.islands[0].population[0], reference.state.islands[0].population[0]);
}

TEST(GaDeterminism, StepByStepWithCheckpointRestoreEqualsOneRun) {
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  const GaOptions options = SmallOptions(5);
  const RunRecord reference = RunWith(&ev, options);

  GaState checkpoint;
  {
    GeneticAlgorithm first(options, &ev);
    first.Initialize();
    for (int g = 0; g < 10; ++g) first.Step();
    checkpoint = first.state();  // e.g. serialised by the master here
  }
  GeneticAlgorithm second(options, &ev);
  second.RestoreState(checkpoint);
  GaSummary summary;
  for (;;) {
    if (auto t = second.CheckTermination()) {
      summary = second.MakeSummary(*t);
      break;
    }
    second.Step();
  }
  ExpectSameRun(reference, {second.state(), summary});

  // A corrupt checkpoint is refused with a named field.
  GaState bad = checkpoint;
  bad.islands[0].population[3].bits.pop_back();
  GeneticAlgorithm third(options, &ev);
  try {
    third.RestoreState(bad);
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("state.islands[0].population[3].bits.size()"),
              std::string::npos)
        << e.what();
  }
  bad = checkpoint;
  std::swap(bad.islands[0].fitness[0], bad.islands[0].fitness[59]);
  EXPECT_THROW(third.RestoreState(bad), InputError);
}

// ------------------------------------------------------------------------------------------
// Operators and invariants

TEST(GaInvariants, ElitismBestNeverWorsensAndOnlyOffspringAreEvaluated) {
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  GaOptions o = SmallOptions(11);
  o.max_generations = 40;
  GeneticAlgorithm ga(o, &ev);
  std::vector<GenerationSummary> seen;
  ga.AddGenerationCallback([&seen](const GenerationSummary& s) { seen.push_back(s); });
  const GaSummary summary = ga.Run();
  ASSERT_EQ(seen.size(), 41u);
  EXPECT_EQ(seen[0].generation, 0u);
  EXPECT_EQ(seen[0].evaluations, 60);
  for (size_t g = 1; g < seen.size(); ++g) {
    EXPECT_EQ(seen[g].generation, g);
    EXPECT_LE(seen[g].best_cost, seen[g - 1].best_cost);
    EXPECT_EQ(seen[g].evaluations, 30);  // 50 % elitism: only the 30 offspring
    EXPECT_EQ(seen[g].evaluations_total, 60 + 30 * static_cast<int64_t>(g));
    EXPECT_EQ(seen[g].improved, seen[g].best_cost < seen[g - 1].best_cost);
  }
  EXPECT_LT(seen.back().best_cost, seen.front().best_cost);
  const GaState& st = ga.state();
  EXPECT_EQ(st.best, st.islands[0].population[0]);
  EXPECT_EQ(st.best_fitness.cost, seen.back().best_cost);
  EXPECT_EQ(HashFitness{}.Evaluate(st.best).cost, st.best_fitness.cost);
  // The median of the ranked population (60: the mean of the 30th and 31st costs).
  const auto& fit = st.islands[0].fitness;
  EXPECT_EQ(seen.back().median_cost, fit[29].cost + (fit[30].cost - fit[29].cost) / 2);
  EXPECT_LE(seen.back().best_cost, seen.back().median_cost);
  EXPECT_TRUE(std::is_sorted(
      fit.begin(), fit.end(),
      [](const FitnessResult& a, const FitnessResult& b) { return a.cost < b.cost; }));
  EXPECT_EQ(summary.termination, GaTermination::kMaxGenerations);
  EXPECT_EQ(summary.generations, 40u);
  EXPECT_EQ(summary.evaluations, 60 + 30 * 40);
}

TEST(GaInvariants, PenalisedAndFailedIndividualsNeverPutNaNInSummaries) {
  const HashFitness fitness;
  ThreadPoolEvaluator ev(fitness, 2);
  GaOptions o = SmallOptions(3);
  o.max_generations = 5;
  GeneticAlgorithm ga(o, &ev);
  const GaSummary summary = ga.Run();
  int penalized = 0, errors = 0;
  std::map<std::string, int> reasons;
  for (const GenerationSummary& s : ga.state().log) {
    EXPECT_TRUE(std::isfinite(s.best_cost) && std::isfinite(s.mean_cost) &&
                std::isfinite(s.worst_cost))
        << s.BriefReport();
    EXPECT_EQ(s.failures, s.penalized + s.errors);
    int total = 0;
    for (const auto& [reason, count] : s.failure_reasons) total += count, reasons[reason] += count;
    EXPECT_EQ(total, s.failures);
    penalized += s.penalized;
    errors += s.errors;
  }
  EXPECT_GT(penalized, 0);
  EXPECT_GT(errors, 0);
  EXPECT_GT(reasons["unbounded hysteresis"], 0);
  EXPECT_GT(reasons["exception: solver blew up"], 0);
  EXPECT_GT(reasons["non-finite cost nan"], 0);
  EXPECT_EQ(summary.failures, penalized + errors);
  for (const FitnessResult& f : ga.state().islands[0].fitness) {
    EXPECT_TRUE(std::isfinite(f.cost));
    if (f.status == FitnessStatus::kError) {
      EXPECT_EQ(f.cost, kDefaultErrorCost);
    }
  }
  // Generation 0 is uniform: about 1/8 start with 111 (penalised 1e6) — and they rank above the
  // 1e30 errors and below every ok individual.
  const GenerationSummary& g0 = ga.state().log[0];
  EXPECT_EQ(g0.worst_cost, kDefaultErrorCost);
}

TEST(GaInvariants, SeedsEnterGenerationZeroAndDescriberIsCalled) {
  const OneMax fitness;
  InlineEvaluator ev(fitness);
  GaOptions o = SmallOptions();
  o.max_generations = 3;
  GeneticAlgorithm ga(o, &ev);
  ga.SetDescriber([](const Genome& g) {
    return "ones=" + std::to_string(std::count(g.bits.begin(), g.bits.end(), 1));
  });
  Genome all_ones;
  all_ones.bits.assign(o.genome_bits, 1);
  const GenerationSummary& g0 = ga.Initialize(std::vector<Genome>{all_ones});
  EXPECT_EQ(g0.best_cost, 0);
  EXPECT_EQ(g0.best_description, "ones=1415");
  EXPECT_EQ(ga.state().islands[0].population[0], all_ones);
  EXPECT_EQ(ga.CheckTermination(), std::nullopt);
  Genome bad;
  bad.bits.assign(10, 1);
  GeneticAlgorithm ga2(o, &ev);
  EXPECT_THROW(ga2.Initialize(std::vector<Genome>{bad}), InputError);
}

// ------------------------------------------------------------------------------------------
// Termination

TEST(GaTermination, StallStopsAfterStallGenerationsWithoutImprovement) {
  const ConstantFitness fitness;  // nothing ever improves on generation 0
  InlineEvaluator ev(fitness);
  GaOptions o = SmallOptions();
  o.max_generations = 1000;
  o.stall_generations = 7;
  GeneticAlgorithm ga(o, &ev);
  const GaSummary s = ga.Run();
  EXPECT_EQ(s.termination, GaTermination::kStall);
  EXPECT_EQ(s.generations, 7u);
  EXPECT_EQ(s.best_generation, 0u);
  EXPECT_NE(s.message.find("in 7 generations"), std::string::npos) << s.message;
  EXPECT_TRUE(ga.state().log[0].improved);
  EXPECT_FALSE(ga.state().log[7].improved);
  EXPECT_EQ(ga.state().log[7].stall, 7);
  EXPECT_NE(s.BriefReport().find("STALL"), std::string::npos);
}

TEST(GaTermination, ARelativeStallCountsOnlyStepsLargerThanItsShareOfTheBest) {
  // OneMax from uniform bits: the best falls by a few of its ≈ 700 zeros (of 1415 bits) a
  // generation, far less than half of it. With stall_relative 0.5 those steps keep the best but do
  // not reset the stall count: the GA stops after stall_generations although it improved; with 0
  // it runs on.
  const OneMax fitness;
  InlineEvaluator ev(fitness);
  GaOptions o = SmallOptions();
  o.max_generations = 40;
  o.stall_generations = 5;
  o.stall_relative = 0.5;
  GeneticAlgorithm ga(o, &ev);
  const GaSummary s = ga.Run();
  EXPECT_EQ(s.termination, GaTermination::kStall);
  EXPECT_EQ(s.generations, 5u);
  EXPECT_GT(s.best_generation, 0u);  // improved, and kept
  EXPECT_LT(s.best_fitness.cost, ga.state().log[0].best_cost);
  o.stall_relative = 0;
  EXPECT_GT(RunWith(&ev, o).summary.generations, 5u);
  o.stall_relative = 1;
  EXPECT_THROW(GeneticAlgorithm(o, &ev), InputError);
}

TEST(GaTermination, MaxGenerationsTargetAndCancel) {
  const OneMax fitness;
  InlineEvaluator ev(fitness);
  GaOptions o = SmallOptions();
  o.max_generations = 0;
  EXPECT_EQ(RunWith(&ev, o).summary.generations, 0u);
  EXPECT_EQ(RunWith(&ev, o).summary.termination, GaTermination::kMaxGenerations);

  o = SmallOptions();
  o.target_cost = 1e9;  // reached by generation 0
  EXPECT_EQ(RunWith(&ev, o).summary.termination, GaTermination::kTargetReached);

  o = SmallOptions();
  GeneticAlgorithm ga(o, &ev);
  ga.AddGenerationCallback([&ga](const GenerationSummary& s) {
    if (s.generation == 4) ga.Cancel();
  });
  const GaSummary s = ga.Run();
  EXPECT_EQ(s.termination, GaTermination::kCancelled);
  EXPECT_EQ(s.generations, 4u);
  ga.ClearCancel();
  EXPECT_EQ(ga.Run().termination, GaTermination::kMaxGenerations);  // resumes to the end
  EXPECT_EQ(ga.state().generation, 25u);
}

// ------------------------------------------------------------------------------------------
// Toy problems

TEST(GaConvergence, OneMaxOn1415Bits) {
  // Paper operators with a per-bit mutation of 1/L (0.01 flips ~14 bits per child, which near the
  // optimum mostly breaks what is there).
  const OneMax fitness;
  ThreadPoolEvaluator ev(fitness, 2);
  GaOptions o;
  o.population_size = 100;
  o.mutation_probability = 1.0 / 1415;
  o.max_generations = 1500;
  o.target_cost = 0;
  GeneticAlgorithm ga(o, &ev);
  const GaSummary s = ga.Run();
  EXPECT_EQ(s.termination, GaTermination::kTargetReached) << s.BriefReport();
  EXPECT_EQ(s.best_fitness.cost, 0);
}

// Fitting a target network through the codec: cost = squared error of the scaled outputs (s in
// [0, 1]) on a grid of drives. The GA must cut the initial best error by a large factor.
class NetworkFitFitness final : public FitnessFunction {
 public:
  NetworkFitFitness() {
    std::vector<uint8_t> target_bits(model::kChromosomeBits);
    std::mt19937_64 g(2024);
    for (uint8_t& b : target_bits) b = static_cast<uint8_t>(g() >> 63);
    target_bits[0] = 0, target_bits[1] = 0, target_bits[2] = 1;  // H = 3
    target_ = model::DecodeChromosome(target_bits, norm_, {});
  }
  FitnessResult Evaluate(const Genome& genome) const override {
    const model::Network n = model::DecodeChromosome(genome.bits, norm_, {});
    double cost = 0;
    for (double v : {375.0, 500.0, 750.0}) {
      for (double f : {0.25, 0.5, 1.0}) {
        const auto a = n.Forward(v, f).s, b = target_.Forward(v, f).s;
        cost += (a - b).squaredNorm();
      }
    }
    return {cost, FitnessStatus::kOk, ""};
  }

 private:
  model::InputNormalization norm_{375, 750, 0.25, 1.0};
  model::Network target_;
};

TEST(GaConvergence, DecodeAndFitATargetNetwork) {
  const NetworkFitFitness fitness;
  ThreadPoolEvaluator ev(fitness, 2);
  GaOptions o;
  o.population_size = 100;
  o.max_generations = 150;
  GeneticAlgorithm ga(o, &ev);
  ga.SetDescriber([](const Genome& g) { return model::DescribeChromosome(g.bits); });
  const GaSummary s = ga.Run();
  const auto& log = ga.state().log;
  EXPECT_LT(log.back().best_cost, 0.05 * log.front().best_cost) << s.BriefReport();
  EXPECT_EQ(log.back().best_description.substr(1, 1), "-");  // "2-H-7 …"
}

// ------------------------------------------------------------------------------------------
// Islands

namespace islands {

/// The run's outcome folded into one number: every island's population, costs and generator,
/// the log's figures, the end. The same fold over the GA before islands existed (one population,
/// GaState::population / fitness / rng) gave the pinned value of OneIslandIsTheGaBeforeIslands.
uint64_t Digest(const GaState& st, const GaSummary& s) {
  uint64_t h = 1469598103934665603ull;
  auto add = [&h](const void* p, size_t n) {
    for (size_t i = 0; i < n; ++i)
      h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ull;
  };
  auto d = [&add](double x) { add(&x, 8); };
  auto u = [&add](uint64_t x) { add(&x, 8); };
  for (const IslandState& is : st.islands) {
    for (size_t i = 0; i < is.population.size(); ++i) {
      add(is.population[i].bits.data(), is.population[i].bits.size());
      d(is.fitness[i].cost);
    }
    for (uint64_t w : is.rng.words) u(w);
    u(is.rng.position);
  }
  for (const GenerationSummary& g : st.log) {
    d(g.best_cost);
    d(g.mean_cost);
    d(g.median_cost);
    d(g.worst_cost);
    u(static_cast<uint64_t>(g.stall));
    u(static_cast<uint64_t>(g.failures));
  }
  u(s.generations);
  d(s.best_fitness.cost);
  return h;
}

// The tests of the mechanisms below name the rules they exercise: a ring without a margin, every
// island at one rate (the defaults of the migration are tested in
// GaOptions.DefaultsArePaperTable2).
GaOptions IslandOptions(int k, uint64_t seed = 42) {
  GaOptions o = SmallOptions(seed);
  o.islands = k;
  o.migration_interval = 3;
  o.migrants = 2;
  o.topology = MigrationTopology::kRing;
  o.migration_margin = 0;
  o.island_mutation.assign(k, o.mutation_probability);
  return o;
}

TEST(GaIslands, OneIslandIsTheGaBeforeIslands) {
  // The value printed by the GA of the commit before islands (same options, fitness and fold).
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  GaOptions o = SmallOptions();
  RunRecord r = RunWith(&ev, o);
  EXPECT_EQ(Digest(r.state, r.summary), 0xd70ed114cf6bb092ull);
  EXPECT_EQ(r.summary.best_fitness.cost, 551.54706204370177);
  EXPECT_TRUE(r.state.log.back().islands.empty());
  // With one island the migration settings are not used.
  o.migration_interval = 1;
  o.migrants = 7;
  o.topology = MigrationTopology::kFullyConnected;
  r = RunWith(&ev, o);
  EXPECT_EQ(Digest(r.state, r.summary), 0xd70ed114cf6bb092ull);
}

TEST(GaIslands, ValidateNamesTheFieldAndTheRange) {
  auto error = [](auto mutate) {
    GaOptions o;
    mutate(o);
    const Status s = o.Validate();
    EXPECT_FALSE(s.ok());
    return s.message();
  };
  EXPECT_EQ(error([](GaOptions& o) { o.islands = 0; }), "islands = 0: must be in [1, 1024]");
  EXPECT_EQ(error([](GaOptions& o) { o.islands = 1025; }).rfind("islands = 1025", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.migrants = 400; }),
            "migrants = 400: must be in [0, population_size - 1 = 399]");
  EXPECT_EQ(error([](GaOptions& o) { o.migrants = -1; }).rfind("migrants = -1", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) {
              o.migrants = 0;
            }).rfind("migrants = 0: must be >= 1 when migration_interval = 25", 0),
            0u);
  EXPECT_EQ(
      error([](GaOptions& o) { o.migration_interval = -1; }).rfind("migration_interval = -1", 0),
      0u);
  EXPECT_NE(error([](GaOptions& o) {
              o.topology = static_cast<MigrationTopology>(9);
            }).find("topology = 9: must be \"ring\""),
            std::string::npos);
  EXPECT_EQ(error([](GaOptions& o) {
              o.island_stall_generations = -2;
            }).rfind("island_stall_generations = -2", 0),
            0u);
  EXPECT_EQ(error([](GaOptions& o) { o.migration_margin = 1; }),
            "migration_margin = 1: must be in [0, 1) (0 = every source)");
  EXPECT_EQ(
      error([](GaOptions& o) { o.migration_margin = -0.5; }).rfind("migration_margin = -0.5", 0),
      0u);
  EXPECT_EQ(error([](GaOptions& o) {
              o.migration_margin = std::nan("");
            }).rfind("migration_margin = nan", 0),
            0u);
  EXPECT_EQ(error([](GaOptions& o) { o.broadcast_interval = -1; }),
            "broadcast_interval = -1: must be >= 0 (0 = no broadcast)");
  EXPECT_EQ(error([](GaOptions& o) {
              o.migration_interval = 0;
              o.migrants = 0;
              o.broadcast_interval = 25;
            }),
            "migrants = 0: must be >= 1 when broadcast_interval = 25 > 0");
  EXPECT_EQ(error([](GaOptions& o) { o.broadcast_margin = 0; }),
            "broadcast_margin = 0: must be in (0, 1)");
  EXPECT_EQ(error([](GaOptions& o) { o.broadcast_margin = 1; }),
            "broadcast_margin = 1: must be in (0, 1)");
  EXPECT_EQ(error([](GaOptions& o) {
              o.broadcast_margin = std::nan("");
            }).rfind("broadcast_margin = nan", 0),
            0u);
  EXPECT_EQ(error([](GaOptions& o) {
              o.island_mutation = {0.01, 0.02};
            }),
            "island_mutation.size() = 2: must be 0 (the ladder: mutation_probability × 1, 2, 3, 5) "
            "or islands = 1");
  EXPECT_EQ(error([](GaOptions& o) {
              o.islands = 3;
              o.island_mutation = {0.01, 1.5, 0.02};
            }),
            "island_mutation[1] = 1.5: must be in [0, 1]");
  EXPECT_EQ(error([](GaOptions& o) {
              o.islands = 2;
              o.island_mutation = {std::nan(""), 0.02};
            }).rfind("island_mutation[0] = nan", 0),
            0u);
  // A caller names the fields as its user wrote them, in the field and in the rule.
  GaOptions named;
  named.migrants = 400;
  EXPECT_EQ(named.Validate([](std::string_view f) { return "ga." + std::string(f); }).message(),
            "ga.migrants = 400: must be in [0, ga.population_size - 1 = 399]");
  GaOptions multistart;
  multistart.migration_interval = 0;
  multistart.migrants = 0;
  EXPECT_TRUE(multistart.Validate().ok());
  EXPECT_EQ(ParseTopology("fully_connected"), MigrationTopology::kFullyConnected);
  EXPECT_EQ(ParseTopology("star"), std::nullopt);
}

TEST(GaIslands, TopologiesAreFixedAndConnected) {
  GaOptions o = IslandOptions(5);
  EXPECT_EQ(o.MigrationSources(0), std::vector<int>{4});
  EXPECT_EQ(o.MigrationSources(3), std::vector<int>{2});
  o.topology = MigrationTopology::kFullyConnected;
  EXPECT_EQ(o.MigrationSources(2), (std::vector<int>{0, 1, 3, 4}));
  o.topology = MigrationTopology::kRandom;
  // A ring in a seeded order: each island has one source, and following sources visits all.
  std::vector<int> seen;
  int at = 0;
  for (int step = 0; step < 5; ++step) {
    ASSERT_EQ(o.MigrationSources(at).size(), 1u);
    at = o.MigrationSources(at)[0];
    seen.push_back(at);
  }
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, (std::vector<int>{0, 1, 2, 3, 4}));
  GaOptions again = o;
  for (int i = 0; i < 5; ++i) EXPECT_EQ(again.MigrationSources(i), o.MigrationSources(i));
  bool differs = false;
  for (uint64_t seed = 1; seed < 20 && !differs; ++seed) {
    again.seed = seed;
    for (int i = 0; i < 5; ++i)
      differs = differs || again.MigrationSources(i) != o.MigrationSources(i);
  }
  EXPECT_TRUE(differs) << "the random topology should depend on the seed";
  EXPECT_TRUE(IslandOptions(1).MigrationSources(0).empty());
}

TEST(GaIslands, SameRunWhateverTheEvaluatorItsThreadsAndTheCompletionOrder) {
  const HashFitness fitness;
  for (MigrationTopology t : kTopologies) {
    SCOPED_TRACE(TopologyName(t));
    GaOptions o = IslandOptions(4);
    o.topology = t;
    o.island_stall_generations = 4;
    InlineEvaluator inline_ev(fitness);
    const RunRecord reference = RunWith(&inline_ev, o);
    ThreadPoolEvaluator pool2(fitness, 2), pool4(fitness, 4);
    ShuffledEvaluator shuffled(&pool4);
    for (BatchEvaluator* ev : std::initializer_list<BatchEvaluator*>{&pool2, &shuffled})
      ExpectSameRun(reference, RunWith(ev, o));
    int migrations = 0, immigrants = 0;
    for (const GenerationSummary& g : reference.state.log) {
      ASSERT_EQ(g.islands.size(), 4u);
      EXPECT_EQ(g.migrated, g.generation > 0 && g.generation % 3 == 0) << g.generation;
      migrations += g.migrated;
      for (const IslandSummary& i : g.islands) immigrants += i.immigrants;
      double best = INFINITY;
      for (const IslandSummary& i : g.islands) best = std::min(best, i.best_cost);
      EXPECT_LE(g.best_cost, best) << "the generation's best is over the islands";
    }
    EXPECT_EQ(migrations, 8);
    EXPECT_GT(immigrants, 0);
  }
}

/// Passes each batch to `inner` and keeps its indices and genomes.
struct RecordingEvaluator final : BatchEvaluator {
  explicit RecordingEvaluator(BatchEvaluator* in) : inner(in) {}
  void Evaluate(const EvalBatch& b, std::span<FitnessResult> out) override {
    indices.emplace_back(b.indices.begin(), b.indices.end());
    genomes.emplace_back(b.genomes.begin(), b.genomes.end());
    inner->Evaluate(b, out);
  }
  BatchEvaluator* inner;
  std::vector<std::vector<int>> indices;
  std::vector<std::vector<Genome>> genomes;
};

TEST(GaIslands, OneDispatchPerGenerationWithEveryIslandsIndividuals) {
  const HashFitness fitness;
  InlineEvaluator inner(fitness);
  RecordingEvaluator counting(&inner);
  GaOptions o = IslandOptions(4);
  o.max_generations = 5;
  GeneticAlgorithm ga(o, &counting);
  ga.Run();
  const auto& batches = counting.indices;
  ASSERT_EQ(batches.size(), 6u);
  EXPECT_EQ(batches[0].size(), 240u);  // 4 × 60
  for (size_t g = 1; g < 6; ++g) {
    ASSERT_EQ(batches[g].size(), 120u);  // 4 × 30 offspring
    EXPECT_EQ(batches[g][0], 30);        // island 0, slots 30 … 59
    EXPECT_EQ(batches[g][30], 90);       // island 1 starts at 60 + 30
    EXPECT_EQ(batches[g][119], 239);
  }
}

TEST(GaIslands, MultiStartIsIndependentRunsOnTheIslandStreams) {
  // Migration interval 0: island k is exactly the one-island GA seeded StreamSeed(seed, k), at
  // mutation probability island_mutation[k] when the islands have their own rates.
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  for (const std::vector<double>& rates :
       {std::vector<double>{}, std::vector<double>{0.002, 0.05, 0.2}}) {
    SCOPED_TRACE("island_mutation of " + std::to_string(rates.size()));
    GaOptions o = IslandOptions(3);
    o.migration_interval = 0;
    o.stall_generations = 0;
    o.island_mutation = rates;
    const RunRecord multi = RunWith(&ev, o);
    double best = INFINITY;
    int best_island = -1;
    for (int k = 0; k < 3; ++k) {
      GaOptions one = SmallOptions(StreamSeed(o.seed, k));
      one.stall_generations = 0;
      one.mutation_probability = o.MutationProbability(k);
      const RunRecord single = RunWith(&ev, one);
      const IslandState &x = single.state.islands[0], &y = multi.state.islands[k];
      EXPECT_EQ(x.population, y.population) << "island " << k;
      ASSERT_EQ(x.fitness.size(), y.fitness.size());
      for (size_t i = 0; i < x.fitness.size(); ++i)
        EXPECT_EQ(x.fitness[i].cost, y.fitness[i].cost) << k << " " << i;
      EXPECT_EQ(x.rng, y.rng) << "island " << k;
      if (single.summary.best_fitness.cost < best)
        best = single.summary.best_fitness.cost, best_island = k;
    }
    EXPECT_EQ(multi.summary.best_fitness.cost, best);
    EXPECT_EQ(multi.summary.best_island, best_island);
    for (const GenerationSummary& g : multi.state.log) EXPECT_FALSE(g.migrated);
  }
}

TEST(GaIslands, EachIslandMutatesAtItsOwnRate) {
  // (Island k at its own rate is the one-island run at that rate: MultiStartIsIndependentRuns….)
  // The same rate for every island is the run without island_mutation; different rates differ.
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  GaOptions o = IslandOptions(3);
  const RunRecord uniform = RunWith(&ev, o);
  o.island_mutation.assign(3, o.mutation_probability);
  const RunRecord same_rate = RunWith(&ev, o);
  EXPECT_EQ(Digest(same_rate.state, same_rate.summary), Digest(uniform.state, uniform.summary));
  o.island_mutation[1] = 0.05;
  const RunRecord mixed = RunWith(&ev, o);
  EXPECT_EQ(uniform.state.log[0], mixed.state.log[0]) << "generation 0 draws no mutation";
  EXPECT_NE(uniform.state.islands[1].population, mixed.state.islands[1].population);
  // With migration: the same run whatever the evaluator's threads and the completion order.
  GaOptions migrating = IslandOptions(4);
  migrating.island_mutation = {0.01, 0.02, 0.03, 0.05};
  ThreadPoolEvaluator pool(fitness, 3);
  ShuffledEvaluator shuffled(&pool);
  ExpectSameRun(RunWith(&ev, migrating), RunWith(&shuffled, migrating));
}

TEST(GaIslands, MigrantsReplaceTheWorstWhenBetter) {
  // Ring of 2 at every generation: after a migration, each island holds the two best of the
  // other (they are better than its worst, penalised or error-cost individuals).
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  GaOptions o = IslandOptions(2);
  o.migration_interval = 1;
  GeneticAlgorithm ga(o, &ev);
  ga.Initialize();
  ga.Step();
  const GenerationSummary& g = ga.state().log.back();
  ASSERT_TRUE(g.migrated);
  for (int k = 0; k < 2; ++k) {
    const IslandState& is = ga.state().islands[k];
    EXPECT_EQ(g.islands[k].immigrants, 2);
    EXPECT_TRUE(std::is_sorted(
        is.fitness.begin(), is.fitness.end(),
        [](const FitnessResult& a, const FitnessResult& b) { return a.cost < b.cost; }));
    EXPECT_EQ(g.islands[k].best_cost, is.fitness[0].cost);
  }
  // The other island's top two (after its breeding, before the exchange) are in each island: the
  // exchange takes copies, so both islands hold both.
  const IslandState &a = ga.state().islands[0], &b = ga.state().islands[1];
  EXPECT_NE(std::find(b.population.begin(), b.population.end(), a.population[0]),
            b.population.end());
  EXPECT_NE(std::find(a.population.begin(), a.population.end(), b.population[0]),
            a.population.end());
}

TEST(GaIslands, MarginHearsOnlySourcesBetterByTheMargin) {
  // Ring of 2 at every generation, as above, with a margin: an island takes migrants only from a
  // source whose best is below its own by more than margin · |its best|.
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  for (double margin : {1e-12, 0.999}) {
    GaOptions o = IslandOptions(2);
    o.migration_interval = 1;
    o.migration_margin = margin;
    GeneticAlgorithm ga(o, &ev);
    ga.Initialize();
    // The islands' bests before the exchange: run the same generation without migration.
    GaOptions apart = o;
    apart.migration_interval = 0;
    GeneticAlgorithm alone(apart, &ev);
    alone.Initialize();
    alone.Step();
    const double b0 = alone.state().islands[0].fitness[0].cost,
                 b1 = alone.state().islands[1].fitness[0].cost;
    ASSERT_GT(b0, 0);
    ASSERT_GT(b1, 0);
    ASSERT_NE(b0, b1);
    const GenerationSummary& g = ga.Step();
    ASSERT_TRUE(g.migrated);
    const int better = b0 < b1 ? 0 : 1, worse = 1 - better;
    // The better island never hears the worse one; the worse hears the better only if the gap
    // exceeds the margin (a tiny margin: yes; 0.999: no, the costs are not a thousandfold apart).
    EXPECT_EQ(g.islands[better].immigrants, 0) << margin;
    const double lo = std::min(b0, b1), hi = std::max(b0, b1);
    const bool heard = lo < hi - margin * hi;
    EXPECT_EQ(g.islands[worse].immigrants, heard ? 2 : 0) << margin;
    EXPECT_EQ(heard, margin < 0.5) << "the two margins test both sides of the gate";
    // An island that hears nothing is the island of the run without migration, bit for bit.
    EXPECT_EQ(ga.state().islands[better].population, alone.state().islands[better].population);
  }
}

/// A run stopped after each of `stops` generations (on `before`), its state restored into a new GA
/// (on `after`) and run to the end, is `reference` bit for bit.
void ExpectResumesBitForBit(const RunRecord& reference, const GaOptions& o, BatchEvaluator* before,
                            BatchEvaluator* after, std::initializer_list<int> stops) {
  for (int stop : stops) {
    SCOPED_TRACE("checkpoint after generation " + std::to_string(stop));
    GaState checkpoint;
    {
      GeneticAlgorithm first(o, before);
      first.Initialize();
      for (int g = 0; g < stop; ++g) first.Step();
      checkpoint = first.state();
    }
    GeneticAlgorithm second(o, after);
    second.RestoreState(checkpoint);
    while (!second.CheckTermination()) second.Step();
    ExpectSameRun(reference, {second.state(), second.MakeSummary(*second.CheckTermination())});
  }
}

TEST(GaIslands, BroadcastReachesTheIslandsLedByItsMarginBetweenMigrations) {
  // A ring every 4 generations, ungated, and a broadcast every generation from every island
  // better by more than the broadcast's margin: at generations 1, 2, 3 the broadcast (every other
  // island is a source, through its gate), at 4 the ring (one source, no gate).
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  for (double margin : {1e-12, 0.999}) {
    SCOPED_TRACE(margin);
    GaOptions o = IslandOptions(3);
    o.migration_interval = 4;
    o.broadcast_interval = 1;
    o.broadcast_margin = margin;
    o.max_generations = 4;
    GeneticAlgorithm ga(o, &ev);
    ga.Initialize();
    for (int g = 1; g <= 4; ++g) {
      // The islands' bests before the exchange: the same generation from the same state without
      // one.
      GaOptions apart = o;
      apart.migration_interval = 0;
      apart.broadcast_interval = 0;
      GeneticAlgorithm alone(apart, &ev);
      alone.RestoreState(ga.state());
      alone.Step();
      std::vector<double> before;
      for (const IslandState& is : alone.state().islands) before.push_back(is.fitness[0].cost);
      const GenerationSummary& s = ga.Step();
      ASSERT_TRUE(s.migrated) << g;
      // What island k takes from `from`: the best two of their top two (ties: source order),
      // replacing its worst two pair by pair while strictly better.
      const auto expected = [&](int k, const std::vector<int>& from) {
        std::vector<double> in;
        for (int j : from)
          for (int r = 0; r < 2; ++r) in.push_back(alone.state().islands[j].fitness[r].cost);
        std::stable_sort(in.begin(), in.end());
        const auto& own = alone.state().islands[k].fitness;
        int taken = 0;
        while (taken < 2 && taken < static_cast<int>(in.size()) &&
               in[taken] < own[own.size() - 1 - taken].cost)
          ++taken;
        return taken;
      };
      for (int k = 0; k < 3; ++k) {
        std::vector<int> from;
        if (g == 4) {
          from = {(k + 2) % 3};  // the ring: island k hears k − 1 whatever its best
        } else {
          for (int j = 0; j < 3; ++j)
            if (j != k && before[j] < before[k] - margin * std::abs(before[k])) from.push_back(j);
        }
        EXPECT_EQ(s.islands[k].immigrants, expected(k, from))
            << "island " << k << ", generation " << g;
        if (from.empty()) {  // an island that hears nothing is the island of the run without
                             // migration
          EXPECT_EQ(ga.state().islands[k].population, alone.state().islands[k].population);
        }
      }
    }
    int heard = 0;
    for (const GenerationSummary& s : ga.state().log)
      if (s.generation < 4)
        for (const IslandSummary& i : s.islands) heard += i.immigrants;
    if (margin < 0.5) {
      EXPECT_GT(heard, 0) << "a tiny margin lets the better islands through";
    } else {
      EXPECT_EQ(heard, 0) << "the costs are not a thousandfold apart";
    }
  }
  // Without a broadcast interval the margin is not used: the run is the run before broadcasts.
  GaOptions plain = IslandOptions(3), unused = plain;
  unused.broadcast_margin = 0.7;
  ExpectSameRun(RunWith(&ev, plain), RunWith(&ev, unused));
}

TEST(GaIslands, BroadcastRunIsTheSameWhateverTheEvaluatorAndResumesFromACheckpoint) {
  const HashFitness fitness;
  InlineEvaluator inline_ev(fitness);
  GaOptions o = IslandOptions(4);
  o.migration_interval = 6;  // the ring at 6, the broadcast at 2, 4, 8, 10, …
  o.broadcast_interval = 2;
  o.broadcast_margin = 1e-9;
  o.island_mutation = {0.01, 0.02, 0.03, 0.05};
  const RunRecord reference = RunWith(&inline_ev, o);
  ThreadPoolEvaluator pool4(fitness, 4);
  ShuffledEvaluator shuffled(&pool4);
  ExpectSameRun(reference, RunWith(&shuffled, o));
  int broadcasts = 0, immigrants = 0;
  for (const GenerationSummary& g : reference.state.log) {
    EXPECT_EQ(g.migrated, g.generation > 0 && g.generation % 2 == 0) << g.generation;
    broadcasts += g.migrated && g.generation % 6 != 0;
    for (const IslandSummary& i : g.islands) immigrants += g.generation % 6 != 0 ? i.immigrants : 0;
  }
  EXPECT_GT(broadcasts, 0);
  EXPECT_GT(immigrants, 0) << "the broadcasts moved individuals";
  // Another setting is another run.
  GaOptions none = o;
  none.broadcast_interval = 0;
  const RunRecord without = RunWith(&inline_ev, none);
  EXPECT_NE(Digest(without.state, without.summary), Digest(reference.state, reference.summary));
  ExpectResumesBitForBit(reference, o, &inline_ev, &shuffled,
                         {1, 2, 3});  // before, at and after a broadcast
}

TEST(GaIslands, StalledIslandRestartsFromMigrantsAndFreshIndividuals) {
  const ConstantFitness fitness;  // nothing ever improves: every island stalls
  InlineEvaluator ev(fitness);
  GaOptions o = IslandOptions(3);
  o.migration_interval = 100;  // no migration in this run, but migrants for restarts
  o.island_stall_generations = 2;
  o.stall_generations = 0;
  o.max_generations = 6;
  GeneticAlgorithm ga(o, &ev);
  ga.Initialize();
  ga.Step();
  ga.Step();  // generation 2: every island at stall 2
  for (const IslandState& is : ga.state().islands) EXPECT_EQ(is.stall, 2);
  const GaState before = ga.state();
  const GenerationSummary& g3 = ga.Step();
  // Each island: the two best of its ring source (kept, not evaluated) + 58 fresh ones.
  EXPECT_EQ(g3.evaluations, 3 * 58);
  for (int k = 0; k < 3; ++k) {
    const IslandState& is = ga.state().islands[k];
    const IslandState& src = before.islands[(k + 2) % 3];
    EXPECT_TRUE(g3.islands[k].restarted);
    EXPECT_EQ(g3.islands[k].stall, 0);
    EXPECT_EQ(is.restarts, 1);
    // Equal costs rank by index: the migrants first, in the source's order.
    EXPECT_EQ(is.population[0], src.population[0]);
    EXPECT_EQ(is.population[1], src.population[1]);
    EXPECT_EQ(
        std::find(is.population.begin() + 2, is.population.end(), before.islands[k].population[0]),
        is.population.end())
        << "the fresh individuals are new draws";
  }
  // The job's stall is over the islands' best, and a restart does not reset it.
  EXPECT_EQ(g3.stall, 3);
  EXPECT_FALSE(g3.improved);
  // One island restarts from fresh individuals only.
  GaOptions one = SmallOptions();
  one.island_stall_generations = 1;
  one.stall_generations = 0;
  GeneticAlgorithm single(one, &ev);
  single.Initialize();
  single.Step();
  EXPECT_EQ(single.Step().evaluations, 60);
  EXPECT_TRUE(single.state().log.back().islands.empty());
  EXPECT_EQ(single.state().islands[0].restarts, 1);
}

TEST(GaIslands, CheckpointAtAndAroundAMigrationResumesBitForBit) {
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  GaOptions o = IslandOptions(4);
  o.island_stall_generations = 3;
  o.island_mutation = {0.01, 0.02, 0.03, 0.05};
  const RunRecord reference = RunWith(&ev, o);
  ExpectResumesBitForBit(reference, o, &ev, &ev,
                         {2, 3, 4});  // before, at (interval 3) and after a migration
  GaState bad = reference.state;
  bad.islands.pop_back();
  GeneticAlgorithm third(o, &ev);
  try {
    third.RestoreState(bad);
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("state.islands.size() = 3: must equal islands = 4"),
              std::string::npos)
        << e.what();
  }
}

// ------------------------------------------------------------------------------------------
// Output moves (file comment of ga.h, 9.)

// A move for the tests: the parent with three bits flipped at drawn positions (a function of the
// parent and the draws, as a move must be); it records what it was given and what it made.
struct FlipMove {
  std::shared_ptr<std::vector<std::pair<Genome, Genome>>> calls =
      std::make_shared<std::vector<std::pair<Genome, Genome>>>();
  void operator()(const Genome& parent, Rng& rng, std::span<Genome> children) const {
    for (Genome& child : children) {
      child.bits = parent.bits;
      for (int i = 0; i < 3; ++i) child.bits[rng.UniformBelow(child.bits.size())] ^= 1u;
      calls->emplace_back(parent, child);
    }
  }
};

RunRecord RunWithMove(BatchEvaluator* evaluator, const GaOptions& options,
                      GeneticAlgorithm::Move move) {
  GeneticAlgorithm ga(options, evaluator);
  if (move) ga.SetMove(std::move(move));
  RunRecord r;
  r.summary = ga.Run();
  r.state = ga.state();
  return r;
}

TEST(GaOutputMoves, NoneWithOneIslandSixteenPercentWithSeveralUnlessGiven) {
  GaOptions o;
  EXPECT_EQ(o.output_moves, GaOptions::kAutoOutputMoves);
  EXPECT_EQ(o.OutputMoves(), 0) << "one island: the paper's GA";
  o.islands = 4;
  EXPECT_EQ(o.OutputMoves(), 32) << "16 % of 200 offspring";
  o.population_size = 30;
  EXPECT_EQ(o.OutputMoves(), 2) << "16 % of 15, rounded";
  o.population_size = 400;
  o.output_moves = 0;
  EXPECT_EQ(o.OutputMoves(), 0);
  o.islands = 1;
  o.output_moves = 5;
  EXPECT_EQ(o.OutputMoves(), 5);
  EXPECT_TRUE(o.Validate().ok());
  o.output_moves = 200;
  EXPECT_TRUE(o.Validate().ok()) << "every offspring a move";
  o.output_moves = 201;
  EXPECT_EQ(o.Validate().message(),
            "output_moves = 201: must be in [0, population_size − the elite = 200] (-1: 0 with one "
            "island, 16 % of the offspring with several)");
  o.output_moves = -2;
  EXPECT_EQ(o.Validate().message().rfind("output_moves = -2: must be in [0, ", 0), 0u);
}

TEST(GaOutputMoves, TheLastOffspringOfEachIslandAreMovesOfItsBest) {
  const HashFitness fitness;
  InlineEvaluator inner(fitness);
  RecordingEvaluator recording(&inner);
  GaOptions o = IslandOptions(3);
  o.output_moves = 4;
  const FlipMove move;
  GeneticAlgorithm ga(o, &recording);
  ga.SetMove(move);
  ga.Initialize();
  EXPECT_TRUE(move.calls->empty()) << "generation 0 is drawn uniformly";
  for (int g = 1; g <= 6; ++g) {
    std::vector<Genome> bests;
    for (const IslandState& is : ga.state().islands) bests.push_back(is.population.front());
    move.calls->clear();
    ga.Step();
    ASSERT_EQ(move.calls->size(), 12u) << "4 per island, island by island";
    const std::vector<Genome>& genomes = recording.genomes.back();
    const std::vector<int>& indices = recording.indices.back();
    ASSERT_EQ(genomes.size(), 90u) << "3 × 30 offspring: the moves replace bred ones";
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 4; ++j) {
        const auto& [parent, child] = (*move.calls)[4 * k + j];
        EXPECT_EQ(parent.bits, bests[k].bits) << "generation " << g << " island " << k;
        const size_t at = 30 * k + 26 + j;  // island k's slots 56 … 59 of its 30 … 59
        EXPECT_EQ(indices[at], 60 * k + 56 + j);
        EXPECT_EQ(genomes[at].bits, child.bits);
      }
  }
}

TEST(GaOutputMoves, WithoutAMoveOrWithNoneEveryOffspringIsBred) {
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  GaOptions o = IslandOptions(3);  // auto: 5 moves per island (16 % of 30) when a move is set
  const RunRecord bred = RunWith(&ev, o);
  ExpectSameRun(bred, RunWithMove(&ev, o, nullptr));
  GaOptions none = o;
  none.output_moves = 0;
  ExpectSameRun(bred, RunWithMove(&ev, none, FlipMove{}));
  const RunRecord moved = RunWithMove(&ev, o, FlipMove{});
  EXPECT_NE(Digest(moved.state, moved.summary), Digest(bred.state, bred.summary));
  // One island: none by default, the paper's GA draw for draw, with a move set or not.
  const RunRecord one = RunWithMove(&ev, SmallOptions(), FlipMove{});
  EXPECT_EQ(Digest(one.state, one.summary), 0xd70ed114cf6bb092ull);
}

TEST(GaOutputMoves, SameRunWhateverTheEvaluatorAndResumesFromACheckpoint) {
  const HashFitness fitness;
  InlineEvaluator ev(fitness);
  ThreadPoolEvaluator pool(fitness, 3);
  ShuffledEvaluator shuffled(&pool);
  GaOptions o = IslandOptions(4);
  o.output_moves = 6;
  const RunRecord whole = RunWithMove(&ev, o, FlipMove{});
  ExpectSameRun(whole, RunWithMove(&shuffled, o, FlipMove{}));
  GaState saved;
  {
    GeneticAlgorithm first(o, &ev);
    first.SetMove(FlipMove{});
    first.Initialize();
    for (int g = 0; g < 10; ++g) first.Step();
    saved = first.state();
  }
  GeneticAlgorithm second(o, &shuffled);
  second.SetMove(FlipMove{});
  second.RestoreState(saved);
  RunRecord resumed;
  resumed.summary = second.Run();
  resumed.state = second.state();
  ExpectSameRun(whole, resumed);
}

// The repair (file comment 10.): every fresh genome of every generation, seeds and drawn ones
// included, passes through it before the batch is evaluated; the run stays a function of the
// options and seed (a repair is a function of the genome alone).
TEST(GaRepair, EveryEvaluatedGenomeIsRepairedFirst) {
  const HashFitness fitness;
  InlineEvaluator inner(fitness);
  const auto repair = [](Genome& g) {  // HashFitness penalises b0 b1 b2 all set: clear b2 there
    if (!(g.bits[0] && g.bits[1] && g.bits[2])) return false;
    g.bits[2] = 0;
    return true;
  };
  const auto run = [&](BatchEvaluator* ev, int64_t* repaired) {
    GeneticAlgorithm ga(IslandOptions(3), ev);
    ga.SetRepair(repair);
    RunRecord r;
    r.summary = ga.Run();
    r.state = ga.state();
    *repaired = ga.repaired();
    return r;
  };
  RecordingEvaluator recording(&inner);
  int64_t repaired = 0;
  const RunRecord with = run(&recording, &repaired);
  int64_t evaluated = 0;
  for (const auto& batch : recording.genomes)
    for (const Genome& g : batch) {
      EXPECT_FALSE(g.bits[0] && g.bits[1] && g.bits[2]);
      ++evaluated;
    }
  EXPECT_EQ(evaluated, with.summary.evaluations);
  EXPECT_GT(repaired, 0) << "an eighth of uniform genomes have b0 b1 b2 set";
  for (const GenerationSummary& g : with.state.log)
    EXPECT_EQ(g.failure_reasons.count("unbounded hysteresis"), 0u) << "generation " << g.generation;
  int64_t again = 0;
  ExpectSameRun(with, run(&inner, &again));
  EXPECT_EQ(again, repaired);
}

}  // namespace islands

}  // namespace
}  // namespace pz::opt
