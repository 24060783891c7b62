// A record model: a plant family (records/families.h) plus candidate unmodelled effects, and its
// output on a record with the record's explicit offset (issue 14).
//
// Effects: the one library's (model/effect_library.h) drive and output effects — driver-lowpass,
// quadratic-drive, creep, delay (drive, before the family), creep-spectrum, friction, stiffening,
// drift (output, after it) — with ranges scaled to the data; zero magnitude is the identity. A
// model applies them in the library's chain order through EffectDef::ApplyDrive / ApplyOutput. Beam
// effects (hinge-friction, cubic-stiffening) need a plant with a beam (the bimorph fin of `piezoid
// diagnose`); a records family has none, and ParseEffect says so.
// Offsets (io::OffsetMode): ŷ_total = polarity · ŷ + o with o the least-squares offset over the
// scored window (fit), the measured rest level minus the model's rest output (rest: the family's
// output at rest, before the output effects — a drift is zero at the window's start, not at rest),
// or the given value (fixed).
//
// Simulation skips the record's rest segment: every family and effect is at equilibrium under a
// constant drive, so the output there is the rest output (exact).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "io/records.h"
#include "records/families.h"

namespace pz::records {

/// A records effect: the library's handle (model/effect_library.h), one of its drive or output
/// effects (a records family has no beam; bimorph-fin's bench form has one and takes the fin's
/// effects, RecordModel).
using model::EffectKind;
using model::EffectName;

struct EffectInfo {
  EffectKind kind;
  std::string name;
  std::string title;
  std::string equation;
  std::vector<ParamInfo> params;  ///< scaled to the data; params[0] is the magnitude
  std::string unsupported;  ///< why the data cannot support it (creep-spectrum on a short window;
                            ///< params empty)
};
/// Every records effect, in chain order, with ranges scaled to the data (an effect the data cannot
/// support says why in `unsupported`; a model that takes it throws that).
std::vector<EffectInfo> EffectLibrary(const DataScale& scale);
/// The records effects (the library's drive and output effects), in chain order.
const std::vector<EffectKind>& RecordEffects();
/// Their names in that order.
const std::vector<std::string>& EffectNames();
/// The records effect of that name (or former name). Throws InputError naming an unknown effect
/// and the known ones, or a beam effect and why.
EffectKind ParseEffect(std::string_view name);

/// The first simulated sample of a record: the last sample of its rest segment (the model is at
/// rest before it), at most end − 2 (end ≥ 2): two samples at least, as a sampled drive has them
/// (the bimorph fin's, the Bouc–Wen oscillator's; a window that ends inside the rest gave NaN or
/// an error naming their internals), exact because the model is at rest all along the rest. It
/// may lie after the scored window's start when the window starts inside the rest: rows of
/// regressors computed from here cover [from, end), and a sample k < from takes the rest row
/// (RegressorRow).
size_t SimulatedFrom(const io::Record& r, size_t end);
/// The row of sample k in regressors computed from sample `from` (SimulatedFrom): k − from, or the
/// rest row 0 for a sample before it.
inline size_t RegressorRow(size_t k, size_t from) { return k < from ? 0 : k - from; }

/// A family with effects; a parameter vector is the family's params then each effect's. A family
/// that simulates records itself (Family::simulates_records: bimorph-fin's bench form) takes its
/// own effects, beam ones included, in their boxes and in the order given; it then runs each
/// record with every parameter, and the drive and output effects below are not applied around it.
class RecordModel {
 public:
  RecordModel(std::shared_ptr<const Family> family, std::vector<EffectKind> effects,
              const DataScale& scale);
  const Family& family() const { return *family_; }
  std::shared_ptr<const Family> family_ptr() const { return family_; }
  const std::vector<EffectKind>& effects() const { return effects_; }
  const DataScale& scale() const { return scale_; }
  /// The searched parameters: the family's then the effects'.
  const std::vector<ParamInfo>& params() const { return params_; }
  /// How each of params() is searched (Family::SearchForm: a ratio, a typical scale); one per
  /// parameter.
  const std::vector<Family::SearchForm>& search_forms() const { return forms_; }
  /// True when a parameter is searched as a ratio of another (records/fit.h RecordMap).
  bool has_ratio() const;
  /// "backlash-like + delay".
  std::string Describe() const;

  /// The model output ŷ (without polarity and offset) on samples [0, end) of the record — only
  /// [rest, end) is simulated. For a linear family, `weights` are the solved weights; else empty.
  /// Returns the model's rest output (before the output effects: what a rest measurement is).
  /// `prepared`: Prepare(r, end) (null: none; the output is the same bit for bit).
  double Simulate(const io::Record& r, std::span<const double> p, std::span<const double> weights,
                  size_t end, std::span<double> yhat,
                  const Family::Prepared* prepared = nullptr) const;
  /// Simulate for several parameter vectors of a non-linear family at once (Family::lanes side by
  /// side: Family::SimulatePreparedMany on the record's drive, or SimulateMany on each vector's own
  /// drive when drive effects change it; then each vector's output effects): yhats[l] and rest[l]
  /// as Simulate(r, ps[l], {}, end, yhats[l], prepared) has them, bit for bit. Throws InputError as
  /// Simulate does, and for a linear family.
  void SimulateMany(const io::Record& r, std::span<const std::span<const double>> ps, size_t end,
                    std::span<const std::span<double>> yhats, std::span<double> rest,
                    const Family::Prepared* prepared = nullptr) const;
  /// The family's per-record prepare step (Family::Prepare) on the drive that Simulate(r, …, end)
  /// hands the family; null when a drive effect changes that drive with the parameters, or when
  /// the family prepares nothing.
  std::shared_ptr<const Family::Prepared> Prepare(const io::Record& r, size_t end) const;
  /// The effective drive after the drive effects, on samples [from, end); and the family's
  /// regressors for a linear family (rows = samples from..end).
  void EffectiveDrive(const io::Record& r, std::span<const double> effect_params, size_t from,
                      size_t end, std::vector<double>& ue) const;
  /// Applies the output effects in place to y on samples [from, end) of the record (y[0] = rest).
  void ApplyOutputEffects(const io::Record& r, std::span<const double> effect_params, size_t from,
                          std::span<double> y) const;
  /// True when the output stage starts with effects linear in y (EffectDef::linear_output, e.g.
  /// creep-spectrum): a linear family's fit applies those to each regressor column, so that its
  /// weights are solved for the output they make.
  bool has_linear_output_effects() const;
  /// Applies those leading linear output effects to the columns of `reg` (rows = samples from..,
  /// row-major, m columns; row 0 at rest).
  void ApplyLinearOutputEffects(const io::Record& r, std::span<const double> effect_params,
                                size_t from, std::span<double> reg, size_t m) const;
  /// A linear family's output from its regressors: yhat[from + k] = Σ_j reg[k m + j] w_j on the
  /// simulated samples (rows from SimulatedFrom(r, end) on), the rest output before them, then the
  /// output effects — what Simulate does after computing the regressors (the same arithmetic: a
  /// fit that already has them passes them here). Returns the rest output.
  double LinearOutput(const io::Record& r, std::span<const double> p,
                      std::span<const double> weights, size_t end, std::span<const double> reg,
                      std::span<double> yhat) const;
  size_t family_param_count() const { return family_->params().size(); }
  /// Where effect e's parameters are in params(): {first index, count}; {0, 0} when the model
  /// does not take e.
  std::pair<size_t, size_t> EffectParams(EffectKind e) const;

 private:
  std::shared_ptr<const Family> family_;
  std::vector<EffectKind> effects_;
  DataScale scale_;
  std::vector<ParamInfo> params_;
  std::vector<Family::SearchForm> forms_;
  std::vector<const model::EffectDef*> defs_;  ///< the library's effect of each of effects_
  std::vector<size_t> effect_offset_;          ///< index of each effect's first parameter in p
};

/// The offset o of a record given the model output over the window and its rest output (polarity
/// applied to both by the caller).
double RecordOffset(const io::Record& r, std::span<const double> signed_yhat,
                    double signed_rest_output);

}  // namespace pz::records
