#include "client/search_flags.h"

#include "records/families.h"
#include "records/registry.h"

namespace pz::client {

void AddSearchFlags(CLI::App* cmd, SearchFlags* f, bool sized) {
  // A sized flag shows the rule's values (records::SizedSearchBudget) for d searched parameters.
  auto s = [sized](auto v, const char* rule = nullptr) {
    return sized && rule ? std::string(rule) + " for d searched parameters (PSO)"
                         : std::to_string(v);
  };
  cmd->add_option("--repetitions", f->repetitions, "seeded searches (seed, seed+1, …), best kept")
      ->default_str(s(f->repetitions, "d <= 2 ? 2 : 3"));
  cmd->add_option("--seed", f->seed, "seed of the first repetition")->default_str(s(f->seed));
  cmd->add_option("--particles", f->particles, "PSO swarm size")
      ->default_str(s(f->particles, "min(30, 5 d + 5)"));
  cmd->add_option("--iterations", f->iterations, "PSO iterations")
      ->default_str(s(f->iterations, "min(150, 30 d)"));
  cmd->add_option("--population", f->population, "GA / DE population")
      ->default_str(s(f->population));
  cmd->add_option("--generations", f->generations, "GA / DE generations")
      ->default_str(s(f->generations));
  cmd->add_option(
         "--stall", f->stall,
         "stop a repetition after this many iterations / generations without a relative "
         "improvement of 1e-6 (DE: 1e-4; 0: never)" +
             std::string(
                 sized ? "; a sized PSO also stops when every particle is within 1e-3 of the best"
                       : ""))
      ->default_str(s(f->stall, "min(40, 10 d)"));
}

void ApplySearchFlags(const SearchFlags& f, opt::SearchOptions* o) {
  o->repetitions = f.repetitions;
  o->pso.seed = o->ga_real.seed = o->ga_binary.ga.seed = o->de.seed = f.seed;
  o->pso.particles = f.particles;
  o->pso.iterations = f.iterations;
  o->pso.stall_iterations = f.stall;
  o->ga_real.population = f.population;
  o->ga_real.generations = f.generations;
  o->ga_real.stall_generations = f.stall;
  o->ga_binary.ga.population_size = f.population;
  o->ga_binary.ga.max_generations = f.generations;
  o->ga_binary.ga.stall_generations = f.stall;
  o->de.population = f.population;
  o->de.generations = f.generations;
  o->de.stall_generations = f.stall;
}

void AddInitialStateFlag(CLI::App* cmd, std::string* value) {
  const char* dflt = model::InitialStateName(records::FamilyOptions{}.initial_state);
  cmd->add_option("--initial-state", *value,
                  "the memory at rest at the first sample's drive of " + records::FamilyList(true) +
                      std::string(": centred (demagnetised), descended (the drive came down to "
                                  "the rest from the top of its range: a stack resting at the "
                                  "bottom of its range after use), ascended, or auto (descended "
                                  "for a rest at the bottom of the training drive range, ascended "
                                  "at its top, else centred; resolved on each record's first "
                                  "drive; docs/records.md)"))
      ->type_name("NAME")
      ->default_str(dflt);
}

model::InitialState InitialStateOfFlag(const std::string& value, const std::string& family) {
  const model::InitialState dflt = records::FamilyOptions{}.initial_state;
  if (value.empty()) return dflt;
  const model::InitialState s = model::ParseInitialState(value, "--initial-state");
  if (!records::TakesInitialState(family) && s != model::InitialState::kCentred) {
    throw InputError("--initial-state " + value + ": family " + family +
                     " starts centred (the flag applies to " + records::FamilyList(true) + ")");
  }
  return s;
}

}  // namespace pz::client
