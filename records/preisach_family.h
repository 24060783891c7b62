// The record families with exact return-point memory for real stacks (issue 22): `preisach` and
// `asymmetric-pi` (model/preisach.h), linear in their weights, registered in records/families.cc.
#pragma once

#include <memory>

#include "records/families.h"

namespace pz::records {

/// The discrete Preisach model on a triangular grid of FamilyOptions::pi_operators levels over the
/// scale's drive range. Throws InputError on a bad grid (levels 1 … 200, a constant drive).
std::unique_ptr<Family> MakePreisachFamily(const DataScale& scale, const FamilyOptions& options);
/// The asymmetric PI operator: FamilyOptions::pi_operators plays and kAsymmetricPiKnots dead zones
/// each way.
std::unique_ptr<Family> MakeAsymmetricPiFamily(const DataScale& scale, const FamilyOptions& options);

/// One-sided dead zones per side of the asymmetric PI (evenly inside the training drive range).
inline constexpr int kAsymmetricPiKnots = 6;

}  // namespace pz::records
