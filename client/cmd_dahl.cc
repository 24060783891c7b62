// `piezoid dahl`: the Dahl-model networks of seed 001. Generates the four data sets (10,001 points
// at 0.001 s, CVODE Adams), trains a 1-H-1 tansig network t ↦ d per case by Levenberg–Marquardt
// and/or Bayesian regularisation on a seeded 70/15/15 split, and prints our MSE / R / epochs / time
// beside the paper's Tables 3 and 4.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "client/commands.h"
#include "client/dahl_nets.h"
#include "io/csv.h"
#include "model/dense_kernels.h"

namespace pz::client {
namespace {

struct DahlArgs {
  std::vector<int> cases{1, 2, 3, 4};
  std::string method = "both";
  uint64_t seed = 1;
  int lm_restarts = 1;
  int br_restarts = 1;
  bool no_pin_ends = false;
  int hidden = 100;
  std::string init;
  std::string lm_init, br_init;
  double adaptive_fraction = 0.25;
  int epochs = -1;
  double time_limit_s = 0;
  std::string b1 = "paper";
  std::string min_grad_units = "normalised";
  std::string data_dir;
  std::string history_dir;
  std::string json_file;
  std::string csv_file;
  int progress = 0;
  bool data_only = false;
};

int RunDahl(const DahlArgs& a) {
  DahlStudyOptions o;
  o.cases = a.cases;
  o.lm = a.method == "lm" || a.method == "both";
  o.br = a.method == "br" || a.method == "both";
  o.seed = a.seed;
  o.lm_restarts = a.lm_restarts;
  o.br_restarts = a.br_restarts;
  o.pin_ends = !a.no_pin_ends;
  o.hidden = a.hidden;
  auto parse_init = [](const std::string& v) {
    return v == "adaptive" ? DahlInit::kAdaptive : DahlInit::kNguyenWidrow;
  };
  if (!a.init.empty()) o.lm_init = o.br_init = parse_init(a.init);
  if (!a.lm_init.empty()) o.lm_init = parse_init(a.lm_init);
  if (!a.br_init.empty()) o.br_init = parse_init(a.br_init);
  o.adaptive_fraction = a.adaptive_fraction;
  o.b1 = a.b1 == "spec" ? DahlB1Policy::kSpec : DahlB1Policy::kPaper;
  if (a.epochs >= 0) o.lm_options.epochs = o.br_options.epochs = a.epochs;
  if (a.time_limit_s > 0) o.lm_options.time_limit_s = o.br_options.time_limit_s = a.time_limit_s;
  o.lm_options.min_grad_normalised = o.br_options.min_grad_normalised =
      a.min_grad_units == "normalised";
  ThrowIfError(o.lm_options.Validate());
  ThrowIfError(o.br_options.Validate());
  std::cout << "piezoid dahl: seed " << o.seed << ", " << o.hidden
            << " tansig neurons, input t -> d, "
            << "70/15/15 split" << (o.pin_ends ? " (t = 0 and 10 s kept in training)" : "") << ", "
            << o.lm_restarts << " LM / " << o.br_restarts << " BR initialisation(s) per network ("
            << DahlInitName(o.lm_init) << " / " << DahlInitName(o.br_init)
            << (o.lm_init == DahlInit::kAdaptive || o.br_init == DahlInit::kAdaptive
                    ? ", adaptive fraction " + std::to_string(o.adaptive_fraction)
                    : std::string())
            << "), the lowest validation MSE kept; min_grad in " << a.min_grad_units
            << " target units; dense kernels: " << model::DenseBackendName() << "\n";

  std::vector<DahlNetRun> runs;
  for (int id : o.cases) {
    const DahlDataset ds = MakeDahlDataset(PaperDahlCase(id, o.b1));
    std::cout << "case " << id << ": " << ds.data.size() << " points, b1 = " << ds.dcase.params.b1
              << ", d in [" << ds.data.t.minCoeff() << ", " << ds.data.t.maxCoeff()
              << "], simulated in " << ds.sim.wall_time_s << " s" << std::endl;
    const std::string stem = "dahl_case" + std::to_string(id);
    if (!a.data_dir.empty()) {
      std::filesystem::create_directories(a.data_dir);
      io::WriteFileWith(std::filesystem::path(a.data_dir) / (stem + ".csv"),
                        [&](std::ostream& out) { WriteDahlDatasetCsv(out, ds, nullptr, nullptr); });
    }
    if (a.data_only) continue;
    for (model::TrainMethod m :
         {model::TrainMethod::kLevenbergMarquardt, model::TrainMethod::kBayesianRegularization}) {
      const bool br = m == model::TrainMethod::kBayesianRegularization;
      if ((br && !o.br) || (!br && !o.lm)) continue;
      model::EpochCallback cb;
      if (a.progress > 0)
        cb = [&, id, br](const model::EpochRecord& e) {
          if (e.epoch % a.progress == 0)
            std::fprintf(
                stderr, "case %d %s epoch %4d  %7.2f s  mse %.3e  val %.3e  mu %.0e  grad %.2e\n",
                id, br ? "BR" : "LM", e.epoch, e.time_s, e.mse_train, e.mse_val, e.mu, e.gradient);
        };
      DahlNetRun run = TrainDahlNet(ds, m, o, cb);
      std::cout << "case " << id << " " << run.summary.BriefReport() << std::endl;
      const std::string run_stem = stem + "_" + (br ? "br" : "lm");
      if (!a.data_dir.empty())
        io::WriteFileWith(
            std::filesystem::path(a.data_dir) / (run_stem + "_fit.csv"),
            [&](std::ostream& out) { WriteDahlDatasetCsv(out, ds, &run.split, &run.prediction); });
      if (!a.history_dir.empty()) {
        std::filesystem::create_directories(a.history_dir);
        io::WriteFileWith(std::filesystem::path(a.history_dir) / (run_stem + "_history.csv"),
                          [&](std::ostream& out) { WriteDahlHistoryCsv(out, run); });
      }
      runs.push_back(std::move(run));
    }
  }
  if (a.data_only) return 0;
  std::cout << "\n";
  PrintDahlTable(std::cout, runs);
  std::cout.flush();
  if (!a.json_file.empty())
    io::WriteFileWith(a.json_file, [&](std::ostream& out) {
      WriteDahlJson(out, runs, model::DenseBackendName());
    });
  if (!a.csv_file.empty())
    io::WriteFileWith(a.csv_file, [&](std::ostream& out) { WriteDahlCsv(out, runs); });
  return 0;
}

}  // namespace

void RegisterDahl(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<DahlArgs>();
  CLI::App* cmd = app.add_subcommand("dahl",
                                     "Dahl-model networks (seed 001): generate the four "
                                     "10,001-point data sets, train a 1-H-1 tansig "
                                     "network t -> d per case by Levenberg-Marquardt (trainlm) "
                                     "and/or Bayesian regularisation (trainbr) "
                                     "on a seeded 70/15/15 split, and print MSE / R / epochs / "
                                     "time beside the paper's Tables 3 and 4.");
  cmd->add_option("--cases", args->cases, "cases to run (1..4)")
      ->delimiter(',')
      ->check(CLI::Range(1, 4))
      ->default_str("1,2,3,4");
  cmd->add_option("--method", args->method, "lm, br or both")
      ->check(CLI::IsMember({"lm", "br", "both"}))
      ->default_str("both");
  cmd->add_option("--seed", args->seed,
                  "seed of the one generator: split, then the initial weights of each restart")
      ->default_str("1");
  cmd->add_option(
         "--lm-restarts", args->lm_restarts,
         "initialisations per LM network on the same split; the lowest validation MSE is kept")
      ->check(CLI::Range(1, 1000))
      ->default_str("1");
  cmd->add_option("--br-restarts", args->br_restarts,
                  "the same for BR (validation data are not trained on)")
      ->check(CLI::Range(1, 1000))
      ->default_str("1");
  cmd->add_flag(
      "--no-pin-ends", args->no_pin_ends,
      "pure dividerand: let t = 0 and t = 10 s fall into validation / test (extrapolation)");
  cmd->add_option("--hidden", args->hidden, "hidden tansig neurons")
      ->check(CLI::Range(1, 100000))
      ->default_str("100");
  const auto inits = CLI::IsMember({"nguyen-widrow", "adaptive"});
  cmd->add_option("--init", args->init,
                  "initial weights of both trainers: nguyen-widrow (MATLAB's initnw) or adaptive "
                  "(Nguyen-Widrow "
                  "with the neuron centres denser where the training target varies; default: "
                  "adaptive for LM, "
                  "nguyen-widrow for BR)")
      ->check(inits);
  cmd->add_option("--lm-init", args->lm_init,
                  "initial weights of the LM networks (default adaptive)")
      ->check(inits);
  cmd->add_option("--br-init", args->br_init,
                  "initial weights of the BR networks (default nguyen-widrow)")
      ->check(inits);
  cmd->add_option(
         "--adaptive-fraction", args->adaptive_fraction,
         "adaptive init: share of the neurons placed by the target's variation (the rest evenly)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--epochs", args->epochs, "maximum epochs (default: 1000 for both, as MATLAB)")
      ->check(CLI::Range(0, 1000000000));
  cmd->add_option("--time-limit", args->time_limit_s,
                  "wall-time budget per run [s] (default: none)")
      ->check(CLI::PositiveNumber);
  cmd->add_option(
         "--b1", args->b1,
         "case 2's b1: paper (3.09292e4, reproduces the paper's Table 2 data) or spec (3.09292e5)")
      ->check(CLI::IsMember({"paper", "spec"}))
      ->default_str("paper");
  cmd->add_option("--min-grad-units", args->min_grad_units,
                  "units of the min_grad = 1e-7 stop: normalised (the gradient of the MSE in "
                  "mapminmax-normalised "
                  "target units, the same test for every case) or target (MATLAB's: in units of d, "
                  "so case 2's "
                  "targets, 10 x smaller, stop 100 x sooner)")
      ->check(CLI::IsMember({"normalised", "target"}))
      ->default_str("normalised");
  cmd->add_option("--data-dir", args->data_dir,
                  "write dahl_case<k>.csv (t, v, d) and, per run, dahl_case<k>_<lm|br>_fit.csv "
                  "(subset, network "
                  "output) here")
      ->type_name("DIR");
  cmd->add_option("--history-dir", args->history_dir, "write one epoch-history CSV per run here")
      ->type_name("DIR");
  cmd->add_option("--json", args->json_file, "also write the summary as JSON to this file")
      ->type_name("FILE");
  cmd->add_option("--csv", args->csv_file, "also write the summary table as CSV to this file")
      ->type_name("FILE");
  cmd->add_option("--progress", args->progress, "print every N-th epoch to stderr (0: none)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--data-only", args->data_only, "only generate the data sets (needs --data-dir)");
  cmd->callback([args, &exit_code] {
    if (args->data_only && args->data_dir.empty()) throw InputError("--data-only needs --data-dir");
    exit_code = RunDahl(*args);
  });
}

}  // namespace pz::client
