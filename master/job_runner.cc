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
  if (Status s = kinds.Layout(spec_, &layout); !s.ok()) return s;
  try {
    ga_ = std::make_unique<GeneticAlgorithm>(ToGaOptions(spec_, layout), &forward_);
    if (const JobKind* k = kinds.Find(spec_.kind()); k && k->describe)
      ga_->SetDescriber([this, describe = k->describe](const Genome& g) { return describe(spec_, g); });
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
  const GenerationSummary& s = ga_->state().initialized ? ga_->Step() : ga_->Initialize();
  GenerationRecord rec = s;
  if (auto q = s.failure_reasons.find("quarantined"); q != s.failure_reasons.end()) rec.quarantined = q->second;
  forward_.target = nullptr;

  const GaState& st = ga_->state();
  checkpoint_.optimizer = st;
  checkpoint_.optimizer.log.clear();
  checkpoint_.best.clear();
  for (size_t i = 0; i < st.population.size() && i < static_cast<size_t>(kBestKept); ++i)
    checkpoint_.best.push_back({static_cast<int>(i), st.population[i], st.fitness[i]});
  checkpoint_.log.push_back(rec);
  checkpoint_.elapsed_s +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (auto t = ga_->CheckTermination()) {
    checkpoint_.state = JobState::kSucceeded;
    checkpoint_.message = GaTerminationName(*t);
  }
  return checkpoint_.log.back();
}

Status RunJobInProcess(const std::string& job_id, const JobSpec& spec,
                       const JobKindRegistry& kinds, JobCheckpoint* out) {
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
