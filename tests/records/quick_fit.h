// The quick Preisach fit of the real-like tests (tests/records/creep_spectrum_test.cc,
// rate_dependence_test.cc): one repetition of PSO 10 × 15, a short LM polish, no uncertainty table;
// and each record's RMSE against its true noise RMS.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "records/fit.h"
#include "synth/reallike.h"

namespace pz::testing {

/// `piezoid fit --family preisach --effects … --repetitions 1 --particles 10 --iterations 15`.
inline records::FitOptions QuickPreisach(std::vector<records::EffectKind> effects) {
  records::FitOptions f;
  f.family = "preisach";
  f.effects = std::move(effects);
  f.uncertainty = false;
  f.search.repetitions = 1;
  f.search.pso.particles = 10;
  f.search.pso.iterations = 15;
  f.lm.max_iterations = 30;
  return f;
}

/// Each record's RMSE / its true noise RMS, by name, for the fit `f` of the set (kept in *out).
inline std::map<std::string, double> FloorRatios(const synth::RealLikeSet& s,
                                                 const records::FitOptions& f,
                                                 records::FitResult* out = nullptr) {
  records::FitResult r = records::FitRecords(s.set, f);
  std::map<std::string, double> ratios;
  for (size_t i = 0; i < s.set.records.size(); ++i)
    ratios[s.set.records[i].name] = r.metrics[i].rmse / s.truth[i].noise_rms_um;
  if (out) *out = std::move(r);
  return ratios;
}

}  // namespace pz::testing
