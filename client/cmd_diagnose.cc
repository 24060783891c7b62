// `piezoid diagnose`: where the sim-to-real gap of a bench lies, which unmodelled effect causes it,
// and how far it shrinks once the effect is in the model (diagnose/fin_diagnose.h DiagnoseBench:
// the records engine on the bench's record set). Writes a terminal summary and the report folder
// (reports/diagnose_report.h, with the bench's grid section). `piezoid diagnose-check`: the same
// diagnosis on random synthetic benches whose effect is withheld from it; prints the confusion
// matrix and the distribution of the share of the gap closed.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "client/commands.h"
#include "client/search_flags.h"
#include "client/service_flags.h"
#include "diagnose/check.h"
#include "diagnose/reallike_check.h"
#include "diagnose/verdict.h"
#include "io/bench_data.h"
#include "io/csv.h"
#include "io/fin_records.h"
#include "records/registry.h"
#include "reports/bench_grid.h"
#include "reports/check_report.h"
#include "reports/diagnose_report.h"
#include "reports/excitation_report.h"
#include "reports/record_windows.h"
#include "reports/select_report.h"
#include "svcclient/complete_service.h"
#include "svcclient/service_evaluator.h"

namespace pz::client {
namespace fs = std::filesystem;
namespace {

/// `piezoid diagnose --records`: its flags.
struct RecordsDiagnoseRequest {
  std::string records;
  std::string family = "auto";  ///< "auto": chosen by records/select.h first (--family not given)
  std::vector<std::string> train_windows, validate_windows, test_windows;
  double settle_s =
      0;  ///< --settle-s: scored from this long after each record's rest (io::SkipSettling)
  std::string initial_state;  ///< --initial-state (empty: FamilyOptions' default)
  std::string out;
  std::string candidates;  ///< comma-separated, empty = every applicable effect
  int threads = 2;
  uint64_t seed = 1;
  bool quick = false;
  bool no_plots = false;
  bool quiet = false;
  double significance_ratio = 1.25;
  records::RecordEvaluatorFactory evaluator_factory;  ///< --master (null: local threads)
  /// --master with --family auto: the factory for a family's options (the chosen resolution's).
  std::function<records::RecordEvaluatorFactory(const records::FamilyOptions&)> service;
};

/// `piezoid diagnose --records`: the diagnosis of diagnose/diagnose.h on a record set of any drive,
/// its report folder by reports/diagnose_report.h.
int RunRecordsDiagnose(const RecordsDiagnoseRequest& a) {
  const io::RecordSet set = reports::LoadRecordSetWithWindows(
      a.records, a.train_windows, a.validate_windows, a.test_windows, a.settle_s);
  diagnose::RecordDiagnoseOptions o;
  o.family = a.family;
  const bool select = a.family == "auto";
  if (select) {
    if (!a.initial_state.empty())
      o.fit.family_options.initial_state =
          model::ParseInitialState(a.initial_state, "--initial-state");
  } else {
    o.fit.family_options.initial_state = InitialStateOfFlag(a.initial_state, a.family);
  }
  o.rules.significance_ratio = a.significance_ratio;
  std::stringstream ss(a.candidates);
  std::string name;
  while (std::getline(ss, name, ','))
    if (!name.empty()) o.candidates.push_back(records::ParseEffect(name));
  o.fit.threads = a.threads;
  o.fit.evaluator_factory = a.evaluator_factory;
  o.fit.search.pso.seed = a.seed;
  if (a.quick) {
    o.fit.search.repetitions = 1;
    o.fit.search.pso.particles = 20;
    o.fit.search.pso.iterations = 60;
    o.fit.lm.max_iterations = 30;
  }
  // No --family: the family, its resolution and initial state chosen by cross-validation on the
  // training records first (records/select.h), the diagnosis then run on it.
  records::SelectionResult selection;
  if (select) {
    records::SelectOptions so;
    so.fit = o.fit;
    so.fit.evaluator_factory = nullptr;
    so.fit.sizing.enabled = !a.quick;  // `piezoid fit`'s search (sized), or the quick one
    so.fit.polish_repetitions = true;
    so.fit.lm_differences_auto = true;
    so.initial_state_given = !a.initial_state.empty();
    so.service = a.service;
    if (!a.quiet) so.progress = [](const std::string& s) { std::cerr << s << std::endl; };
    selection = records::SelectModel(set, so);
    reports::PrintSelection(std::cout, set, selection);
    o.family = selection.fit_options.family;
    o.fit.family_options = selection.fit_options.family_options;
    if (a.service) o.fit.evaluator_factory = a.service(o.fit.family_options);
  }
  if (!a.quiet) o.fit.progress = [](const std::string& s) { std::cerr << s << std::endl; };
  const fs::path out =
      a.out.empty() ? fs::path("diagnose_" + fs::path(a.records).stem().string()) : fs::path(a.out);
  io::PrepareOutputFolder(out, "--out");  // before the run: its work is not lost at the end
  const diagnose::RecordDiagnosis d = diagnose::DiagnoseRecords(set, o);
  std::cout << d.verdict << "\n";
  reports::PrintExcitationSummary(std::cout, set, d.excitation);
  const std::vector<std::string> errors = reports::WriteDiagnosisFolder(
      out, set, d, {.settle_s = a.settle_s, .selection = select ? &selection : nullptr},
      !a.no_plots);
  for (const auto& e : errors) std::cerr << "piezoid diagnose: warning: " << e << "\n";
  std::cout << "written: " << (out / "report.md").string() << ", "
            << (out / "diagnosis.json").string() << "\n";
  return 0;
}

struct DiagnoseArgs {
  std::string cases_dir;
  RecordsDiagnoseRequest records;  ///< --records: a record set of any drive (diagnose/diagnose.h)
  std::string out_dir;
  std::string json_file;
  std::string candidates;
  int threads = 2;
  uint64_t seed = 1;
  bool no_second = false;
  bool no_trends = false;
  bool no_plots = false;
  bool quick = false;
  bool quiet = false;
  double significance_ratio = 1.25;
  CompleteServiceFlags
      service;  ///< --master etc.: evaluate on a piezoid-master's workers (empty: locally)
};

std::vector<model::EffectKind> ParseKinds(const std::string& list) {
  std::vector<model::EffectKind> kinds;
  std::stringstream ss(list);
  std::string name;
  while (std::getline(ss, name, ',')) {
    if (name.empty()) continue;
    const auto k = records::ParseEffectKind(name);
    if (!k || k->none()) throw InputError(records::FinEffectError(name));
    kinds.push_back(*k);
  }
  return kinds;
}

diagnose::DiagnoseOptions Options(const std::string& candidates, int threads, uint64_t seed,
                                  bool quick, double significance_ratio, bool quiet) {
  diagnose::DiagnoseOptions o;
  o.candidates = ParseKinds(candidates);
  o.threads = threads;
  o.seed = seed;
  o.rules.significance_ratio = significance_ratio;
  if (quick) {  // a smaller search: quick looks and tests
    o.de_base.population = 24;
    o.de_base.generations = 40;
    o.de_candidate.population = 24;
    o.de_candidate.generations = 30;
    o.lm.max_iterations = 20;
    o.cvode_lm_iterations = 8;
  }
  if (!quiet) o.progress = [](const std::string& s) { std::cerr << s << std::endl; };
  return o;
}

int RunDiagnose(const DiagnoseArgs& a) {
  if (!a.records.records.empty()) {
    if (!a.cases_dir.empty())
      throw InputError("give either --cases (a fin bench) or --records (any record set), not both");
    RecordsDiagnoseRequest r = a.records;
    if (a.service.enabled()) {
      r.evaluator_factory = svcclient::RecordsServiceFactory(
          a.service.Options(), records::FamilyOptions{}, "piezoid diagnose");
      const svcclient::ServiceEvaluatorOptions service = a.service.Options();
      r.service = [service](const records::FamilyOptions& f) {
        return RecordsServiceFactory(service, f, "piezoid diagnose");
      };
    }
    // (the family's options, its initial state among them, travel with each fit's model:
    // CompleteModelProblemOf)
    r.out = a.out_dir;
    r.candidates = a.candidates;
    r.threads = a.threads;
    r.seed = a.seed;
    r.quick = a.quick;
    r.no_plots = a.no_plots;
    r.quiet = a.quiet;
    r.significance_ratio = a.significance_ratio;
    try {
      return RunRecordsDiagnose(r);
    } catch (const svcclient::ServiceError& e) {
      std::fprintf(stderr, "piezoid diagnose: error: %s\n", e.what());
      return ExitCodeOf(e.status());
    }
  }
  if (a.cases_dir.empty())
    throw InputError(
        "piezoid diagnose needs --cases DIR (a fin bench) or --records PATH --family NAME");
  const std::filesystem::path dir(a.cases_dir);
  const io::RecordSet set = io::RecordsFromCaseSet(io::LoadCaseSet(dir));
  diagnose::DiagnoseOptions o =
      Options(a.candidates, a.threads, a.seed, a.quick, a.significance_ratio, a.quiet);
  o.second_effect = !a.no_second;
  o.trends = !a.no_trends;
  if (a.service.enabled()) {
    // Every fit as complete_model sessions (bimorph-fin's bench form on the workers, bit for bit
    // as locally); bad --master / CURVE flags fail here, before any work.
    const svcclient::ServiceEvaluatorOptions so = a.service.Options();
    o.records_service = [so](const records::FamilyOptions& f) {
      return svcclient::RecordsServiceFactory(so, f, "piezoid diagnose");
    };
  }
  // Where the results go, checked before the run (a run is minutes: its work is not lost at the
  // end).
  const std::filesystem::path out =
      a.out_dir.empty() ? std::filesystem::path("diagnose_" + dir.filename().string())
                        : std::filesystem::path(a.out_dir);
  io::PrepareOutputFolder(out, "--out");
  if (!a.json_file.empty()) io::CheckWritableFile(a.json_file, "--json");
  diagnose::BenchDiagnosis d;
  try {
    // The records engine on the bench's records (with --master: on the workers as
    // complete_model sessions).
    d = diagnose::DiagnoseBench(set, o);
  } catch (const svcclient::ServiceError& e) {
    std::fprintf(stderr, "piezoid diagnose: error: %s\n", e.what());
    return ExitCodeOf(e.status());
  }
  reports::PrintBenchSummary(std::cout, d);
  const reports::DiagnosisReport report{.grid = &d};
  const std::vector<std::string> warnings =
      reports::WriteDiagnosisFolder(out, d.set, d.records, report, !a.no_plots);
  if (!a.json_file.empty()) {
    std::error_code ec;
    fs::copy_file(out / "diagnosis.json", a.json_file, fs::copy_options::overwrite_existing, ec);
    if (ec) throw InputError("--json " + a.json_file + ": cannot write (" + ec.message() + ")");
  }
  for (const auto& w : warnings) std::cerr << "piezoid diagnose: warning: " << w << "\n";
  std::cout << "written: " << (out / "report.md").string() << ", "
            << (out / "diagnosis.json").string() << (a.json_file.empty() ? "" : ", " + a.json_file)
            << " (figures in " << (out / "figures").string() << ")\n";
  return 0;
}

struct CheckArgs {
  std::string
      records_family;  ///< --records-family: the records diagnosis on synthetic records of it
  int trials = 50;
  uint64_t seed = 1;
  int threads = 2;
  std::string json_file;
  std::string candidates;
  std::string kinds;
  double none_probability = 0.2;
  double other_form_probability = 0.3;
  bool second = false;
  bool quick = false;
  double significance_ratio = 1.25;
  bool real_like = false;         ///< --real-like: real-like stack sets (synth/reallike.h) instead
  double real_like_train_s = 20;  ///< their training sine's length
  double real_like_withheld_s = 10;
};

/// The records diagnosis of a check: its rules, threads and (--quick) a smaller search.
diagnose::RecordDiagnoseOptions CheckDiagnoseOptions(const CheckArgs& a) {
  diagnose::RecordDiagnoseOptions d;
  d.rules.significance_ratio = a.significance_ratio;
  d.fit.threads = a.threads;
  if (a.quick) {
    d.fit.search.repetitions = 1;
    d.fit.search.pso.particles = 20;
    d.fit.search.pso.iterations = 60;
    d.fit.lm.max_iterations = 30;
  }
  return d;
}

/// The records diagnosis on real-like stack sets, checked against their truth
/// (diagnose/reallike_check.h).
int RunRealLikeCheckCommand(const CheckArgs& a) {
  diagnose::RealLikeCheckOptions o;
  o.family = a.records_family;
  o.trials = a.trials;
  o.seed = a.seed;
  o.base.train_s = a.real_like_train_s;
  o.base.withheld_s = a.real_like_withheld_s;
  o.diagnose = CheckDiagnoseOptions(a);
  const diagnose::RealLikeCheckSummary s =
      diagnose::RunRealLikeCheck(o, [](const diagnose::RealLikeCheckTrial& t, int i) {
        char floor[300];
        std::snprintf(floor, sizeof floor, "%-52s floor %.4f/%.4f (%s) excitation %-5s [%s]",
                      t.description.c_str(), t.floor_estimate, t.floor_truth, t.floor_used.c_str(),
                      t.excitation_right ? "right" : "WRONG", t.excitation.c_str());
        std::cout << diagnose::TrialLine(
                         i + 1, "", floor, 0, t,
                         t.named == "none" ? ""
                                           : (t.named_present ? " (in truth)" : " (not in truth)"),
                         t.excitation_note ? "; excitation gap said" : "")
                  << std::endl;
      });
  const int n = static_cast<int>(s.trials.size());
  std::cout << "real-like stacks: " << n << "; noise floor estimate / truth " << s.floor_ratio_min
            << " … " << s.floor_ratio_max << "; excitation report right in " << s.excitation_right
            << " of " << n << "; significant gaps " << s.significant << ", excitation gap said in "
            << s.excitation_notes << "; effects named " << s.named << ", of which in the truth "
            << s.named_present << "\n"
            << static_cast<int>(s.wall_time_s) << " s in all\n";
  return 0;
}

/// The check's form: records of a family (--records-family) or fin benches.
diagnose::CheckForm CheckFormOf(const CheckArgs& a) {
  if (!(a.none_probability >= 0 && a.none_probability <= 1))
    throw InputError(FieldError("--none-probability", a.none_probability, "must be in [0, 1]"));
  if (!(a.other_form_probability >= 0 && a.other_form_probability <= 1))
    throw InputError(
        FieldError("--other-form-probability", a.other_form_probability, "must be in [0, 1]"));
  if (!a.records_family.empty()) {
    records::FamilyNamed(a.records_family, "--records-family");  // named by its flag
    diagnose::RecordsCheckOptions o;
    o.trials.family = a.records_family;
    o.trials.none_probability = a.none_probability;
    o.diagnose = CheckDiagnoseOptions(a);
    return diagnose::RecordsCheckForm(o);
  }
  diagnose::DiagnoseOptions o =
      Options(a.candidates, a.threads, a.seed, a.quick, a.significance_ratio, true);
  o.second_effect = a.second;
  o.trends = false;
  synth::FinTrialOptions so;
  so.kinds = ParseKinds(a.kinds);
  so.none_probability = a.none_probability;
  so.other_form_probability = a.other_form_probability;
  return diagnose::FinCheckForm(o, so);
}

int RunCheckCommand(const CheckArgs& a) {
  if (a.real_like && a.records_family.empty())
    throw InputError(
        "diagnose-check --real-like needs --records-family NAME (the family the diagnosis fits)");
  if (a.real_like) return RunRealLikeCheckCommand(a);
  const diagnose::CheckForm form = CheckFormOf(a);
  if (!a.json_file.empty()) io::CheckWritableFile(a.json_file, "--json");
  const diagnose::CheckSummary s =
      diagnose::RunCheck(form, a.trials, a.seed, [&](const diagnose::CheckTrial& t, int i) {
        std::cout << reports::CheckTrialLine(form.text, t, i) << std::endl;
      });
  reports::PrintCheckSummary(std::cout, s);
  if (!a.json_file.empty())
    io::WriteFileWith(a.json_file, [&](std::ostream& out) { reports::WriteCheckJson(out, s); });
  return 0;
}

}  // namespace

void RegisterDiagnose(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<DiagnoseArgs>();
  CLI::App* cmd = app.add_subcommand("diagnose",
                                     "Diagnose the sim-to-real gap of a bench: localise the "
                                     "residual of a global model against the noise floor, "
                                     "re-identify the model with each candidate unmodelled effect "
                                     "on the training cases, score it on the withheld "
                                     "cases, name the effect (or say that no gap is significant) "
                                     "and report how far the gap shrinks.");
  cmd->add_option("--cases", a->cases_dir, "bench case set folder (cases.csv + one CSV per case)")
      ->type_name("DIR");
  cmd->add_option("--records", a->records.records,
                  "instead of --cases: any record set (folder with manifest.csv, a stack or fin "
                  "bench folder, or one "
                  "CSV with windows), diagnosed for --family")
      ->type_name("PATH");
  cmd->add_option("--family", a->records.family,
                  "with --records: auto (chosen with its resolution and initial state by blocked "
                  "cross-validation on "
                  "the training records first, as `piezoid fit --family auto`), " +
                      records::FamilyList())
      ->default_str("auto");
  cmd->add_option("--train-window", a->records.train_windows,
                  "with one CSV: a training window START:END [s]");
  cmd->add_option("--validate-window", a->records.validate_windows,
                  "with one CSV: a withheld window START:END [s]");
  cmd->add_option("--test-window", a->records.test_windows,
                  "with one CSV: a withheld test window START:END [s]");
  cmd->add_option("--settle-s", a->records.settle_s,
                  "with --records: score every record from this long after the end of its rest [s] "
                  "(the models start "
                  "at rest with the memory of --initial-state; docs/records.md)")
      ->check(CLI::Range(0.0, 1e6));
  AddInitialStateFlag(cmd, &a->records.initial_state);
  cmd->add_option("--out", a->out_dir, "report folder (default: diagnose_<set name>)")
      ->type_name("DIR");
  cmd->add_option("--json", a->json_file, "also write the diagnosis JSON to this file")
      ->type_name("FILE");
  cmd->add_option("--candidates", a->candidates,
                  "comma-separated effects to try (default: the whole library: driver-lowpass, "
                  "creep, hinge-friction, "
                  "delay, cubic-stiffening, quadratic-drive, drift)")
      ->type_name("LIST");
  cmd->add_option("--threads", a->threads, "evaluator threads")->check(CLI::Range(1, 256));
  cmd->add_option("--seed", a->seed, "seed of the global searches");
  cmd->add_option("--significance-ratio", a->significance_ratio,
                  "withheld RMS / noise floor above which a gap is significant")
      ->check(CLI::Range(1.0001, 100.0));
  cmd->add_flag("--no-second", a->no_second, "do not look for a second effect");
  cmd->add_flag("--no-trends", a->no_trends, "skip the per-case fits and their V x f trends");
  cmd->add_flag("--no-plots", a->no_plots, "write the figure scripts but do not run gnuplot");
  cmd->add_flag("--quick", a->quick, "smaller global searches (a quick look)");
  cmd->add_flag("--quiet", a->quiet, "no progress lines on stderr");
  AddCompleteServiceFlags(
      cmd, a->service);  // --master, --timeout-ms, --retries, --curve-secret, --master-public
  cmd->callback([a, &exit_code] { exit_code = RunDiagnose(*a); });
}

void RegisterDiagnoseCheck(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<CheckArgs>();
  CLI::App* cmd = app.add_subcommand("diagnose-check",
                                     "Check the diagnosis on synthetic benches: the bench plant "
                                     "with an effect drawn at random from the library "
                                     "(random magnitude and seed, sometimes in a functional form "
                                     "the library lacks) or none, quantised and noisy "
                                     "like the encoder; the effect is withheld from the model; "
                                     "prints the confusion matrix (true x named effect) "
                                     "and the distribution of the share of the gap closed.");
  cmd->add_option("--trials", a->trials, "number of benches")->check(CLI::Range(1, 100000));
  std::string checkable;
  for (const std::string& name : synth::RecordsTrialFamilies())
    checkable += (checkable.empty() ? "" : ", ") + name;
  cmd->add_option("--records-family", a->records_family,
                  "check the records diagnosis instead (diagnose --records) on synthetic records "
                  "of this family: " +
                      checkable);
  cmd->add_flag("--real-like", a->real_like,
                "with --records-family: diagnose real-like stack record sets (synth-stack: a "
                "Preisach plant with log "
                "creep and sensor lag, not a family of the product) and check the floor, the "
                "excitation report and "
                "the named effect against their truth");
  cmd->add_option("--real-like-train-s", a->real_like_train_s,
                  "with --real-like: training sine length [s]")
      ->check(CLI::Range(2.0, 1000.0));
  cmd->add_option("--real-like-withheld-s", a->real_like_withheld_s,
                  "with --real-like: withheld record length [s]")
      ->check(CLI::Range(2.0, 1000.0));
  cmd->add_option("--seed", a->seed, "first bench seed (bench i uses seed + i)");
  cmd->add_option("--threads", a->threads, "evaluator threads")->check(CLI::Range(1, 256));
  cmd->add_option("--json", a->json_file, "write the trials and the matrix as JSON")
      ->type_name("FILE");
  cmd->add_option("--candidates", a->candidates,
                  "effects the diagnosis tries (default: the library)")
      ->type_name("LIST");
  cmd->add_option("--kinds", a->kinds, "effects drawn for the benches (default: the library)")
      ->type_name("LIST");
  cmd->add_option("--none-probability", a->none_probability, "share of clean benches");
  cmd->add_option("--other-form-probability", a->other_form_probability,
                  "share of effects drawn in a form the library lacks (second-order amplifier, two "
                  "creep relaxations)");
  cmd->add_option("--significance-ratio", a->significance_ratio, "as for diagnose")
      ->check(CLI::Range(1.0001, 100.0));
  cmd->add_flag("--second", a->second, "also run the greedy search for a second effect");
  cmd->add_flag("--quick", a->quick, "smaller global searches");
  cmd->callback([a, &exit_code] { exit_code = RunCheckCommand(*a); });
}

}  // namespace pz::client
