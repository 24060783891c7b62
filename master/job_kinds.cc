#include "master/job_kinds.h"

#include "master/hgann_job.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <thread>

namespace pz::master {
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
  k.validate = [](const JobSpec&) { return std::vector<FieldViolation>{}; };
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

JobKindRegistry& JobKindRegistry::Default() {
  static JobKindRegistry* registry = [] {
    auto* r = new JobKindRegistry;
    r->Register(SyntheticJobKind());
    r->Register(HgannJobKind());
    return r;
  }();
  return *registry;
}

void JobKindRegistry::Register(JobKind kind) {
  std::lock_guard lock(mu_);
  std::string name = kind.name;
  kinds_[name] = std::make_shared<const JobKind>(std::move(kind));
}

const JobKind* JobKindRegistry::Find(const std::string& name) const {
  std::lock_guard lock(mu_);
  auto it = kinds_.find(name);
  return it == kinds_.end() ? nullptr : it->second.get();
}

std::vector<FieldViolation> JobKindRegistry::Validate(const JobSpec& spec) const {
  std::vector<FieldViolation> out = spec.Validate();
  if (spec.kind().empty()) return out;
  const JobKind* k = Find(spec.kind());
  if (!k) {
    out.push_back({spec.kind(), spec.kind() + ": job kind not available on this master"});
    return out;
  }
  if (k->validate) {
    auto more = k->validate(spec);
    out.insert(out.end(), more.begin(), more.end());
  }
  return out;
}

Status JobKindRegistry::Layout(const JobSpec& spec, GenomeLayout* layout) const {
  const JobKind* k = Find(spec.kind());
  if (!k || !k->layout) return NotFound("job kind '" + spec.kind() + "' has no genome layout");
  return k->layout(spec, layout);
}

Status JobKindRegistry::MakeFitness(const JobSpec& spec,
                                    std::unique_ptr<FitnessFunction>* out) const {
  const JobKind* k = Find(spec.kind());
  if (!k || !k->make_fitness) return NotFound("job kind '" + spec.kind() + "' has no fitness");
  return k->make_fitness(spec, out);
}

}  // namespace pz::master
