// The binary GA: options validation, the generator (MT19937-64 and its portable mappings),
// determinism across evaluators and thread counts and checkpoint/restore, elitism, termination
// (stall, max generations, target, cancel), failure accounting without NaN, and two toy problems
// that must converge (OneMax on 1415 bits; fitting a target HGANN network through the codec).
#include "opt/ga.h"

#include <gtest/gtest.h>

#include <algorithm>
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
    return {static_cast<double>(std::count(g.bits.begin(), g.bits.end(), 0)), FitnessStatus::kOk, ""};
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
    std::shuffle(perm.begin(), perm.end(), std::mt19937(static_cast<unsigned>(batch.generation * 7919 + 1)));
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

TEST(Rng, MatchesStdMt19937_64) {
  for (uint64_t seed : {5489ull, 0ull, 42ull, 0xFFFFFFFFFFFFFFFFull}) {
    Rng r(seed);
    std::mt19937_64 ref(seed);
    for (int i = 0; i < 20000; ++i) ASSERT_EQ(r.NextU64(), ref()) << "seed " << seed << " draw " << i;
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
  EXPECT_TRUE(o.Validate().ok());
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
  EXPECT_EQ(error([](GaOptions& o) { o.mutation_probability = 1.5; }).rfind("mutation_probability", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.crossover_probability = -1; }).rfind("crossover_probability", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.max_generations = -1; }).rfind("max_generations", 0), 0u);
  EXPECT_EQ(error([](GaOptions& o) { o.stall_generations = -1; }).rfind("stall_generations", 0), 0u);
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
  ASSERT_EQ(a.state.population.size(), b.state.population.size());
  for (size_t i = 0; i < a.state.population.size(); ++i) {
    ASSERT_EQ(a.state.population[i], b.state.population[i]) << "individual " << i;
    ASSERT_EQ(a.state.fitness[i].cost, b.state.fitness[i].cost) << "individual " << i;
    ASSERT_EQ(a.state.fitness[i].status, b.state.fitness[i].status);
    ASSERT_EQ(a.state.fitness[i].reason, b.state.fitness[i].reason);
  }
  EXPECT_EQ(a.state.rng, b.state.rng);
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
  EXPECT_NE(other.state.population[0], reference.state.population[0]);
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
  bad.population[3].bits.pop_back();
  GeneticAlgorithm third(options, &ev);
  try {
    third.RestoreState(bad);
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("state.population[3].bits.size()"), std::string::npos) << e.what();
  }
  bad = checkpoint;
  std::swap(bad.fitness[0], bad.fitness[59]);
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
  EXPECT_EQ(st.best, st.population[0]);
  EXPECT_EQ(st.best_fitness.cost, seen.back().best_cost);
  EXPECT_EQ(HashFitness{}.Evaluate(st.best).cost, st.best_fitness.cost);
  EXPECT_TRUE(std::is_sorted(st.fitness.begin(), st.fitness.end(),
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
    EXPECT_TRUE(std::isfinite(s.best_cost) && std::isfinite(s.mean_cost) && std::isfinite(s.worst_cost))
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
  for (const FitnessResult& f : ga.state().fitness) {
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
  EXPECT_EQ(ga.state().population[0], all_ones);
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

}  // namespace
}  // namespace pz::opt
