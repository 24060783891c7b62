#include "hgann/identify.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include "hgann/loop_repair.h"
#include "hgann/output_move.h"
#include "model/chromosome.h"
#include "opt/thread_pool_evaluator.h"

namespace pz::hgann {

std::optional<model::ParameterRanges> RangesPreset(std::string_view name) {
  if (name.empty() || name == "default") return model::ParameterRanges{};
  if (name == "paper") return model::ParameterRanges::PaperTable3();
  return std::nullopt;
}

std::optional<SearchSettings> SearchPreset(std::string_view name) {
  if (name.empty()) return std::nullopt;  // `--preset ""`: a name is asked for
  return job::HgannSearchPreset(name);
}

double PaperTable8Pi(double v, double f) {
  static const std::map<std::pair<int, int>, double> table = {
      {{375, 25}, 1.42}, {{375, 50}, 2.08}, {{375, 100}, 2.38},
      {{500, 25}, 2.49}, {{500, 50}, 1.96}, {{500, 100}, 1.51},
      {{750, 25}, 5.64}, {{750, 50}, 3.23}, {{750, 100}, 6.78}};
  const int vi = static_cast<int>(std::lround(v)), fi = static_cast<int>(std::lround(f * 100));
  if (std::abs(v - vi) > 1e-9 || std::abs(f * 100 - fi) > 1e-9) return std::nan("");
  auto it = table.find({vi, fi});
  return it == table.end() ? std::nan("") : it->second;
}

std::optional<LawCommittee> RunCommittee(const HgannFitness& fitness,
                                         const std::optional<TrendSeeds>& seeds,
                                         const model::Network& best,
                                         const std::vector<std::pair<double, double>>& candidates,
                                         int threads) {
  if (!seeds || !seeds->law.ok) return std::nullopt;
  CommitteeOptions o;
  o.threads = std::max(1, threads);
  o.kept = &best;
  o.candidates = candidates;
  return CommitteeOf(fitness, seeds->law, o);
}

IdentifyResult RunIdentify(
    const IdentifyOptions& options, const io::CaseSet& set, const HgannFitness& fitness,
    const std::function<void(const opt::GenerationSummary&)>& on_generation) {
  opt::GaOptions ga = options.ga;
  ga.genome_bits = model::kChromosomeBits;
  ga.error_cost = fitness.penalty_cost();
  opt::ThreadPoolEvaluator evaluator(fitness, options.threads, fitness.penalty_cost());
  opt::GeneticAlgorithm algorithm(ga, &evaluator);
  algorithm.SetDescriber([](const opt::Genome& g) { return model::DescribeChromosome(g.bits); });
  if (HgannOutputMoves(ga, fitness.config().spread_penalty) > 0)
    algorithm.SetMove(OutputMove(fitness.config()));  // the hgann job kind's move (hgann_job.cc)
  if (options.repair_loops) algorithm.SetRepair(LoopRepair(fitness.config()));
  if (on_generation) algorithm.AddGenerationCallback(on_generation);

  IdentifyResult r;
  if (options.trend_seeds) {
    // As the hgann job kind's seeds (hgann_job.cc): the same genomes whatever the thread count.
    TrendSeedOptions so;
    so.threads = std::max(1, options.threads > 0 ? options.threads : 2);
    r.seeds = MakeTrendSeeds(fitness, so);
    algorithm.Initialize(r.seeds->genomes);
  }
  r.summary = algorithm.Run();
  r.repaired = algorithm.repaired();
  r.log = algorithm.state().log;
  r.best.network = fitness.Decode(r.summary.best);
  r.best.chromosome = r.summary.best.bits;
  auto& p = r.best.provenance;
  p.job_id = options.job_id;
  p.seed = ga.seed;
  p.generation = r.summary.best_generation;
  p.fitness = r.summary.best_fitness.cost;
  p.created_unix_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  p.piezoid_version = PIEZOID_VERSION;
  for (const auto* c : set.Training())
    p.training_cases.push_back("case" + std::to_string(c->number));
  r.cases = fitness.EvaluateCases(r.best.network);
  // The same thread count as the seeds' (the committee's Jacobian is the same whatever it is).
  r.committee = RunCommittee(fitness, r.seeds, r.best.network, options.next_candidates,
                             std::max(1, options.threads > 0 ? options.threads : 2));
  return r;
}

}  // namespace pz::hgann
