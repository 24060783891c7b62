// The registry of the plant families (issue 46: above the families it lists): every family's
// registration (its `FamilyDef`, defined beside its class: records/families.cc for six,
// records/preisach_family.cc for preisach and asymmetric-pi), in one list, and the look-ups every
// user of a family by name goes through — the CLI's lists and help texts, `--family auto`'s grid,
// the stepper's and the export's kernel ids, fit.json's family name. A new family: its
// registration in its own source, declared in its header, and one line of Families()
// (records/registry.cc). No family source includes this header.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "records/families.h"

namespace pz::records {

/// Every family, in registration order (the order of the header comment, of `--family auto`'s grid
/// and of every list shown to a user).
const std::vector<const FamilyDef*>& Families();
/// The registered family of that name; null for none.
const FamilyDef* FindFamily(std::string_view name);
/// FindFamily, or throws InputError "FIELD 'NAME' is unknown (families: …)".
const FamilyDef& FamilyNamed(std::string_view name, std::string_view field);
/// The registered families' names joined by ", " (help texts, errors); `initial_state_only`: those
/// that take an initial state.
std::string FamilyList(bool initial_state_only = false);

/// True for the families whose memory at rest FamilyOptions::initial_state sets
/// (FamilyDef::takes_initial_state). (duhem relaxes to its curve at rest, the oscillator and the
/// fin start from their own equilibrium.)
bool TakesInitialState(std::string_view family);

/// Every family name, in registration order.
const std::vector<std::string>& FamilyNames();
/// Makes a family for the scale. Throws InputError naming an unknown family (and the known ones)
/// or bad options.
std::unique_ptr<Family> MakeFamily(std::string_view name, const DataScale& scale,
                                   const FamilyOptions& options = {});

}  // namespace pz::records
