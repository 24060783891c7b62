// The global identification problem of the diagnosis (issue 6): ONE parameter set shared by every
// case of a bench — μ, δ, α, β, γ, a1, a2 and the parameters of the effects in the model structure
// — with per-case saturations b1, b2 from each case's measured extremes (model/saturation.h). The
// cost is the paper's CF = Σ_{training cases} PI_c; the withheld cases score the result.
//
// Parameter vector (physical units): [μ, δ, α, β, γ, a1, a2, effect parameters in structure order].
// Search coordinates: every parameter is mapped to [0, 1] over its range (log scale where marked),
// except that γ is searched as the ratio g = γ/β ∈ [−0.98, 1], so that every point of the box has a
// bounded Bouc–Wen loop (β ≥ |γ| with β > 0). The fitness over Genome.reals is a pure function of
// (genome, problem), so the broker-backed evaluator can run it on workers.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "opt/evaluator.h"
#include "model/bimorph.h"
#include "model/fin_case.h"
#include "model/effects.h"
#include "records/noise_floor.h"

namespace pz::io {
struct CaseSet;
}

namespace pz::diagnose {

/// One bench case of the problem (saturations from the measured extremes) with its noise floor.
struct DiagCase : model::FinCase {
  records::CaseNoise noise;  ///< noise floor of the record
};

/// The cases of a bench with their noise. Throws InputError on a set without training or
/// without withheld cases, or a case whose extremes give no saturation.
std::vector<DiagCase> CasesFromCaseSet(const io::CaseSet& set);
/// The same from raw records (synthetic benches): cycles = 3, saturations from the extremes.
DiagCase MakeCase(int number, const model::Sinusoid& drive, std::vector<double> measured,
                  bool training);

/// One parameter of the search.
struct ParamSpec {
  std::string name;  ///< "mu", "delta", …, or "<effect>.<param>"
  std::string unit;
  double lower = 0, upper = 1;  ///< physical range (γ: ratio range)
  double scale = 1;             ///< typical magnitude (finite-difference steps, report)
  bool log_scale = false;
  bool ratio = false;  ///< true for γ: searched as g = γ/β
  int effect = -1;     ///< index into the structure, −1 for the base model
  int effect_param = -1;
};

/// The parameter layout of a model structure (base model + a list of effect kinds).
class ParameterLayout {
 public:
  explicit ParameterLayout(std::vector<model::EffectKind> structure);
  int size() const { return static_cast<int>(specs_.size()); }
  const std::vector<ParamSpec>& specs() const { return specs_; }
  const std::vector<model::EffectKind>& structure() const { return structure_; }
  static constexpr int kBase = 7;  ///< μ, δ, α, β, γ, a1, a2

  /// Search coordinates in [0, 1] → physical parameter vector (γ = g β).
  std::vector<double> FromUnit(std::span<const double> unit) const;
  /// Physical → search coordinates (clamped into [0, 1]).
  std::vector<double> ToUnit(std::span<const double> physical) const;
  /// Physical vector → plant parameters (b1, b2 left at the given values) and effects.
  void Decode(std::span<const double> physical, model::BimorphParams* params,
              std::vector<model::Effect>* effects) const;
  /// Plant parameters and effects (matching the structure) → physical vector.
  std::vector<double> Encode(const model::BimorphParams& params,
                             std::span<const model::Effect> effects) const;
  /// Physical vector of the base parameters with every effect at zero magnitude (identity).
  std::vector<double> Extend(std::span<const double> base_physical,
                             const ParameterLayout& from) const;
  /// ∂physical/∂unit at a point (size × size, column j = unit coordinate j): diagonal but for γ,
  /// which depends on g and β.
  std::vector<double> UnitJacobian(std::span<const double> unit) const;
  /// "base", "base + creep", …
  std::string Describe() const;

 private:
  std::vector<model::EffectKind> structure_;
  std::vector<ParamSpec> specs_;
};

/// Evaluates a model structure on the cases: residuals, PIs, traces. Immutable, thread-safe.
class DiagnosisModel {
 public:
  DiagnosisModel(std::shared_ptr<const model::BimorphPlant> plant, std::vector<DiagCase> cases,
                 model::EffectSimOptions sim = {});

  const std::vector<DiagCase>& cases() const { return cases_; }
  const model::EffectSimulator& simulator() const { return *sim_; }
  const model::EffectSimOptions& sim_options() const { return sim_options_; }
  std::shared_ptr<const model::BimorphPlant> plant() const { return plant_; }
  int training_samples() const { return n_train_; }
  int withheld_samples() const { return n_withheld_; }

  /// Model output of case c [deg]; returns the simulation summary (angle_deg sized by the call).
  model::SimulationSummary Simulate(const ParameterLayout& layout, std::span<const double> physical,
                                    size_t c, std::vector<double>& angle_deg) const;
  /// Residuals y_meas − y_model of the selected cases (training or withheld, concatenated in case
  /// order) into r. Returns false if a simulation failed (r then holds a large finite penalty).
  bool Residuals(const ParameterLayout& layout, std::span<const double> physical, bool training,
                 std::vector<double>& r) const;
  /// PI of every case (NaN where the simulation failed).
  std::vector<double> CasePi(const ParameterLayout& layout, std::span<const double> physical) const;

 private:
  std::shared_ptr<const model::BimorphPlant> plant_;
  std::unique_ptr<model::EffectSimulator> sim_;
  std::vector<DiagCase> cases_;
  model::EffectSimOptions sim_options_;
  int n_train_ = 0, n_withheld_ = 0;
};

/// The cost over Genome.reals (search coordinates in [0, 1]): CF = Σ_training PI [deg²]; an invalid
/// genome or failed simulation gets the finite penalty_cost() with status kPenalized. With
/// `residuals`, an evaluable genome's result also carries the training residual vector (what
/// Levenberg–Marquardt needs: DiagnosisModel::Residuals at FromUnit(genome.reals)).
class DiagnosisFitness final : public opt::FitnessFunction {
 public:
  DiagnosisFitness(const DiagnosisModel& model, ParameterLayout layout, bool residuals = false);
  opt::FitnessResult Evaluate(const opt::Genome& genome) const override;
  const DiagnosisModel& model() const { return model_; }
  const ParameterLayout& layout() const { return layout_; }
  bool residuals() const { return residuals_; }
  double penalty_cost() const { return penalty_; }

 private:
  const DiagnosisModel& model_;
  ParameterLayout layout_;
  bool residuals_ = false;
  double penalty_ = 0;
};

}  // namespace pz::diagnose
