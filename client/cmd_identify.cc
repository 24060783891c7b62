// `piezoid identify`: HGANN identification on one machine.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <string>

#include "client/commands.h"
#include "client/identify_report.h"

#ifndef PIEZOID_DATA_DIR
#define PIEZOID_DATA_DIR "data"
#endif

namespace pz::client {
namespace {

std::filesystem::path DefaultCasesDir() {
  if (const char* env = std::getenv("PIEZOID_DATA")) return std::filesystem::path(env) / "bimorph-fin/nominal";
  return std::filesystem::path(PIEZOID_DATA_DIR) / "bimorph-fin/nominal";
}

struct Progress {
  bool tty = isatty(STDERR_FILENO);
  int max_generations = 0;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_print{};

  void operator()(const opt::GenerationSummary& g) {
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    const bool final_line = static_cast<int>(g.generation) >= max_generations;
    if (!final_line && now - last_print < std::chrono::milliseconds(tty ? 200 : 5000)) return;
    last_print = now;
    const double rate = elapsed > 0 ? g.evaluations_total / elapsed : 0;
    const int width = 24;
    const int filled = max_generations > 0 ? static_cast<int>(width * g.generation / max_generations) : width;
    std::string bar(filled, '#');
    bar.resize(width, '.');
    const std::string islands = IslandsBrief(g);
    std::fprintf(stderr, "%s[%s] gen %llu/%d  best %.5g  mean %.4g  stall %d  %.0f eval/s  %s%s  %.0f s%s",
                 tty ? "\r" : "", bar.c_str(), static_cast<unsigned long long>(g.generation), max_generations,
                 g.best_cost, g.mean_cost, g.stall, rate, g.best_description.substr(0, 5).c_str(), islands.c_str(),
                 elapsed, tty ? "   " : "\n");
    std::fflush(stderr);
  }
};

}  // namespace

void RegisterIdentify(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("identify",
                                 "HGANN identification on this machine: train on the case set's training cases, "
                                 "validate on every case, write a result folder");
  auto opts = std::make_shared<IdentifyOptions>();
  opts->cases_dir = DefaultCasesDir();
  opts->out_dir = "piezoid-identify";
  auto cases = std::make_shared<std::string>(opts->cases_dir.string());
  auto out = std::make_shared<std::string>(opts->out_dir.string());
  auto no_plots = std::make_shared<bool>(false);
  cmd->add_option("--cases", *cases, "bench case set folder (cases.csv + per-case CSV)")->capture_default_str();
  cmd->add_option("--out", *out, "result folder (created; files in it are overwritten)")->capture_default_str();
  // The GA's options, each with the GaOptions member it sets: a bad value is reported under its flag.
  auto flag_of = std::make_shared<std::map<std::string, std::string, std::less<>>>();
  auto given = std::make_shared<std::map<std::string, CLI::Option*, std::less<>>>();  // by field
  const auto ga_option = [&](const char* flag, const char* field, auto& value, const std::string& help) {
    (*flag_of)[field] = flag;
    (*given)[field] = cmd->add_option(flag, value, help)->capture_default_str();
  };
  auto preset = std::make_shared<std::string>(hgann::kDefaultSearchPreset);
  cmd->add_option(
         "--preset", *preset,
         "search settings: 'robust' (the default: 4 islands x 250 generations, spread penalty 10 "
         "deg², "
         "generation 0 seeded with networks fitted to per-case fits of the training cases, output "
         "moves; docs/performance.md, \"Trend seeds\") or 'paper' (the paper's Table 2: one "
         "population, "
         "1000 generations, no penalty, uniform bits). A flag given beside it overrides its value")
      ->capture_default_str();
  ga_option("--seed", "seed", opts->ga.seed, "seed of the GA's generator");
  ga_option("--population", "population_size", opts->ga.population_size,
            "individuals per generation, per island (paper: 400)");
  ga_option("--generations", "max_generations", opts->ga.max_generations, "maximum generations (paper: 1000)");
  ga_option("--stall", "stall_generations", opts->ga.stall_generations,
            "stop after this many generations without improvement of the best over the islands (paper: 200; "
            "0 = never)");
  ga_option("--elite", "elite_fraction", opts->ga.elite_fraction, "share of the population kept unchanged (paper: 0.5)");
  ga_option("--mutation", "mutation_probability", opts->ga.mutation_probability,
            "per-bit mutation probability (paper: 0.01)");
  ga_option("--islands", "islands", opts->ga.islands,
            "populations of --population each, bred apart and evaluated together (1 = one population; "
            "4 with --generations 560 and the migration defaults: the measured archipelago, docs/performance.md)");
  ga_option("--migration-interval", "migration_interval", opts->ga.migration_interval,
            "generations between migrations of the islands' best (0 = never: independent runs, best kept)");
  ga_option("--migrants", "migrants", opts->ga.migrants, "individuals each island sends per migration");
  auto topology = std::make_shared<std::string>(opt::TopologyName(opts->ga.topology));
  ga_option("--topology", "topology", *topology, "who sends migrants to whom: ring, fully_connected, random (seeded)");
  ga_option("--migration-margin", "migration_margin", opts->ga.migration_margin,
            "an island takes migrants only from sources whose best is below its own by more than this share "
            "of it, [0, 1) (0 = from every source)");
  ga_option("--broadcast-interval", "broadcast_interval", opts->ga.broadcast_interval,
            "generations between gated broadcasts: each island takes the best --migrants of every other island "
            "better than its own by more than --broadcast-margin (0 = none; skipped at a migration's generation)");
  ga_option("--broadcast-margin", "broadcast_margin", opts->ga.broadcast_margin,
            "the broadcast's gate: a source's best must be below the island's by more than this share of it, (0, 1)");
  ga_option("--island-stall", "island_stall_generations", opts->ga.island_stall_generations,
            "restart an island (its sources' migrants + fresh random individuals) after this many "
            "generations without a better best of its own (0 = never)");
  (*flag_of)["island_mutation"] = "--island-mutation";
  cmd->add_option("--island-mutation", opts->ga.island_mutation,
                  "per-bit mutation probability of each island, one per island, comma-separated (e.g. "
                  "0.01,0.01,0.01,0.01; default with several islands: the ladder --mutation × 1, 2, 3, 5, repeated, "
                  "which at 0.01 is 0.01,0.02,0.03,0.05)")
      ->delimiter(',');
  (*flag_of)["output_moves"] = "--output-moves";
  cmd->add_option("--output-moves", opts->ga.output_moves,
                  "offspring per island and generation made by a step of the network's outputs in the model's "
                  "parameter space instead of crossover and mutation, 0 … population − elite (default -1: 0 with one "
                  "island, the paper's GA; with several and a --spread-penalty, 16 % of the offspring, 32 of the paper's 200: the measured archipelago)")
      ->capture_default_str();
  cmd->add_option("--threads", opts->threads, "evaluator threads (0 = all cores)")->capture_default_str();
  cmd->add_option("--ranges", opts->ranges,
                  "parameter ranges: 'default' (spec: α∈[0,0.01], β∈[0,0.02], γ∈[-0.02,0.02] …) or 'paper' "
                  "(Table 3: α, β, γ ∈ [-0.1, 0])")
      ->capture_default_str();
  (*given)["trend_seeds"] =
      cmd->add_option("--trend-seeds", opts->trend_seeds,
                      "true: generation 0 starts with networks fitted to per-case fits of the "
                      "training cases "
                      "(hgann/trend_seeds.h); false: uniform bits (the paper's GA)")
          ->capture_default_str();
  (*given)["spread_penalty"] = cmd->add_option("--spread-penalty", opts->spread_penalty,
                                               "λ [deg²]: adds λ·Σ Var(normalised outputs over the "
                                               "training box) to the cost, so that "
                                               "parameters vary over the envelope only where the "
                                               "data pay for it (0 = the paper's cost)")
                                   ->capture_default_str();
  // What the preset sets shows as its default in --help (the value is the preset's unless given).
  for (const char* field : {"islands", "max_generations", "spread_penalty", "trend_seeds"})
    given->at(field)->default_str("from --preset");
  cmd->add_flag("--no-plots", *no_plots, "do not render figures (scripts are still written)");
  cmd->callback([=, &exit_code] {
    opts->cases_dir = *cases;
    opts->out_dir = *out;
    opts->plots = !*no_plots;
    {
      // The preset's settings where no flag says otherwise.
      const auto search = hgann::SearchPreset(*preset);
      if (!search) throw InputError(FieldError("--preset", *preset, hgann::kSearchPresetRule));
      const auto unset = [&](const char* field) { return given->at(field)->count() == 0; };
      if (unset("islands")) opts->ga.islands = search->islands;
      if (unset("max_generations")) opts->ga.max_generations = search->generations;
      if (unset("spread_penalty")) opts->spread_penalty = search->spread_penalty;
      if (unset("trend_seeds")) opts->trend_seeds = search->trend_seeds;
      opts->preset = *preset;
    }
    const auto parsed_topology = opt::ParseTopology(*topology);
    if (!parsed_topology) throw InputError(FieldError(flag_of->at("topology"), *topology, opt::kTopologyRule));
    opts->ga.topology = *parsed_topology;
    const auto ranges = hgann::RangesPreset(opts->ranges);
    if (!ranges) throw InputError(FieldError("--ranges", opts->ranges, hgann::kRangesPresetRule));
    ThrowIfError(opts->ga.Validate([flag_of](std::string_view field) {
      const auto it = flag_of->find(field);
      return it == flag_of->end() ? std::string(field) : it->second;
    }));
    const io::CaseSet set = io::LoadCaseSet(opts->cases_dir);
    auto config = hgann::HgannConfigFromCaseSet(set, *ranges);
    config.spread_penalty = opts->spread_penalty;
    const hgann::HgannFitness fitness(std::move(config));
    std::fprintf(stderr, "piezoid identify: %zu cases from %s (%zu training), population %d%s, up to %d generations, seed %llu\n",
                 set.cases.size(), opts->cases_dir.string().c_str(), set.Training().size(), opts->ga.population_size,
                 opts->ga.islands > 1 ? (" x " + std::to_string(opts->ga.islands) + " islands").c_str() : "",
                 opts->ga.max_generations, static_cast<unsigned long long>(opts->ga.seed));
    Progress progress;
    progress.max_generations = opts->ga.max_generations;
    const auto result = hgann::RunIdentify(*opts, set, fitness, [&](const opt::GenerationSummary& g) { progress(g); });
    if (progress.tty) std::fprintf(stderr, "\n");
    WriteIdentifyReport(*opts, set, fitness, result, std::cout);
    exit_code = 0;
  });
}

}  // namespace pz::client
