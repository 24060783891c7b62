// The global-search flags shared by the commands that fit physical parameters (`piezoid fit`,
// `piezoid committee`): repetitions, seed, PSO swarm / iterations, GA population / generations,
// stall — one definition of their names, help and defaults, one mapping onto opt::SearchOptions.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

#include "model/prandtl_ishlinskii.h"
#include "opt/param_search.h"

namespace pz::client {

struct SearchFlags {
  int repetitions = 3;
  uint64_t seed = 1;
  int particles = 30, iterations = 150, population = 30, generations = 150, stall = 40;
};

/// Adds --repetitions --seed --particles --iterations --population --generations --stall to `cmd`,
/// with `flags`' values as the shown defaults; `sized`: the PSO's --repetitions, --particles,
/// --iterations and --stall default to a budget sized by the searched parameters (`piezoid fit`,
/// records::SizedSearchBudget), which the help says.
void AddSearchFlags(CLI::App* cmd, SearchFlags* flags, bool sized = false);

/// Sets every algorithm's options in `o` from the flags (the algorithm itself is the caller's).
void ApplySearchFlags(const SearchFlags& flags, opt::SearchOptions* o);

/// Adds --initial-state NAME (`fit`, `diagnose --records`, `committee`): the memory at rest of the
/// families that take one (records/families.h FamilyOptions::initial_state); `value` empty = the
/// default (auto).
void AddInitialStateFlag(CLI::App* cmd, std::string* value);

/// The initial state of the flag's value for `family` (empty: FamilyOptions' default). Throws
/// InputError naming --initial-state and the allowed values, or a family that does not take one.
/// (With --master the state travels in the job spec: complete_model.initial_state.)
model::InitialState InitialStateOfFlag(const std::string& value, const std::string& family);

}  // namespace pz::client
