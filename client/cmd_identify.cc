// `piezoid identify`: HGANN identification on one machine.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <string>

#include "client/commands.h"
#include "client/data_root.h"
#include "reports/identify_report.h"

namespace pz::client {
namespace {

std::filesystem::path DefaultCasesDir() { return BundledData("bimorph-fin/nominal"); }

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
    const int filled =
        max_generations > 0 ? static_cast<int>(width * g.generation / max_generations) : width;
    std::string bar(filled, '#');
    bar.resize(width, '.');
    const std::string islands = reports::IslandsBrief(g);
    std::fprintf(
        stderr, "%s[%s] gen %llu/%d  best %.5g  mean %.4g  stall %d  %.0f eval/s  %s%s  %.0f s%s",
        tty ? "\r" : "", bar.c_str(), static_cast<unsigned long long>(g.generation),
        max_generations, g.best_cost, g.mean_cost, g.stall, rate,
        g.best_description.substr(0, 5).c_str(), islands.c_str(), elapsed, tty ? "   " : "\n");
    std::fflush(stderr);
  }
};

}  // namespace

namespace {

/// The command's flags as the callback reads them.
struct IdentifyFlags {
  reports::IdentifyOptions opts;
  std::string cases, out, preset = std::string(hgann::kDefaultSearchPreset), topology;
  std::vector<std::string> next_candidates;  ///< --next-candidates, "V:f" each
  bool no_plots = false;
  std::map<std::string, std::string, std::less<>> flag_of;  ///< GaOptions field → its flag
  std::map<std::string, CLI::Option*, std::less<>> given;  ///< field → its option (set by a preset)
};

/// The GA's options, each with the GaOptions member it sets: a bad value is reported under its
/// flag.
void AddGaOptions(CLI::App* cmd, IdentifyFlags& f) {
  const auto ga_option = [&](const char* flag, const char* field, auto& value,
                             const std::string& help) {
    f.flag_of[field] = flag;
    f.given[field] = cmd->add_option(flag, value, help)->capture_default_str();
  };
  opt::GaOptions& ga = f.opts.ga;
  ga_option("--seed", "seed", ga.seed, "seed of the GA's generator");
  ga_option("--population", "population_size", ga.population_size,
            "individuals per generation, per island (paper: 400)");
  ga_option("--generations", "max_generations", ga.max_generations,
            "maximum generations (robust: 250; paper: 1000)");
  ga_option("--stall", "stall_generations", ga.stall_generations,
            "stop after this many generations without improvement of the best over the islands "
            "(robust: 30 generations in which none lowers the best by more than a relative 1e-6; "
            "paper: 200, any lower cost; 0 = never)");
  ga_option("--elite", "elite_fraction", ga.elite_fraction,
            "share of the population kept unchanged (paper: 0.5)");
  ga_option("--mutation", "mutation_probability", ga.mutation_probability,
            "per-bit mutation probability (paper: 0.01)");
  ga_option("--islands", "islands", ga.islands,
            "populations of --population each, bred apart and evaluated together (1 = one "
            "population, the paper's; robust: 4)");
  ga_option(
      "--migration-interval", "migration_interval", ga.migration_interval,
      "generations between migrations of the islands' best (0 = never: independent runs, best "
      "kept)");
  ga_option("--migrants", "migrants", ga.migrants, "individuals each island sends per migration");
  f.topology = opt::TopologyName(ga.topology);
  ga_option("--topology", "topology", f.topology,
            "who sends migrants to whom: ring, fully_connected, random (seeded)");
  ga_option("--migration-margin", "migration_margin", ga.migration_margin,
            "an island takes migrants only from sources whose best is below its own by more than "
            "this share of it, [0, 1) (0 = from every source)");
  ga_option(
      "--broadcast-interval", "broadcast_interval", ga.broadcast_interval,
      "generations between gated broadcasts: each island takes the best --migrants of every "
      "other island better than its own by more than --broadcast-margin (0 = none; skipped at "
      "a migration's generation)");
  ga_option("--broadcast-margin", "broadcast_margin", ga.broadcast_margin,
            "the broadcast's gate: a source's best must be below the island's by more than this "
            "share of it, (0, 1)");
  ga_option("--island-stall", "island_stall_generations", ga.island_stall_generations,
            "restart an island (its sources' migrants + fresh random individuals) after this many "
            "generations without a better best of its own (0 = never)");
  f.flag_of["island_mutation"] = "--island-mutation";
  cmd->add_option(
         "--island-mutation", ga.island_mutation,
         "per-bit mutation probability of each island, one per island, comma-separated "
         "(e.g. 0.01,0.01,0.01,0.01; default with several islands: the ladder --mutation × "
         "1, 2, 3, 5, repeated, which at 0.01 is 0.01,0.02,0.03,0.05)")
      ->delimiter(',');
  f.flag_of["output_moves"] = "--output-moves";
  cmd->add_option("--output-moves", ga.output_moves,
                  "offspring per island and generation made by a step of the network's outputs in "
                  "the model's parameter space instead of crossover and mutation, 0 … population − "
                  "elite (default -1: 0 with one island, the paper's GA; with several and a "
                  "--spread-penalty, 16 % of the offspring, 32 of the paper's 200)")
      ->capture_default_str();
}

/// The model's options and the search preset.
void AddModelOptions(CLI::App* cmd, IdentifyFlags& f) {
  cmd->add_option("--preset", f.preset,
                  "search settings: 'robust' (the default: 4 islands x 250 generations, spread "
                  "penalty 10 deg², generation 0 seeded with networks fitted to per-case fits of "
                  "the training cases, output moves; docs/performance.md, \"Trend seeds\") or "
                  "'paper' (the paper's Table 2: one population, 1000 generations, no penalty, "
                  "uniform bits). A flag given beside it overrides its value")
      ->capture_default_str();
  cmd->add_option("--threads", f.opts.threads, "evaluator threads (0 = all cores)")
      ->capture_default_str();
  cmd->add_option("--ranges", f.opts.ranges,
                  "parameter ranges: 'default' (spec: α∈[0,0.01], β∈[0,0.02], γ∈[-0.02,0.02] …) or "
                  "'paper' (Table 3: α, β, γ ∈ [-0.1, 0])")
      ->capture_default_str();
  f.given["trend_seeds"] =
      cmd->add_option("--trend-seeds", f.opts.trend_seeds,
                      "true: generation 0 starts with networks fitted to per-case fits of the "
                      "training cases (hgann/trend_seeds.h); false: uniform bits (the paper's GA)")
          ->capture_default_str();
  f.given["spread_penalty"] =
      cmd->add_option("--spread-penalty", f.opts.spread_penalty,
                      "λ [deg²]: adds λ·Σ Var(normalised outputs over the training box) to the "
                      "cost, so that parameters vary over the envelope only where the data pay for "
                      "it (0 = the paper's cost)")
          ->capture_default_str();
}

/// --next-candidates' points, "V:f" each ("750:1"): V [V] and f [Hz] finite and > 0; an error
/// names the flag and the bad point.
std::vector<std::pair<double, double>> ParseNextCandidates(const std::vector<std::string>& points) {
  static constexpr const char* kRule =
      "must be V:f, the amplitude [V] and the frequency [Hz] of a feasible operating point, each "
      "a finite number > 0 (e.g. 750:1)";
  std::vector<std::pair<double, double>> out;
  for (const std::string& point : points) {
    const size_t colon = point.find(':');
    double v = 0, f = 0;
    size_t used_v = 0, used_f = 0;
    bool ok = colon != std::string::npos && colon > 0 && colon + 1 < point.size();
    if (ok) {
      try {
        v = std::stod(point.substr(0, colon), &used_v);
        f = std::stod(point.substr(colon + 1), &used_f);
      } catch (const std::exception&) {
        ok = false;
      }
    }
    ok = ok && used_v == colon && used_f == point.size() - colon - 1 && std::isfinite(v) &&
         v > 0 && std::isfinite(f) && f > 0;
    if (!ok) throw InputError(FieldError("--next-candidates", "\"" + point + "\"", kRule));
    out.emplace_back(v, f);
  }
  if (out.size() > job::kMaxNextCandidates)
    throw InputError(FieldError("--next-candidates", std::to_string(out.size()) + " points",
                                "must be at most " + std::to_string(job::kMaxNextCandidates)));
  return out;
}

/// The command: the preset where no flag says otherwise, the options checked, the run, the report.
void RunIdentifyCommand(IdentifyFlags& f) {
  reports::IdentifyOptions& opts = f.opts;
  opts.cases_dir = f.cases;
  opts.out_dir = f.out;
  opts.plots = !f.no_plots;
  const auto search = hgann::SearchPreset(f.preset);
  if (!search) throw InputError(FieldError("--preset", f.preset, hgann::kSearchPresetRule));
  const auto unset = [&](const char* field) { return f.given.at(field)->count() == 0; };
  if (unset("islands")) opts.ga.islands = search->islands;
  if (unset("max_generations")) opts.ga.max_generations = search->generations;
  if (unset("stall_generations")) opts.ga.stall_generations = search->stall_generations;
  opts.ga.stall_relative = search->stall_relative;
  opts.repair_loops = search->repair_loops;
  if (unset("spread_penalty")) opts.spread_penalty = search->spread_penalty;
  if (unset("trend_seeds")) opts.trend_seeds = search->trend_seeds;
  opts.preset = f.preset;
  opts.next_candidates = ParseNextCandidates(f.next_candidates);
  const auto parsed_topology = opt::ParseTopology(f.topology);
  if (!parsed_topology) {
    throw InputError(FieldError(f.flag_of.at("topology"), f.topology, opt::kTopologyRule));
  }
  opts.ga.topology = *parsed_topology;
  const auto ranges = hgann::RangesPreset(opts.ranges);
  if (!ranges) throw InputError(FieldError("--ranges", opts.ranges, hgann::kRangesPresetRule));
  ThrowIfError(opts.ga.Validate([&f](std::string_view field) {
    const auto it = f.flag_of.find(field);
    return it == f.flag_of.end() ? std::string(field) : it->second;
  }));
  CheckBundledData(opts.cases_dir, "bimorph-fin/nominal", "--cases DIR");
  const io::CaseSet set = io::LoadCaseSet(opts.cases_dir);
  auto config = hgann::HgannConfigFromCaseSet(set, *ranges);
  config.spread_penalty = opts.spread_penalty;
  const hgann::HgannFitness fitness(std::move(config));
  const std::string islands =
      opts.ga.islands > 1 ? " x " + std::to_string(opts.ga.islands) + " islands" : "";
  std::fprintf(stderr,
               "piezoid identify: %zu cases from %s (%zu training), population %d%s, up to %d "
               "generations, seed %llu\n",
               set.cases.size(), opts.cases_dir.string().c_str(), set.Training().size(),
               opts.ga.population_size, islands.c_str(), opts.ga.max_generations,
               static_cast<unsigned long long>(opts.ga.seed));
  Progress progress;
  progress.max_generations = opts.ga.max_generations;
  const auto result =
      hgann::RunIdentify(opts, set, fitness, [&](const opt::GenerationSummary& g) { progress(g); });
  if (progress.tty) std::fprintf(stderr, "\n");
  if (opts.repair_loops)
    std::fprintf(stderr,
                 "loop repair (robust preset): %lld of %lld fresh genomes had an unbounded "
                 "Bouc-Wen loop and were rewritten into the bounded region before evaluation\n",
                 static_cast<long long>(result.repaired),
                 static_cast<long long>(result.summary.evaluations));
  reports::WriteIdentifyReport(opts, set, fitness, result, std::cout);
}

}  // namespace

void RegisterIdentify(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("identify",
                                 "HGANN identification on this machine: train on the case set's "
                                 "training cases, validate on every case, write a result folder");
  auto f = std::make_shared<IdentifyFlags>();
  f->opts.cases_dir = DefaultCasesDir();
  f->opts.out_dir = "piezoid-identify";
  f->cases = f->opts.cases_dir.string();
  f->out = f->opts.out_dir.string();
  cmd->add_option("--cases", f->cases,
                  std::string("bench case set folder (cases.csv + per-case CSV); default under ") +
                      kDataRootHelp)
      ->capture_default_str();
  cmd->add_option("--out", f->out, "result folder (created; files in it are overwritten)")
      ->capture_default_str();
  AddModelOptions(cmd, *f);
  AddGaOptions(cmd, *f);
  // What the preset sets shows as its default in --help (the value is the preset's unless given).
  for (const char* field :
       {"islands", "max_generations", "stall_generations", "spread_penalty", "trend_seeds"})
    f->given.at(field)->default_str("from --preset");
  cmd->add_flag("--no-plots", f->no_plots, "do not render figures (scripts are still written)");
  cmd->add_option("--next-candidates", f->next_candidates,
                  "feasible operating points V:f (amplitude [V], frequency [Hz]), "
                  "comma-separated (e.g. 750:1,600:0.4): the next-case proposal ranks these by "
                  "how much measuring each would narrow what the training cases leave open "
                  "(query by committee; default: the case set's withheld cases)")
      ->delimiter(',');
  cmd->callback([f, &exit_code] {
    RunIdentifyCommand(*f);
    exit_code = 0;
  });
}

}  // namespace pz::client
