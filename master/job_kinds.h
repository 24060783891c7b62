// Job kinds: how a job spec's problem becomes a genome layout and a FitnessFunction. The master
// (validation, in-process runs) and every worker use the same registry, so a job kind registered
// here is available everywhere. Built in: "synthetic" and "hgann" (master/hgann_job.h). A new kind:
//
//   pz::master::JobKind k;
//   k.name = "hgann";
//   k.validate = [](const JobSpec& s) { return std::vector<FieldViolation>{...}; };
//   k.layout = [](const JobSpec& s, GenomeLayout* l) { l->bits = ...; return pz::Status::Ok(); };
//   k.make_fitness = [](const JobSpec& s, std::unique_ptr<FitnessFunction>* f) { ...; };
//   pz::master::JobKindRegistry::Default().Register(std::move(k));
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "master/evaluator.h"
#include "master/job_spec.h"
#include "model/status.h"

namespace pz::master {

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
  std::function<Status(const JobSpec&, std::unique_ptr<FitnessFunction>*)> make_fitness;
  /// Optional: describes a genome for the generation log (e.g. the decoded network's shape).
  std::function<std::string(const JobSpec&, const Genome&)> describe;
};

class JobKindRegistry {
 public:
  /// The process-wide registry, with the built-in kinds registered.
  static JobKindRegistry& Default();

  void Register(JobKind kind);  ///< replaces a kind of the same name
  /// nullptr when unknown. The pointer stays valid while the kind is not replaced.
  const JobKind* Find(const std::string& name) const;

  /// Generic + kind-specific validation (both, so that every violated field is answered at once);
  /// empty when the spec is acceptable.
  std::vector<FieldViolation> Validate(const JobSpec& spec) const;
  Status Layout(const JobSpec& spec, GenomeLayout* layout) const;
  Status MakeFitness(const JobSpec& spec, std::unique_ptr<FitnessFunction>* out) const;

 private:
  mutable std::mutex mu_;
  std::map<std::string, std::shared_ptr<const JobKind>> kinds_;
};

/// The built-in "synthetic" kind (null / function cost, optional sleep, optional crash prefix).
JobKind SyntheticJobKind();

}  // namespace pz::master
