// `piezoid committee`: the committee machine of seed 002 on a record set whose records state their
// excitation frequency (default: the bundled stack bench data/piezo-stack-bench; any records/
// families.h family): complete models and per-band sub-models of each family by each
// optimiser, selection per band, the committee against the best complete model; writes report.md,
// committee.json and loop figures (complete/committee.h, reports/committee_report.h).
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "client/commands.h"
#include "client/data_root.h"
#include "client/search_flags.h"
#include "client/service_flags.h"
#include "complete/committee.h"
#include "io/csv.h"
#include "records/registry.h"
#include "reports/committee_report.h"
#include "svcclient/complete_service.h"

namespace pz::client {
using namespace complete;
namespace {

struct CommitteeArgs {
  std::string records = BundledData("piezo-stack-bench").string();
  std::string out = "committee-out";
  std::string bands = "0,50,150,250,350";
  std::vector<std::string> families{"stack-bouc-wen", "backlash-like"};
  std::vector<std::string> optimisers{"pso", "ga-real"};
  std::string criterion = "iae";
  double t0 = 0.5, t1 = 2.5;
  SearchFlags search{.repetitions = 5};
  int substeps = 2;
  std::string initial_state;  ///< --initial-state (empty: FamilyOptions' default, auto)
  int threads = 0;
  bool averaging = false;
  bool no_figures = false;
  bool quiet = false;
  CompleteServiceFlags service;  ///< --master: every search's evaluations on the service
};

int RunCommitteeCommand(const CommitteeArgs& a) {
  CommitteeOptions o;
  o.bands = FrequencyBands::Parse(a.bands);
  o.families = a.families;
  o.algorithms.clear();
  for (const std::string& s : a.optimisers) o.algorithms.push_back(opt::ParseSearchAlgorithm(s));
  o.criterion = records::ParseCriterion(a.criterion);
  o.t0_s = a.t0;
  o.t1_s = a.t1;
  o.family_options.substeps = a.substeps;
  // One state for every family on the committee; an explicit one a family cannot take is an error.
  for (const std::string& f : a.families)
    o.family_options.initial_state = InitialStateOfFlag(a.initial_state, f);
  o.averaging = a.averaging;
  ApplySearchFlags(a.search, &o.search);
  ThrowIfError(o.Validate());

  io::RecordReadOptions ro;
  ro.check_stated_drive = true;
  CheckBundledData(a.records, "piezo-stack-bench", "--records PATH");
  const io::RecordSet set = io::LoadRecordSet(a.records, ro);
  std::cout << "piezoid committee: " << set.records.size() << " records from " << a.records << ", "
            << o.bands.size() << " bands, " << o.families.size() << " famil"
            << (o.families.size() == 1 ? "y" : "ies") << " x " << o.algorithms.size()
            << " optimiser(s), " << o.search.repetitions << " repetitions each" << std::endl;
  CommitteeLog log;
  if (!a.quiet) log = [](const std::string& line) { std::cout << "  " << line << std::endl; };
  const EvaluatorFactory factory = a.service.enabled() ? svcclient::CommitteeServiceFactory(
                                                             a.service.Options(), o.family_options)
                                                       : LocalEvaluatorFactory(a.threads);
  CommitteeResult r;
  try {
    r = RunCommittee(set, o, factory, log);
  } catch (const svcclient::ServiceError& e) {
    std::cerr << "piezoid committee: error: " << e.what() << "\n";
    return ExitCodeOf(e.status());
  }

  namespace fs = std::filesystem;
  fs::create_directories(a.out);
  io::WriteFileWith(fs::path(a.out) / "report.md",
                    [&](std::ostream& os) { reports::WriteCommitteeReport(os, r); });
  io::WriteFileWith(fs::path(a.out) / "committee.json",
                    [&](std::ostream& os) { os << reports::CommitteeJson(r); });
  std::vector<std::string> warnings;
  if (!a.no_figures)
    reports::WriteCommitteeFigures((fs::path(a.out) / "figures").string(), r, &warnings);
  for (const auto& w : warnings) std::cerr << "piezoid committee: warning: " << w << "\n";

  std::cout << "committee test RMSE " << r.committee_test.rmse << " um, max error "
            << r.committee_test.max_abs << " um";
  if (r.best_complete >= 0)
    std::cout << "; best complete model " << r.complete[r.best_complete].Name() << " RMSE "
              << r.complete[r.best_complete].all_test.rmse << " um: reduction "
              << 100 * r.rmse_reduction << " % (max error " << 100 * r.max_reduction << " %)";
  std::cout << "\n"
            << r.evaluations << " evaluations in " << r.wall_s << " s on " << r.threads
            << (a.service.enabled() ? " worker thread(s) of " + a.service.master
                                    : std::string(" thread(s)"))
            << "; report in " << (fs::path(a.out) / "report.md").string() << "\n";
  return 0;
}

}  // namespace

void RegisterCommittee(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<CommitteeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "committee",
      "Committee machine (seed 002): identify model families (default the stack Bouc-Wen and "
      "backlash-like models; any records family) by PSO and GA on all training records (complete) "
      "and "
      "per frequency band, select a sub-model per band by "
      "A = (RMSE_train + RMSE_test)/2, and compare the committee with the best complete model on "
      "the "
      "test records; writes report.md, committee.json and loop figures.");
  cmd->add_option("--records", a->records,
                  "record set whose records state their excitation frequency: a stack bench folder "
                  "(records.csv), "
                  "a fin bench (cases.csv) or a manifest.csv with a frequency_Hz column")
      ->type_name("DIR")
      ->default_str("data/piezo-stack-bench");
  cmd->add_option("--out", a->out, "output folder")->type_name("DIR")->default_str("committee-out");
  cmd->add_option("--bands", a->bands,
                  "band edges in Hz ('0,50,150,250,350') or ranges ('0-50,50-150,…'); a record "
                  "belongs to [lo, hi), the last band closed")
      ->default_str("0,50,150,250,350");
  std::string families;
  for (const std::string& f : records::FamilyNames())
    families += (families.empty() ? "" : ", ") + f;
  cmd->add_option("--families", a->families, "model families, any of `piezoid fit`'s: " + families)
      ->delimiter(',')
      ->default_str("stack-bouc-wen,backlash-like");
  cmd->add_option("--optimisers", a->optimisers, "optimisers: pso, ga-real, ga-binary")
      ->delimiter(',')
      ->default_str("pso,ga-real");
  cmd->add_option("--criterion", a->criterion,
                  "identification criterion over the window: iae, sse, rmse (each "
                  "summed over the training records), max (the largest over them) or "
                  "mse (pooled)")
      ->default_str("iae");
  cmd->add_option("--t0", a->t0, "criterion window start [s]")->default_str("0.5");
  cmd->add_option("--t1", a->t1, "criterion window end [s] (clipped to each record's end)")
      ->default_str("2.5");
  AddSearchFlags(cmd, &a->search);
  cmd->add_option("--substeps", a->substeps,
                  "sub-steps per sample interval of the families that take them (stack Bouc-Wen "
                  "driver filter, "
                  "Duhem; oscillator RK4 steps x2), 1 … 512")
      ->default_str("2");
  AddInitialStateFlag(cmd, &a->initial_state);
  cmd->add_option("--threads", a->threads, "evaluation threads (0: all cores; 1: inline)")
      ->default_str("0");
  cmd->add_flag("--averaging", a->averaging,
                "averaging committee (triangular band memberships) instead of the hard switch");
  cmd->add_flag("--no-figures", a->no_figures, "do not write the loop figures");
  cmd->add_flag("--quiet", a->quiet, "no per-search progress lines");
  AddCompleteServiceFlags(cmd, a->service);
  cmd->callback([a, &exit_code] { exit_code = RunCommitteeCommand(*a); });
}

}  // namespace pz::client
