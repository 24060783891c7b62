#include "kinds/kinds.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "complete/job_kind.h"
#include "hgann/hgann_job.h"

namespace pz::kinds {

using job::GenomeLayout;
using job::JobKind;
using job::JobSpec;
using job::SyntheticProblem;
using opt::FitnessFunction;
using opt::FitnessResult;
using opt::FitnessStatus;
using opt::Genome;

namespace {

/// Synthetic fitness: optional sleep, then a cheap deterministic function of the genome (a
/// weighted bit count with weights from a fixed hash, plus a coupling term), or 0.
class SyntheticFitness final : public FitnessFunction {
 public:
  explicit SyntheticFitness(SyntheticProblem p) : p_(std::move(p)) {}

  FitnessResult Evaluate(const Genome& g) const override {
    if (static_cast<int>(g.bits.size()) != p_.genome_bits)
      return {0, FitnessStatus::kError,
              "genome has " + std::to_string(g.bits.size()) + " bits, expected " +
                  std::to_string(p_.genome_bits)};
    if (!p_.crash_prefix.empty()) {
      bool match = true;
      for (size_t i = 0; i < p_.crash_prefix.size() && match; ++i)
        match = g.bits[i] == (p_.crash_prefix[i] == '1');
      if (match) _exit(86);  // the test aid: an individual that kills its evaluator
    }
    if (p_.sleep_ms > 0)
      std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(p_.sleep_ms));
    if (p_.cost == SyntheticProblem::Cost::kNull) return {};
    double cost = 0;
    for (size_t i = 0; i < g.bits.size(); ++i) {
      uint64_t h = (i + 1) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 31;
      h *= 0xBF58476D1CE4E5B9ull;
      h ^= h >> 29;
      double w = static_cast<double>(h >> 11) * 0x1.0p-53;  // [0, 1)
      int target = (h >> 7) & 1;
      if (g.bits[i] != target) cost += 0.5 + w;
      if (i > 0 && g.bits[i] != g.bits[i - 1]) cost += 0.01 * w;
    }
    return {std::sqrt(cost), FitnessStatus::kOk, {}};
  }

 private:
  SyntheticProblem p_;
};

}  // namespace

JobKind SyntheticJobKind() {
  JobKind k;
  k.name = "synthetic";
  k.validate = [](const JobSpec&) { return std::vector<job::FieldViolation>{}; };
  k.layout = [](const JobSpec& s, GenomeLayout* l) {
    l->bits = std::get<SyntheticProblem>(s.problem).genome_bits;
    l->reals = 0;
    return Status::Ok();
  };
  k.make_fitness = [](const JobSpec& s, std::unique_ptr<FitnessFunction>* f) {
    *f = std::make_unique<SyntheticFitness>(std::get<SyntheticProblem>(s.problem));
    return Status::Ok();
  };
  return k;
}

const job::JobKindRegistry& All() {
  static const job::JobKindRegistry* registry = [] {
    auto* r = new job::JobKindRegistry;
    r->Register(SyntheticJobKind());
    r->Register(hgann::HgannJobKind());
    r->Register(complete::CompleteModelJobKind());
    return r;
  }();
  return *registry;
}

}  // namespace pz::kinds
