#include "master/job_runner.h"

#include <algorithm>
#include <chrono>

#include "opt/inline_evaluator.h"

namespace pz::master {

using job::GaSettings;
using job::GenomeLayout;
using job::JobKind;
using job::JobKindRegistry;
using job::JobSpec;
using job::LawCommittee;
using opt::BatchEvaluator;
using opt::FitnessFunction;
using opt::GaOptions;
using opt::GaState;
using opt::GaTerminationName;
using opt::GenerationSummary;
using opt::GeneticAlgorithm;
using opt::Genome;
using opt::InlineEvaluator;
using service::GenerationRecord;
using service::JobCheckpoint;
using service::JobState;

JobRunner::JobRunner(std::string job_id, JobSpec spec) : spec_(std::move(spec)) {
  checkpoint_.job_id = std::move(job_id);
}

JobRunner::~JobRunner() = default;

Status JobRunner::Init(const JobKindRegistry& kinds, const JobCheckpoint* resume) {
  GenomeLayout layout;
  kinds_ = &kinds;
  if (Status s = kinds.Layout(spec_, &layout); !s.ok()) return s;
  try {
    ga_ = std::make_unique<GeneticAlgorithm>(ToGaOptions(spec_, layout), &forward_);
    if (const JobKind* k = kinds.Find(spec_.kind()); k && k->describe)
      ga_->SetDescriber(
          [this, describe = k->describe](const Genome& g) { return describe(spec_, g); });
    opt::GeneticAlgorithm::Move move;
    if (Status s = kinds.Move(spec_, &move); !s.ok()) return s;
    if (move) ga_->SetMove(std::move(move));
    opt::GeneticAlgorithm::Repair repair;
    if (Status s = kinds.Repair(spec_, &repair); !s.ok()) return s;
    if (repair) ga_->SetRepair(std::move(repair));
    if (!resume || !resume->optimizer.initialized) {
      if (Status s = kinds.Seeds(spec_, &seeds_); !s.ok()) return s;
    }
    if (resume) {
      ga_->RestoreState(resume->optimizer);
      const std::string id = checkpoint_.job_id;
      checkpoint_ = *resume;
      checkpoint_.job_id = id;
    }
  } catch (const InputError& e) {
    return e.status();
  }
  return Status::Ok();
}

bool JobRunner::Done() const {
  return ga_->state().initialized && ga_->CheckTermination().has_value();
}

const GenerationRecord& JobRunner::Step(BatchEvaluator& evaluator) {
  const auto t0 = std::chrono::steady_clock::now();
  forward_.target = &evaluator;
  const GenerationSummary& s = ga_->state().initialized ? ga_->Step() : ga_->Initialize(seeds_);
  GenerationRecord rec = s;
  if (auto q = s.failure_reasons.find("quarantined"); q != s.failure_reasons.end())
    rec.quarantined = q->second;
  forward_.target = nullptr;
  // The runner keeps the records (checkpoint_.log): the GA's own log would grow by one a generation
  // and be copied with its state at every generation (quadratic in the generations).
  ga_->ClearLog();

  const GaState& st = ga_->state();
  checkpoint_.optimizer = st;
  checkpoint_.best.clear();
  // The best kBestKept over all islands, best first (ties: island, then rank); index = island ·
  // population + rank, the individual's index in the generation's batch (its rank with one island).
  const int n = ga_->options().population_size;
  std::vector<std::pair<int, int>> ranked;  // (island, rank)
  for (size_t k = 0; k < st.islands.size(); ++k)
    for (int r = 0; r < n && r < kBestKept; ++r) ranked.emplace_back(static_cast<int>(k), r);
  std::stable_sort(ranked.begin(), ranked.end(), [&st](const auto& a, const auto& b) {
    return st.islands[a.first].fitness[a.second].cost < st.islands[b.first].fitness[b.second].cost;
  });
  for (size_t i = 0; i < ranked.size() && i < static_cast<size_t>(kBestKept); ++i) {
    const auto [k, r] = ranked[i];
    checkpoint_.best.push_back({k * n + r, st.islands[k].population[r], st.islands[k].fitness[r]});
  }
  checkpoint_.log.push_back(rec);
  checkpoint_.elapsed_s +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (auto t = ga_->CheckTermination()) {
    checkpoint_.state = JobState::kSucceeded;
    checkpoint_.message = GaTerminationName(*t);
    checkpoint_.termination = *t;
    // The kind's committee on the best (hgann with trend seeds), before the final state is saved.
    LawCommittee committee;
    if (kinds_ && !checkpoint_.best.empty()) {
      const Status s = kinds_->Committee(spec_, checkpoint_.best.front().genome, &committee);
      if (s.ok())
        checkpoint_.committee = std::move(committee);
      else if (s.code() != StatusCode::kNotFound)
        checkpoint_.message += " (the law's committee failed: " + s.message() + ")";
    }
  }
  return checkpoint_.log.back();
}

Status RunJobInProcess(const std::string& job_id, const JobSpec& spec, const JobKindRegistry& kinds,
                       JobCheckpoint* out) {
  std::unique_ptr<FitnessFunction> fitness;
  if (Status s = kinds.MakeFitness(spec, &fitness); !s.ok()) return s;
  InlineEvaluator eval(*fitness, spec.limits.penalty_cost);
  JobRunner runner(job_id, spec);
  if (Status s = runner.Init(kinds); !s.ok()) return s;
  while (!runner.Done()) runner.Step(eval);
  *out = runner.checkpoint();
  return Status::Ok();
}

}  // namespace pz::master
