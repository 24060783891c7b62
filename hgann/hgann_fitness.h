// The HGANN fitness (spec hgann.md §1–3, paper eq. 6): a genome is a whole 2-H-7 network; its cost
// is
//
//   CF = Σ_{c ∈ training cases} PI_c,    PI_c = Σ_k (y_meas,c,k − y_model,c,k)²   [deg²]
//
// where y_model,c is the bimorph plant (fast modal path) run with the seven parameters the network
// predicts for case c's (V, f) and that case's saturations b1, b2 (fitted from its measured data).
// A network whose parameters give an unbounded Bouc–Wen loop, or whose simulation fails, gets the
// finite penalty_cost() (larger than any valid cost) and a reason: never a NaN, never a throw.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "model/bimorph.h"
#include "model/fin_case.h"
#include "model/modal_simulator.h"
#include "model/network.h"
#include "opt/evaluator.h"

namespace pz::hgann {

/// The Bouc–Wen loop of a network's parameters is bounded (model::BimorphParams::
/// HysteresisBounded on their α, β, γ): what the fitness checks before simulating.
inline bool LoopBounded(const model::NetworkParameters& p) {
  model::BimorphParams bp;
  bp.alpha = p.alpha;
  bp.beta = p.beta;
  bp.gamma = p.gamma;
  return bp.HysteresisBounded();
}

/// One case of an HGANN problem: its drive, its measured fin angle and its saturations.
using HgannCase = model::FinCase;

struct HgannFitnessConfig {
  std::vector<HgannCase> cases;             ///< ≥ 1 training case
  model::ParameterRanges ranges;            ///< where the network's outputs are mapped
  model::InputNormalization normalization;  ///< default: FromTrainingCases()
  model::BeamGeometry geometry;             ///< the beam (default: the spec's)
  /// λ [deg²] of the optional spread penalty added to the cost: λ · Σ_k Var_grid(s_k), the variance
  /// of each normalised output s_k ∈ [0, 1] over a 5 × 5 grid of the normalised training box
  /// [0, 1]². 0 = the paper's cost exactly. A positive λ prefers networks whose parameters vary
  /// over the operating envelope only where the data pay for it, which keeps predictions at
  /// untrained operating points (corners of the box) from bending; and it penalises a network whose
  /// loop is unbounded at a point of that grid (HgannFitness::BoundedOnEnvelope). Finite, ≥ 0.
  double spread_penalty = 0;

  /// Normalisation over the training cases' (V, f) (spec hgann.md §1).
  model::InputNormalization FromTrainingCases() const;
  /// Field-named errors: no training case, sample counts, finiteness, saturations, ranges.
  Status Validate() const;
};

/// What one network does on one case.
struct HgannCaseResult {
  int number = 0;
  bool training = false;
  model::BimorphParams params;  ///< predicted μ…a2 with the case's b1, b2
  model::SimulationSummary summary;
  double pi = 0;  ///< PI [deg²] (penalty share if the simulation failed)
};

class HgannFitness final : public opt::FitnessFunction {
 public:
  /// Throws InputError if the configuration is invalid.
  explicit HgannFitness(HgannFitnessConfig config);

  /// Decode → predict per training case → simulate → Σ PI. Thread-safe; never throws.
  opt::FitnessResult Evaluate(const opt::Genome& genome) const override;
  /// The same for an already decoded network (e.g. one loaded from a file).
  opt::FitnessResult EvaluateNetwork(const model::Network& network) const;
  /// Every case (training or not) with its parameters and PI, for reports.
  std::vector<HgannCaseResult> EvaluateCases(const model::Network& network) const;
  /// Full traces of one case for plots.
  model::BimorphTrace Trace(const model::Network& network, const HgannCase& c) const;
  /// The fin angle of case `c` (its drive, b1 and b2) for the seven parameters `p`, into `angle`
  /// (c's sample count); false if the simulation fails (e.g. an unbounded loop). Thread-safe.
  bool SimulateCase(const model::NetworkParameters& p, const HgannCase& c,
                    std::span<double> angle) const;
  /// Decodes a genome with this problem's normalisation and ranges. Throws InputError on bad bits.
  model::Network Decode(const opt::Genome& genome) const;

  /// Cost given to a network whose simulation is invalid: 2 · Σ_c Σ_k (max(b1, −b2) + |y_meas,k|)²,
  /// strictly above the cost of any valid output (which stays in [b2, b1]).
  double penalty_cost() const { return penalty_; }
  const HgannFitnessConfig& config() const { return config_; }
  const model::BimorphPlant& plant() const { return *plant_; }

 private:
  model::BimorphParams ParamsFor(const model::NetworkParameters& p, const HgannCase& c) const;

 public:
  /// Σ_k Var_grid(s_k) of a network (without λ); see HgannFitnessConfig::spread_penalty.
  double OutputSpread(const model::Network& network) const;
  /// The network gives a bounded Bouc–Wen loop (model::BimorphParams::HysteresisBounded) at every
  /// point of the spread penalty's grid. With λ > 0 a network that does not is penalised (reason
  /// "unbounded_hysteresis_in_envelope"), as on a training case: its model breaks at untrained
  /// operating points inside the training box.
  bool BoundedOnEnvelope(const model::Network& network) const;
  /// The spread penalty's grid: 5 × 5 (V, f) points evenly over the normalisation's box, V outer.
  static std::vector<std::pair<double, double>> EnvelopeGrid(const model::InputNormalization& n);

  /// Which of the seven parameters the network holds at a bound of its range on every training
  /// case: −1 at the lower bound, +1 at the upper, 0 otherwise (inside on some case, or a
  /// zero-width range). "At a bound" = within kAtBoundShare of the range's width. Such a parameter
  /// is decided by the range, not by the data; the identify report names them (docs/performance.md,
  /// "Islands": the nominal bench's ≈ 2.3 deg² plateau has α, β, γ at or near their upper bounds).
  std::array<int, model::kNetworkOutputs> ParametersAtBound(const model::Network& network) const;
  static constexpr double kAtBoundShare = 1e-6;

 private:
  struct Envelope {
    double spread = 0;    ///< Σ_k Var_grid(s_k)
    bool bounded = true;  ///< a bounded loop at every grid point
  };
  Envelope GridOf(const model::Network& network) const;

  HgannFitnessConfig config_;
  std::unique_ptr<model::BimorphPlant> plant_;
  std::unique_ptr<model::ModalSimulator> simulator_;
  double penalty_ = 0;
};

}  // namespace pz::hgann

namespace pz::io {
struct CaseSet;
}

namespace pz::hgann {

/// Builds the problem of a bench case set: every case with its drive (stated V, f on the record's
/// grid), measured angle and saturations — `given` (one per case), or fitted from its measured
/// extremes (spec §3) — through io::MakeFinCase; training = the manifest's "train" role;
/// normalisation over the training cases. Throws InputError.
HgannFitnessConfig HgannConfigFromCaseSet(const io::CaseSet& set,
                                          const model::ParameterRanges& ranges,
                                          const std::vector<model::SaturationPair>& given = {});

}  // namespace pz::hgann
