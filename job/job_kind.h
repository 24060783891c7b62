// Job kinds: how a job spec's problem becomes a genome layout and a FitnessFunction. Each kind
// lives with its problem (hgann/, diagnose/, complete/); the one list of them is kinds/kinds.h,
// which the master, the workers, the fuzzer and the client all use, so a kind added there is
// available everywhere. A kind:
//
//   pz::job::JobKind k;
//   k.name = "hgann";
//   k.validate = [](const JobSpec& s) { return std::vector<FieldViolation>{...}; };
//   k.layout = [](const JobSpec& s, GenomeLayout* l) { l->bits = ...; return pz::Status::Ok(); };
//   k.make_fitness = [](const JobSpec& s, std::unique_ptr<FitnessFunction>* f) { ...; };
//   registry.Register(std::move(k));   // in kinds/kinds.cc
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "opt/evaluator.h"
#include "opt/ga.h"
#include "job/job_spec.h"
#include "job/law_committee.h"
#include "model/network.h"
#include "model/status.h"

namespace pz::job {

/// Shape of the genomes of a job.
struct GenomeLayout {
  int bits = 0;   ///< binary genes
  int reals = 0;  ///< real genes (none so far)
};

struct JobKind {
  std::string name;
  /// Kind-specific checks of a spec whose kind() == name (may be empty).
  std::function<std::vector<FieldViolation>(const JobSpec&)> validate;
  std::function<Status(const JobSpec&, GenomeLayout*)> layout;
  /// Builds the (pure, thread-safe) fitness of a valid spec.
  std::function<Status(const JobSpec&, std::unique_ptr<opt::FitnessFunction>*)> make_fitness;
  /// Optional: describes a genome for the generation log (e.g. the decoded network's shape).
  std::function<std::string(const JobSpec&, const opt::Genome&)> describe;
  /// Optional, for kinds whose genomes are networks: decodes genomes into the networks a client
  /// deploys (with the spec's input normalisation and parameter ranges); fetch returns them.
  std::function<Status(const JobSpec&, std::span<const opt::Genome>, std::vector<model::Network>*)>
      networks;
  /// Optional: the kind's move for the GA's output moves (opt/ga.h, file comment 9.). A kind
  /// without one refuses a spec that asks for output moves.
  std::function<Status(const JobSpec&, opt::GeneticAlgorithm::Move*)> move;
  /// Optional: the kind's repair of fresh genomes (opt/ga.h, file comment 10.), a function of the
  /// spec (null: genomes are evaluated as made).
  std::function<Status(const JobSpec&, opt::GeneticAlgorithm::Repair*)> repair;
  /// Optional: the genomes that fill the first slots of generation 0
  /// (GeneticAlgorithm::Initialize), a function of the spec alone, computed once when a job starts
  /// (the master's job runner, a local rerun): e.g. the hgann kind's trend seeds. None = uniform
  /// bits.
  std::function<Status(const JobSpec&, std::vector<opt::Genome>*)> seeds;
  /// Optional: what the kind's operating-point law's committee says of a job's best genome
  /// (which withheld cases stay open, the next case to measure: the hgann kind with trend seeds),
  /// computed once by the master's job thread when the job ends. NotFound: none for this spec.
  std::function<Status(const JobSpec&, const opt::Genome& best, LawCommittee*)> committee;
};

/// The GA options of a spec's `ga` settings, limits and seed, for genomes of `layout` (what the
/// master's job runner and a client's local rerun of the job both use).
opt::GaOptions ToGaOptions(const JobSpec& spec, const GenomeLayout& layout);

class JobKindRegistry {
 public:
  void Register(JobKind kind);  ///< replaces a kind of the same name
  /// nullptr when unknown. The pointer stays valid while the kind is not replaced.
  const JobKind* Find(const std::string& name) const;

  /// Generic + kind-specific validation (both, so that every violated field is answered at once);
  /// empty when the spec is acceptable.
  std::vector<FieldViolation> Validate(const JobSpec& spec) const;
  Status Layout(const JobSpec& spec, GenomeLayout* layout) const;
  Status MakeFitness(const JobSpec& spec, std::unique_ptr<opt::FitnessFunction>* out) const;
  /// The kind's networks of `genomes`; NotFound for a kind without networks.
  Status Networks(const JobSpec& spec, std::span<const opt::Genome> genomes,
                  std::vector<model::Network>* out) const;
  /// The kind's move for the GA (null when the kind has none: its genomes are only bred).
  Status Move(const JobSpec& spec, opt::GeneticAlgorithm::Move* out) const;
  /// The kind's repair for the GA (null when the kind has none, or the spec asks for none).
  Status Repair(const JobSpec& spec, opt::GeneticAlgorithm::Repair* out) const;
  /// The kind's seeds of generation 0 (empty when the kind has none).
  Status Seeds(const JobSpec& spec, std::vector<opt::Genome>* out) const;
  /// The kind's committee on `best` (JobKind::committee); NotFound for a kind or spec without.
  Status Committee(const JobSpec& spec, const opt::Genome& best, LawCommittee* out) const;

 private:
  mutable std::mutex mu_;
  std::map<std::string, std::shared_ptr<const JobKind>> kinds_;
};

}  // namespace pz::job
