// The fitness of the Bouc–Wen benchmark oscillator's identification (`piezoid boucwen`,
// model/bw_oscillator.h): θ = (m, c, k, α, β·γ, β·δ) ↦ the output-error MSE of free-run RK4
// simulations pooled over the records' counted samples [m²]. Used locally by the client and
// rebuilt from a "complete_model" spec on the service's workers (complete/job_kind.h): the same
// code, so the same costs bit for bit.
#pragma once

#include <string>
#include <vector>

#include "opt/evaluator.h"
#include "opt/param_search.h"
#include "model/bw_oscillator.h"

namespace pz::complete {

/// A training record as sampled: the input u and measured output y (same length), the samples
/// before `first_counted` a warm-up (simulated, not counted), and how u is reconstructed.
struct BwTrainingRecord {
  std::string name;
  std::vector<double> u, y;
  size_t first_counted = 0;
  model::BwInputOptions input;
};

/// The search box of θ = (m, c, k, alpha, beta_gamma, beta_delta): wide, physically motivated
/// bounds (log scale: the magnitudes are not known a priori; β·δ may have either sign):
/// m 0.2–20 kg, c 0.1–1000 N s/m, k and α 1e3–1e6 N/m, β·γ 1–1e5, β·δ ±1e4.
opt::ParamBox BwOscillatorBox();

class BwOscillatorFitness final : public opt::FitnessFunction {
 public:
  /// Prepares every record's input once (model::BwInput). Throws InputError naming the record and
  /// what is wrong: no records, u and y of different lengths, a non-finite sample, a warm-up that
  /// leaves no counted sample, bad input options; or a penalty that is not finite and > 0.
  explicit BwOscillatorFitness(std::vector<BwTrainingRecord> records, double penalty = 1.0);
  /// cost = the pooled MSE; a diverging simulation is kPenalized with cost `penalty`; a genome
  /// without 6 reals is kError.
  opt::FitnessResult Evaluate(const opt::Genome& genome) const override;

  const std::vector<BwTrainingRecord>& records() const { return records_; }
  double penalty() const { return penalty_; }
  /// Counted samples over all records.
  size_t counted_samples() const;

 private:
  std::vector<BwTrainingRecord> records_;
  std::vector<model::BwRecord> prepared_;
  double penalty_;
};

}  // namespace pz::complete
