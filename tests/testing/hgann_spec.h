// Test fixtures of hgann job specs: the bundled nominal bench as a case set and as a spec, and
// checks on field violations. For tests that link pz::hgann (or a floor above it).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "hgann/hgann_job.h"
#include "io/bench_data.h"
#include "job/job_spec.h"

namespace pz::testing {

inline const io::CaseSet& NominalCaseSet() {
  static const io::CaseSet set =
      io::LoadCaseSet(std::filesystem::path(PIEZOID_DATA_DIR) / "bimorph-fin" / "nominal");
  return set;
}

/// The nominal bench as an hgann spec (seed 11, no stall stop).
inline job::JobSpec NominalHgannSpec(int population, int generations) {
  job::JobSpec s;
  s.name = "nominal";
  s.seed = 11;
  s.problem = hgann::HgannProblemFromCaseSet(NominalCaseSet());
  job::GaSettings ga;
  ga.population = population;
  ga.generations = generations;
  ga.stall_generations = 0;
  s.ga = ga;
  return s;
}

/// Whether a violation of `field` whose description contains `text` is among v.
inline bool HasViolation(const std::vector<job::FieldViolation>& v, const std::string& field,
                         const std::string& text = "") {
  for (const auto& x : v)
    if (x.field == field && x.description.find(text) != std::string::npos) return true;
  return false;
}

/// Every description, one a line (for failure messages).
inline std::string Descriptions(const std::vector<job::FieldViolation>& v) {
  std::string s;
  for (const auto& x : v) s += x.description + "\n";
  return s;
}

}  // namespace pz::testing
