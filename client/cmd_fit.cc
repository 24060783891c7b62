// `piezoid fit`: identify one plant family on a record set of any drive (issue 14, records/fit.h),
// and `piezoid records`: check and describe a record set (io/records.h). Before the fit, the
// excitation report (records/excitation.h): what the training records excite, what each withheld
// record needs beyond it, and a proposed training drive. What the fit writes (report.md, fit.json,
// traces, figures) is reports/fit_report.h's.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "client/commands.h"
#include "client/search_flags.h"
#include "client/service_flags.h"
#include "io/csv.h"
#include "io/records.h"
#include "model/preisach.h"
#include "records/excitation.h"
#include "records/extrapolation.h"
#include "records/fit.h"
#include "records/registry.h"
#include "records/select.h"
#include "reports/excitation_report.h"
#include "reports/fit_report.h"
#include "reports/plots.h"
#include "reports/record_windows.h"
#include "reports/residual_spectrum_report.h"
#include "reports/select_report.h"
#include "svcclient/complete_service.h"

namespace pz::client {
namespace fs = std::filesystem;
namespace {

/// The families `--family auto` tries when none are named (records::FamilyDef::auto_grid).
std::string AutoGridList() {
  std::string s;
  for (const records::FamilyDef* f : records::Families())
    if (f->auto_grid) s += (s.empty() ? "" : ", ") + std::string(f->name);
  return s;
}

std::string Fmt(double x, int prec = 4) {
  std::ostringstream s;
  s << std::setprecision(prec) << x;
  return s.str();
}

struct FitArgs {
  std::string records;
  // The default is the choice by cross-validation: on the real-like stack it chose the model the
  // whole grid fitted by hand ranks first (docs/performance.md, "fit --family auto").
  std::string family = "auto";
  std::vector<std::string> effects;
  std::vector<std::string> train_windows, validate_windows, test_windows;
  double settle_s = 0;
  std::string initial_state;  ///< --initial-state (empty: the default)
  std::string out = "fit-out";
  std::string algorithm = "pso";
  SearchFlags search;
  int threads = 2;
  int substeps = 2;
  int pi_operators = 12;
  std::string pi_operators_text = "12";  ///< --pi-operators: a count, or auto (preisach)
  int lm_iterations = 60;
  std::string lm_differences =
      "auto";  ///< the polish's Jacobian: auto, forward-central, forward or central
  bool no_polish = false;
  bool no_figures = false;
  bool quiet = false;
  CompleteServiceFlags service;  ///< --master: the global search's evaluations on the service
  records::FitOptions::Sizing
      sizing;  ///< the PSO budget sized by the searched parameters, but for the flags given
  opt::LineOptions line;  ///< --line-grid, --line-brackets, --line-tolerance
  // --family auto (records/select.h)
  bool pi_operators_given = false;         ///< --pi-operators: the one resolution tried
  std::vector<std::string> auto_families;  ///< --auto-families (empty: the registry's auto grid)
  int folds = 5;
  int finalists = 4;
  bool selected = false;  ///< the report's family was chosen by --family auto
};

/// The fit's options of the flags (--family auto: the selection's fit options), checked: the
/// families of --auto-families, --initial-state, the preisach grid's bound on --pi-operators.
records::FitOptions FitOptionsOf(const FitArgs& a) {
  const bool select = a.family == "auto";
  records::FitOptions o;
  o.family = a.family;
  for (const auto& e : a.effects) o.effects.push_back(records::ParseEffect(e));
  o.family_options.substeps = a.substeps;
  o.family_options.pi_operators = a.pi_operators;
  if (select) {
    if (!a.initial_state.empty())
      o.family_options.initial_state = model::ParseInitialState(a.initial_state, "--initial-state");
    for (const auto& f : a.auto_families)
      if (records::FindFamily(f) == nullptr)
        throw InputError("--auto-families '" + f +
                         "': not a family (families: " + records::FamilyList() + ")");
  } else {
    if (!a.auto_families.empty()) throw InputError("--auto-families: only with --family auto");
    o.family_options.initial_state = InitialStateOfFlag(a.initial_state, a.family);
  }
  // The grid's own bound, refused under the flag's name.
  if ((a.family == "preisach" || (select && a.pi_operators_given)) &&
      a.pi_operators != records::kAutoLevels) {
    const Status levels = model::PreisachGrid{0, 1, a.pi_operators}.Validate();
    if (!levels.ok() && (!select || a.auto_families.empty() ||
                         std::find(a.auto_families.begin(), a.auto_families.end(), "preisach") !=
                             a.auto_families.end()))
      throw InputError("--pi-operators " + std::to_string(a.pi_operators) + ": " +
                       levels.message());
  }
  if (a.service.enabled() && !select)
    o.evaluator_factory =
        svcclient::RecordsServiceFactory(a.service.Options(), o.family_options, "piezoid fit");
  o.search.algorithm = opt::ParseSearchAlgorithm(a.algorithm);
  ApplySearchFlags(a.search, &o.search);
  o.search.line = a.line;
  o.sizing = a.sizing;
  o.polish_repetitions = true;
  o.polish = !a.no_polish;
  o.lm.max_iterations = a.lm_iterations;
  o.lm.central = a.lm_differences == "central";
  o.lm.central_to_finish = a.lm_differences == "forward-central";
  o.lm_differences_auto = a.lm_differences == "auto";
  o.threads = a.threads;
  if (!a.quiet) o.progress = [](const std::string& s) { std::cout << "  " << s << std::endl; };
  return o;
}

/// The fit, or with --family auto the selection and its fit (`a` then names the chosen family,
/// resolution and effects). A service error is printed and its exit code returned.
std::optional<int> FitOrSelect(const io::RecordSet& set, const records::FitOptions& o, FitArgs& a,
                               records::FitResult& r, records::SelectionResult& selection) {
  const bool select = a.family == "auto";
  try {
    if (select) {
      records::SelectOptions so;
      so.fit = o;
      so.fit.progress = nullptr;
      so.initial_state_given = !a.initial_state.empty();
      so.families = a.auto_families;
      if (a.pi_operators_given) so.levels = {a.pi_operators};
      if (!o.effects.empty()) so.effect_sets = {o.effects};
      so.folds = a.folds;
      so.finalists = static_cast<size_t>(a.finalists);
      if (a.service.enabled()) {
        const svcclient::ServiceEvaluatorOptions service = a.service.Options();
        so.service = [service](const records::FamilyOptions& f) {
          return svcclient::RecordsServiceFactory(service, f, "piezoid fit --family auto");
        };
      }
      if (!a.quiet) so.progress = [](const std::string& s) { std::cout << "  " << s << std::endl; };
      selection = records::SelectModel(set, so);
      r = selection.fit;
      a.family = r.model->family().name();
      a.pi_operators = selection.fit_options.family_options.pi_operators;
      a.effects.clear();
      for (records::EffectKind e : r.model->effects()) a.effects.push_back(records::EffectName(e));
      a.selected = true;
      reports::PrintSelection(std::cout, set, selection);
    } else {
      r = records::FitRecords(set, o);
    }
  } catch (const svcclient::ServiceError& e) {
    std::cerr << "piezoid fit: error: " << e.what() << "\n";
    return ExitCodeOf(e.status());
  }
  return std::nullopt;
}

int RunFit(const FitArgs& args) {
  FitArgs a = args;  // --family auto: the chosen family and resolution replace the flag's
  const bool select = a.family == "auto";
  io::RecordSet set = reports::LoadRecordSetWithWindows(
      a.records, a.train_windows, a.validate_windows, a.test_windows, a.settle_s);
  const records::FitOptions o = FitOptionsOf(a);
  std::cout << "piezoid fit: " << set.records.size() << " record(s) from " << a.records << " ("
            << set.format << "), family " << a.family << std::endl;
  const records::ExcitationReport excitation = records::AnalyseExcitation(set);
  const records::TrainingDriveProposal proposal = records::ProposeTrainingDrive(set, excitation);
  reports::PrintExcitationSummary(std::cout, set, excitation);
  records::FitResult r;
  records::SelectionResult selection;
  if (const std::optional<int> code = FitOrSelect(set, o, a, r, selection)) return *code;
  const std::vector<records::ExtrapolationCheck> extrapolation =
      records::CheckExtrapolation(set, r);
  const reports::FitReportRun run{.records = a.records,
                                  .family = a.family,
                                  .selected = a.selected,
                                  .settle_s = a.settle_s,
                                  .substeps = a.substeps,
                                  .pi_operators = a.pi_operators,
                                  .out = a.out,
                                  .figures = !a.no_figures,
                                  .master = a.service.master};
  const std::vector<std::string> warnings = reports::WriteFitFolder(
      set, r, run, excitation, proposal, extrapolation, select ? &selection : nullptr);
  for (const auto& w : warnings) std::cerr << "piezoid fit: warning: " << w << "\n";
  reports::PrintFitSummary(std::cout, set, r, run, extrapolation);
  return 0;
}

}  // namespace

namespace {

constexpr const char* kPiOperatorsRule = "must be a count in 1 … 10000, or auto (preisach)";

/// --pi-operators as a count 1 … 10000 (the whole text a number), or none.
std::optional<int> PiOperatorsCount(const std::string& text) {
  size_t used = 0;
  int n = 0;
  try {
    n = std::stoi(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != text.size() || n < 1 || n > 10000) return std::nullopt;
  return n;
}

/// One searched parameter: the line search's budget (records::FitOptions::Sizing,
/// opt::LineOptions): --line-grid, --line-brackets, --line-tolerance.
void AddLineFlags(CLI::App* cmd, opt::LineOptions* out) {
  const opt::LineOptions line;
  cmd->add_option("--line-grid", out->grid,
                  "one searched parameter (the default search then): grid points over its range, "
                  "ends included")
      ->check(CLI::Range(3, 100000))
      ->default_str(std::to_string(line.grid));
  cmd->add_option(
         "--line-brackets", out->brackets,
         "one searched parameter: the grid's lowest local minima refined by Brent's method")
      ->check(CLI::Range(1, 100000))
      ->default_str(std::to_string(line.brackets));
  cmd->add_option("--line-tolerance", out->tolerance,
                  "one searched parameter: Brent's tolerance, a fraction of the range, in (0, 0.5)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            double x = 0;
            if (!CLI::detail::lexical_cast(v, x) || !(x > 0 && x < 0.5))
              return "Value " + v + " not in (0, 0.5)";
            return "";
          },
          "in (0, 0.5)"))
      ->default_str(io::FormatNumber(line.tolerance));
}

}  // namespace

void RegisterFit(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<FitArgs>();
  CLI::App* cmd =
      app.add_subcommand("fit",
                         "Identify a plant family on measured records of any drive (a record-set "
                         "folder with manifest.csv, "
                         "a stack or fin bench folder, or one CSV file with windows): global "
                         "search + Levenberg-Marquardt, "
                         "offsets explicit; writes report.md, fit.json, traces and loop figures.");
  cmd->add_option("--records", a->records,
                  "record set: folder (manifest.csv) or one CSV (time, drive, response)")
      ->required()
      ->type_name("PATH");
  cmd->add_option("--family", a->family,
                  "auto (chosen with its effects, plays / levels and initial state by blocked "
                  "cross-validation on the training records; records/select.h), " +
                      records::FamilyList())
      ->default_str("auto");
  cmd->add_option(
         "--auto-families", a->auto_families,
         "--family auto: the families tried (comma-separated; default " + AutoGridList() + ")")
      ->delimiter(',');
  cmd->add_option("--folds", a->folds,
                  "--family auto: blocks per training window (the cross-validation's folds)")
      ->check(CLI::Range(2, 50))
      ->default_str("5");
  cmd->add_option(
         "--finalists", a->finalists,
         "--family auto: the screening round's best cross-validated again with the full search")
      ->check(CLI::Range(1, 100))
      ->default_str("4");
  cmd->add_option("--effects", a->effects, "effects added to the family (comma-separated)")
      ->delimiter(',');
  cmd->add_option("--train-window", a->train_windows,
                  "one CSV: a training window START:END [s] (repeatable)");
  cmd->add_option("--validate-window", a->validate_windows,
                  "one CSV: a withheld validation window START:END [s]");
  cmd->add_option("--test-window", a->test_windows,
                  "one CSV: a withheld test window START:END [s]");
  cmd->add_option("--settle-s", a->settle_s,
                  "score every record from this long after the end of its rest [s] (the models "
                  "start at rest with the "
                  "memory of --initial-state; docs/records.md)")
      ->check(CLI::Range(0.0, 1e6));
  AddInitialStateFlag(cmd, &a->initial_state);
  cmd->add_option("--out", a->out, "output folder")->default_str("fit-out");
  cmd->add_option("--algorithm", a->algorithm,
                  "pso, ga-real, ga-binary, de or line (one searched parameter)")
      ->default_str("pso; line for one searched parameter");
  AddSearchFlags(cmd, &a->search, /*sized=*/true);
  AddLineFlags(cmd, &a->line);
  cmd->add_option("--lm-iterations", a->lm_iterations, "Levenberg-Marquardt polish iterations")
      ->default_str("60");
  cmd->add_option(
         "--lm-differences", a->lm_differences,
         "the polish's Jacobian: auto (forward after the line search of one parameter, else "
         "forward-central), forward-central (forward differences, p + 1 evaluations, until the "
         "polish "
         "converges, then central ones from there until it converges again), forward, or central "
         "(2 p)")
      ->check(CLI::IsMember({"auto", "forward-central", "forward", "central"}))
      ->default_str("auto");
  cmd->add_flag("--no-polish", a->no_polish, "no Levenberg-Marquardt after the search");
  cmd->add_option("--threads", a->threads, "evaluation threads")->default_str("2");
  cmd->add_option("--substeps", a->substeps, "integration sub-steps per sample (1 … 512)")
      ->default_str("2");
  cmd->add_option("--pi-operators", a->pi_operators_text,
                  "Prandtl-Ishlinskii / asymmetric-pi play operators (1 … 10000); preisach grid "
                  "levels (1 … 200), or auto: the levels chosen by cross-validation on the "
                  "training records")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            if (v == "auto" || PiOperatorsCount(v)) return "";
            return std::string(kPiOperatorsRule) + ", not " + v;
          },
          "COUNT|auto"))
      ->default_str("12");
  cmd->add_flag("--no-figures", a->no_figures, "no figures (the trace CSVs are still written)");
  cmd->add_flag("--quiet", a->quiet, "no progress lines");
  AddCompleteServiceFlags(cmd, a->service);  // --master: the same result, bit for bit
  cmd->callback([a, cmd, &exit_code] {
    // The PSO budget is sized by the searched parameters (records::SizedSearchBudget) but for the
    // search flags given.
    a->sizing.enabled = true;
    a->sizing.keep_particles = cmd->count("--particles") > 0;
    a->sizing.keep_iterations = cmd->count("--iterations") > 0;
    a->sizing.keep_stall = cmd->count("--stall") > 0;
    a->sizing.keep_repetitions = cmd->count("--repetitions") > 0;
    a->sizing.keep_algorithm = cmd->count("--algorithm") > 0;
    a->sizing.line_given = cmd->count("--line-grid") > 0 || cmd->count("--line-brackets") > 0 ||
                           cmd->count("--line-tolerance") > 0;
    // --pi-operators: a count 1 … 10000, or auto for the preisach grid (its levels by validation).
    const std::string& ops = a->pi_operators_text;
    if (ops == "auto") {
      if (a->family != "preisach")
        throw InputError(
            "--pi-operators auto: the levels chosen by validation are the preisach "
            "family's; give a count for " +
            a->family);
      a->pi_operators = records::kAutoLevels;
    } else {
      const std::optional<int> n = PiOperatorsCount(ops);
      if (!n) throw InputError("--pi-operators " + ops + ": " + kPiOperatorsRule);
      a->pi_operators = *n;
    }
    a->pi_operators_given = cmd->count("--pi-operators") > 0;
    exit_code = RunFit(*a);
  });
}

void RegisterRecords(CLI::App& app, int& exit_code) {
  auto path = std::make_shared<std::string>();
  auto convert = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "records",
      "Check a record set and describe it (records, roles, windows, units, rest, sample rate, "
      "quantum, repeat groups, the noise floor); --convert writes it in the manifest format.");
  cmd->add_option("path,--records", *path, "record set folder or CSV file")->required();
  cmd->add_option("--convert", *convert, "write the set as a manifest-format folder");
  cmd->callback([path, convert, &exit_code] {
    const io::RecordSet set = io::LoadRecordSet(*path);
    std::cout << set.source.string() << ": " << set.format << ", " << set.records.size()
              << " record(s), drive in " << set.drive_unit << ", response in " << set.response_unit
              << "\n";
    const int name_width = reports::NameColumnWidth(set),
              role_width = reports::RoleColumnWidth(set);
    for (const io::Record& r : set.records) {
      std::cout << "  " << std::left << std::setw(name_width) << r.name << std::setw(role_width)
                << model::CaseRoleName(r.role) << r.size() << " samples at "
                << Fmt(r.sample_rate_hz(), 6) << " Hz, scored " << Fmt(r.t[r.first_scored]) << "–"
                << Fmt(r.t[r.end_scored - 1]) << " s (" << r.scored() << "), rest "
                << Fmt(r.rest_samples * r.dt) << " s, offset " << io::OffsetModeName(r.offset_mode);
      if (r.offset_mode != io::OffsetMode::kFit) std::cout << " " << Fmt(r.offset);
      if (r.quantum > 0) std::cout << ", quantum " << Fmt(r.quantum);
      if (!r.repeat.empty()) std::cout << ", repeat group " << r.repeat;
      std::cout << "\n";
    }
    // The noise floor from the records alone (records/noise_floor.h): every estimate.
    try {
      const records::NoiseFloor nf = records::EstimateNoiseFloor(set);
      std::cout << "noise floor " << nf.Summary(set.response_unit) << "\n";
      for (const records::NoiseEstimate& e : nf.estimates)
        std::cout << "  " << e.method << ": " << Fmt(e.sigma) << " " << set.response_unit << " ("
                  << e.samples << " samples; " << e.detail << ")\n";
      if (!nf.warning.empty()) std::cout << "  warning: " << nf.warning << "\n";
    } catch (const InputError& e) {
      std::cout << "noise floor: none (" << e.what() << ")\n";
    }
    if (!convert->empty()) {
      io::WriteRecordSet(set, *convert);
      std::cout << "written to " << *convert << "\n";
    }
    exit_code = 0;
  });
}

}  // namespace pz::client
