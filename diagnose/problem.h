// The nine-case fin bench as the bench's report reads it (issue 6): ONE parameter set shared by
// every case — μ, δ, α, β, γ, a1, a2 and the parameters of the effects in the model structure —
// with per-case saturations b1, b2 from each case's measured extremes (model/saturation.h), the
// cost the paper's CF = Σ_{training cases} PI_c, the withheld cases scoring the result. The fits
// are the records engine's (bimorph-fin's bench form, records/families.h; the bench's diagnosis:
// diagnose/fin_diagnose.h DiagnoseBench); here are the cases with their noise, the parameter
// vector of a structure, a fit's figures and the simulation of a case (the report's traces).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "opt/fit.h"
#include "model/bimorph.h"
#include "model/fin_case.h"
#include "model/effects.h"
#include "records/noise_floor.h"

namespace pz::io {
struct CaseSet;
}

namespace pz::diagnose {

using opt::Identifiability;
using opt::IdentifiabilityName;
using opt::ParamEstimate;

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

/// The parameter vector of a model structure (base model + a list of effect kinds), in physical
/// units: [μ, δ, α, β, γ, a1, a2, the effects' parameters in structure order]. Its search box and
/// unit coordinates are the records engine's (records/families.h, bimorph-fin's bench form).
class ParameterLayout {
 public:
  explicit ParameterLayout(std::vector<model::EffectKind> structure);
  int size() const { return size_; }
  const std::vector<model::EffectKind>& structure() const { return structure_; }
  static constexpr int kBase = 7;  ///< μ, δ, α, β, γ, a1, a2

  /// Physical vector → plant parameters (b1, b2 left at the given values) and effects.
  void Decode(std::span<const double> physical, model::BimorphParams* params,
              std::vector<model::Effect>* effects) const;
  /// "base", "base + creep", …
  std::string Describe() const;

 private:
  std::vector<model::EffectKind> structure_;
  int size_ = kBase;
};

/// One fit of a model structure on the bench's cases, as the bench's report reads it (made from a
/// records fit by DiagnosisOfRecords, diagnose/fin_diagnose.h).
struct FitResult {
  std::vector<model::EffectKind> structure;
  std::string description;  ///< "base + creep"
  std::vector<double> x;    ///< physical parameters (layout order)
  std::vector<ParamEstimate> params;
  double train_pi = 0;          ///< Σ PI training [deg²]
  double withheld_pi = 0;       ///< Σ PI withheld [deg²]
  std::vector<double> case_pi;  ///< every case, in case order [deg²]
  int train_samples = 0, withheld_samples = 0;
  double residual_sigma = 0;            ///< s = √(train_pi / (N − p)) [deg]
  std::vector<double> singular_values;  ///< of J·diag(scale), descending
  std::string weakest_direction;        ///< the parameters of the smallest singular vector
  int64_t evaluations = 0;
  double wall_time_s = 0;
  std::string message;
  bool ok = false;
  int num_params() const { return static_cast<int>(x.size()); }
};

/// Simulates a model structure on the cases (the report's traces). Immutable, thread-safe.
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

 private:
  std::shared_ptr<const model::BimorphPlant> plant_;
  std::unique_ptr<model::EffectSimulator> sim_;
  std::vector<DiagCase> cases_;
  model::EffectSimOptions sim_options_;
  int n_train_ = 0, n_withheld_ = 0;
};

}  // namespace pz::diagnose
