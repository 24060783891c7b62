// The committee machine of seed 002 (spec committee-machine.md) on a record set (io/records.h;
// the stack bench data/piezo-stack-bench is one), a thin protocol over the records engine
// (records/families.h, records/criterion.h):
//
//  1. complete models: each model family (any records/families.h family; by default the paper's
//     stack Bouc–Wen with driver filter and backlash-like) identified by each optimiser (PSO, real
//     GA, binary GA; opt/param_search.h) on ALL training records; the parameters are the search
//     space (the family's data-scaled ranges, or the protocol's box: seed 002's for the paper's
//     two families), the cost is the engine's criterion (IAE by default) over the window [t0, t1]
//     summed over the records; `repetitions` seeded runs, best kept;
//  2. per band (default 0–50, 50–150, 150–250, 250–350 Hz; a record belongs to the band
//     [lo, hi) containing its stated excitation frequency, the last band closed): the same
//     identifications on the band's training records only;
//  3. selection per band, by the aggregate A = ½ (RMSE_train + RMSE_test), the RMSEs over the
//     window pooled over the band's training, resp. withheld (test, validate) records (lowest A
//     wins; ties to the first family, then the first optimiser, in option order);
//  4. the committee output for a record: the selected sub-model of the record's band (hard switch);
//     or, with `averaging`, Σ_b μ_b(f) ŷ_b with triangular memberships μ_b over the band centres
//     (a partition of unity; μ_b = 1 at band b's centre; the outer bands extend flat);
//  5. comparison on the test records: pooled RMSE and max error of the committee against the best
//     complete model (lowest pooled test RMSE of all complete models: the strongest baseline);
//     reduction = 1 − RMSE_committee / RMSE_complete.
//
// Every record's scored window is set to [t0, t1] of its own time (t1 clipped to its last sample).
// Every search goes through the BatchEvaluator seam, so it runs inline, on a thread pool, or on the
// service's workers (any evaluator made by the factory); the results are the same bit for bit.
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <map>

#include "io/records.h"
#include "model/status.h"
#include "opt/evaluator.h"
#include "opt/param_search.h"
#include "records/criterion.h"
#include "records/families.h"
#include "records/model.h"

namespace pz::complete {

/// Frequency bands by their edges e_0 < e_1 < … < e_B: band b is [e_b, e_{b+1}), the last closed.
struct FrequencyBands {
  std::vector<double> edges{0, 50, 150, 250, 350};
  int size() const { return static_cast<int>(edges.size()) - 1; }
  /// The band containing f, or −1.
  int BandOf(double f_hz) const;
  /// "0–50 Hz".
  std::string Label(int band) const;
  /// ≥ 2 finite edges ≥ 0, strictly increasing; the error names the edge.
  Status Validate() const;
  /// Parses "0,50,150,250,350" (or "0-50,50-150,…"); throws InputError naming the item.
  static FrequencyBands Parse(const std::string& text);
};

/// Seed 002's search boxes of the paper's two families (the committee's default `boxes`):
///  stack-bouc-wen: α ∈ [0.01, 3] (log), β ∈ [1e-5, 0.1] (log), γ ∈ [−0.05, 0.05],
///                  d ∈ [0.02, 0.08] µm/V, fc ∈ [100, 20000] Hz (log);
///  backlash-like:  α ∈ [1e-4, 1] 1/V (log), c ∈ [0.02, 0.08] µm/V, B1 ∈ [−0.05, 0.1] µm/V.
std::map<std::string, opt::ParamBox> Seed002Boxes();

struct CommitteeOptions {
  FrequencyBands bands;
  std::vector<std::string> families{"stack-bouc-wen",
                                    "backlash-like"};  ///< records/families.h names
  std::vector<opt::SearchAlgorithm> algorithms{opt::SearchAlgorithm::kPso,
                                               opt::SearchAlgorithm::kGaReal};
  /// Settings of every search (the algorithm field is set per run; repetitions, seeds, swarm and
  /// population sizes are used as given).
  opt::SearchOptions search;
  records::Criterion criterion = records::Criterion::kIae;
  double t0_s = 0.5;  ///< criterion window [s]
  double t1_s = 2.5;
  records::FamilyOptions family_options;  ///< sub-steps, PI plays, fin geometry
  /// The search box of a family by name (its parameters in order); a family not listed is searched
  /// in its own data-scaled ranges (records/families.h).
  std::map<std::string, opt::ParamBox> boxes = Seed002Boxes();
  bool averaging = false;  ///< averaging committee instead of the hard switch
  bool complete = true;    ///< also identify the complete models (needed for the comparison)
  Status Validate() const;
};

/// Makes the evaluator a search runs on, for a fitness that outlives it (locally a thread pool over
/// it; on the service a session whose spec carries its records, svcclient/complete_service.h).
using EvaluatorFactory =
    std::function<std::unique_ptr<opt::BatchEvaluator>(const records::CriterionFitness&)>;
/// Inline when threads == 1, else a ThreadPoolEvaluator of that many threads (0 = all cores).
EvaluatorFactory LocalEvaluatorFactory(int threads);

/// Errors of one model on the records of one role in one band, over the window.
struct RoleMetrics {
  int records = 0;
  size_t samples = 0;  ///< in the window, all records
  double iae = 0;      ///< Σ over records [µm·s]
  double rmse = 0;     ///< pooled [µm]
  double max_abs = 0;  ///< max over records [µm]
};
struct BandMetrics {
  RoleMetrics train, test;
};

struct IdentifiedModel {
  std::string family;  ///< records/families.h name
  opt::SearchAlgorithm algorithm = opt::SearchAlgorithm::kPso;
  int band = -1;  ///< −1: the complete model (all training records)
  std::shared_ptr<const records::RecordModel> model;  ///< made for its training records' scale
  std::vector<double> params;                         ///< model->params() order
  std::vector<double> weights;                        ///< a linear family's solved weights
  opt::SearchResult search;
  std::vector<BandMetrics> per_band;  ///< its errors on every band's records
  RoleMetrics all_test;               ///< on all test records
  std::string Name() const;           ///< "stack-bouc-wen/pso"
};

struct CommitteeResult {
  CommitteeOptions options;
  io::RecordSet set;  ///< the records, their scored windows set to the criterion's window
  std::vector<IdentifiedModel> complete;                  ///< families × algorithms (may be empty)
  std::vector<std::vector<IdentifiedModel>> band_models;  ///< [band][families × algorithms]
  std::vector<int> selected;      ///< per band: index into band_models[band]
  std::vector<double> aggregate;  ///< per band: A of the selected model
  std::vector<BandMetrics> committee_per_band;
  RoleMetrics committee_test;       ///< all test records
  RoleMetrics committee_train;      ///< all training records
  int best_complete = -1;           ///< index into complete (lowest pooled test RMSE)
  double rmse_reduction = 0;        ///< 1 − RMSE_cm / RMSE_complete on the test records
  double max_reduction = 0;         ///< 1 − max_cm / max_complete on the test records
  std::vector<double> band_wall_s;  ///< identification wall time per band [s]
  double complete_wall_s = 0;
  double wall_s = 0;
  int64_t evaluations = 0;
  int threads = 1;
};

using CommitteeLog = std::function<void(const std::string&)>;

/// Runs the whole study. Throws InputError on bad options, a record without a stated frequency or
/// outside every band, a band without training or test records.
CommitteeResult RunCommittee(const io::RecordSet& set, const CommitteeOptions& options,
                             const EvaluatorFactory& factory, const CommitteeLog& log = {});

/// One identified model's output on a record (samples [0, end_scored)).
std::vector<double> PredictModel(const IdentifiedModel& m, const io::Record& record);
/// The committee's output for a record (hard switch or averaging, as in the result's options).
std::vector<double> PredictCommittee(const CommitteeResult& r, const io::Record& record);
/// Window errors of a prediction on a record, as a one-record RoleMetrics.
RoleMetrics RecordMetrics(const io::Record& record, std::span<const double> yhat, double t0_s,
                          double t1_s);

/// x with 3 significant digits (scientific below 1e-3 and from 1e5), "—" when not finite.
std::string FormatFigure(double x, int precision = 3);
/// 100·x with two decimals and " %".
std::string FormatPercent(double x);

}  // namespace pz::complete
