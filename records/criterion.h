// The criteria a record model is fitted by (issue 21): the engine's fitness for any family and
// effects of records/model.h on any record set, scored by
//
//   mse    the mean squared output error over the records' scored windows (records/fit.h's
//          RecordFitness: `piezoid fit`, `diagnose --records`)
//   iae    ∫ |e| dt over a time window [t0, t1], summed over the records
//   sse    Σ e² over the window's samples, summed over the records
//   rmse   each record's RMSE over the window, summed over the records
//   max    the largest windowed max |e| of the records
//
// (model/criteria.h's functions; the committee machine of seed 002 fits by iae over [0.5, 2.5] s).
// The window is in each record's own time from its first sample (on its uniform grid k·dt), t1
// clipped to the record's last scored sample; the model output is records/fit.h's (polarity,
// offset, a linear family's weights solved by least squares over the scored samples).
#pragma once

#include <span>
#include <string>
#include <vector>

#include "io/records.h"
#include "model/status.h"
#include "opt/evaluator.h"
#include "records/fit.h"

namespace pz::records {

enum class Criterion : int { kMse = 0, kIae = 1, kSse = 2, kRmse = 3, kMax = 4 };
/// "mse", "iae", "sse", "rmse", "max".
const char* CriterionName(Criterion c);
/// Parses the names above; throws InputError naming the value and the known ones otherwise.
Criterion ParseCriterion(const std::string& name);

struct CriterionOptions {
  Criterion kind = Criterion::kMse;
  double t0_s = 0, t1_s = 0;                   ///< the window of every criterion but mse [s]
  double error_cost = opt::kDefaultErrorCost;  ///< the cost of a diverged or invalid parameter set
  bool windowed() const { return kind != Criterion::kMse; }
  /// A window 0 ≤ t0 < t1 (finite) for a windowed criterion; error_cost finite and > 0.
  Status Validate() const;
};

/// The end of the window on a record: t1 clipped to its last scored sample's time ((end − 1)·dt).
double WindowEnd(const io::Record& record, double t1_s);

/// The errors of an output on one record over the window [t0, WindowEnd(t1)].
struct WindowErrors {
  size_t samples = 0;  ///< samples with t0 ≤ k·dt ≤ t1
  double iae = 0;      ///< [unit·s]
  double sse = 0;      ///< [unit²]
  double max_abs = 0;  ///< [unit]
};
/// yhat holds samples [0, record.end_scored) (records/fit.h's Evaluate). Throws InputError when
/// the window holds no sample.
WindowErrors ScoreWindow(const io::Record& record, std::span<const double> yhat, double t0_s,
                         double t1_s);

/// The fitness of a parameter vector (the model's params() order, physical values) by a criterion.
/// Thread-safe. A non-finite output or invalid parameters are penalised (the error cost); a genome
/// of the wrong size is an error.
class CriterionFitness final : public opt::FitnessFunction {
 public:
  /// The model and records must outlive the fitness. Throws InputError on no records, invalid
  /// options or a record that ends before the window starts.
  CriterionFitness(const RecordModel& model, std::vector<const io::Record*> records,
                   CriterionOptions criterion);
  opt::FitnessResult Evaluate(const opt::Genome& genome) const override;
  /// The cost of one parameter vector (+inf when the output is not finite); throws InputError on
  /// invalid parameters.
  double Cost(std::span<const double> params) const;

  const RecordFitness& outputs() const { return fitness_; }
  const RecordModel& model() const { return fitness_.model(); }
  const std::vector<const io::Record*>& records() const { return fitness_.records(); }
  const CriterionOptions& criterion() const { return criterion_; }

 private:
  RecordFitness fitness_;
  CriterionOptions criterion_;
};

/// The search box of a model's parameters (records/families.h's ranges, scaled to the data).
opt::ParamBox ParamBoxOf(const RecordModel& model);

}  // namespace pz::records
