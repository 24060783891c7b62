// The record families with exact return-point memory for real stacks (issue 22): `preisach` and
// `asymmetric-pi` (model/preisach.h), linear in their weights, registered in records/families.cc.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "records/families.h"
#include "records/model.h"
#include "records/regularisation.h"

namespace pz::records {

/// The discrete Preisach model on a triangular grid of FamilyOptions::pi_operators levels over the
/// scale's drive range. Throws InputError on a bad grid (levels 1 … 200, a constant drive).
std::unique_ptr<Family> MakePreisachFamily(const DataScale& scale, const FamilyOptions& options);
/// The asymmetric PI operator: FamilyOptions::pi_operators plays and kAsymmetricPiKnots dead zones
/// each way.
std::unique_ptr<Family> MakeAsymmetricPiFamily(const DataScale& scale,
                                               const FamilyOptions& options);

/// Their registrations (listed by records/registry.cc Families()).
extern const FamilyDef kPreisachFamily, kAsymmetricPiFamily;

/// One-sided dead zones per side of the asymmetric PI (evenly inside the training drive range).
inline constexpr int kAsymmetricPiKnots = 6;

/// The levels a Preisach grid's validation tries (issue 37): 78, 210, 406 and 820 cells.
const std::vector<int>& PreisachLevelCandidates();

class RecordFitness;  // records/fit.h

/// ChoosePreisachLevels with what it validated: per candidate the model (its effects without the
/// undone creep spectrum) and its RecordFitness on `records` (null where refused), whose weights at
/// `params` are that grid's.
struct PreisachLevelFits {
  ResolutionChoice choice;
  std::shared_ptr<std::vector<io::Record>>
      records;                 ///< the training records, a creep spectrum undone
  std::vector<double> params;  ///< the models' parameters
  std::vector<std::shared_ptr<RecordModel>> models;
  std::vector<std::shared_ptr<RecordFitness>> fitness;
};

/// The Preisach grid's levels chosen on the training records (records/regularisation.h
/// ChooseResolution): for each candidate, the family at that many levels over `scale` (options'
/// other fields) with `effects` at `params` (every parameter of that model: the effects', the
/// family has none; empty: their neutral values) has its penalty and strength validated as a fit
/// validates them (RecordFitness), and the blocks' errors at that strength are compared. A
/// candidate the training records cannot support (CheckTraining: too few samples on a level) is
/// refused with the reason. Throws InputError when every one is. With `creep-spectrum` among the
/// effects (and no other output effect), its filter at `params` is undone on the measured responses
/// instead of applied to every regressor (an equation error; the validated rows keep their
/// structure, records/preisach_normal.h).
ResolutionChoice ChoosePreisachLevels(const std::vector<const io::Record*>& train,
                                      const DataScale& scale, const FamilyOptions& options,
                                      const std::vector<EffectKind>& effects,
                                      std::span<const double> params,
                                      const std::vector<int>& candidates);
PreisachLevelFits FitPreisachLevels(const std::vector<const io::Record*>& train,
                                    const DataScale& scale, const FamilyOptions& options,
                                    const std::vector<EffectKind>& effects,
                                    std::span<const double> params,
                                    const std::vector<int>& candidates);

}  // namespace pz::records
