// The fitness of the committee machine's stack models (seed 002; model/stack_models.h) on a set of
// stack records (io/stack_records.h): the identification criterion over a window, summed over the
// records. Used by `piezoid committee` locally and rebuilt by the "complete_model" job kind on the
// service's workers (complete/job_kind.h): the same code, so the same costs bit for bit.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "io/stack_records.h"
#include "opt/inline_evaluator.h"
#include "model/stack_models.h"
#include "model/status.h"

namespace pz::complete {

enum class FitCriterion : int { kIae = 0, kSse = 1, kRmse = 2, kMax = 3 };
/// "iae", "sse", "rmse", "max".
const char* FitCriterionName(FitCriterion c);
/// Parses the names above; throws InputError naming the value otherwise.
FitCriterion ParseFitCriterion(const std::string& name);

/// The end of the window [t0, t1] on a record: t1 clipped to the record's last sample time.
double WindowEnd(const io::StackRecord& record, double t1_s);

/// The fitness of a parameter vector (Genome::reals, in model::StackParamNames order) on a set of
/// records: IAE or SSE over the window summed over the records, the RMSE over the window of each
/// record summed over the records, or the largest windowed max error of the records (model/criteria.h).
/// Pure and thread-safe (one scratch buffer per thread, no allocation once grown). A simulation
/// with non-finite output is a penalised result (the error cost).
class StackFitness final : public opt::FitnessFunction {
 public:
  /// The records must outlive the fitness. Throws InputError on no records, a bad window
  /// (t0 < t1, t0 ≥ 0, t0 inside every record) or bad simulation options. The window end is
  /// clipped to each record's last sample time.
  StackFitness(model::StackFamily family, std::vector<const io::StackRecord*> records,
               FitCriterion criterion, double t0_s, double t1_s,
               model::StackSimOptions sim = {}, double error_cost = opt::kDefaultErrorCost);
  opt::FitnessResult Evaluate(const opt::Genome& genome) const override;
  /// The cost of one parameter vector; throws InputError on a wrong size or invalid parameters.
  double Cost(std::span<const double> params) const;

  model::StackFamily family() const { return family_; }
  const std::vector<const io::StackRecord*>& records() const { return records_; }
  FitCriterion criterion() const { return criterion_; }
  double t0_s() const { return t0_; }
  double t1_s() const { return t1_; }
  const model::StackSimOptions& sim() const { return sim_; }
  double error_cost() const { return error_cost_; }

 private:
  model::StackFamily family_;
  std::vector<const io::StackRecord*> records_;
  FitCriterion criterion_;
  double t0_, t1_;
  model::StackSimOptions sim_;
  double error_cost_;
};

}  // namespace pz::complete
