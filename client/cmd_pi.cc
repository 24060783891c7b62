// `piezoid pi`: score a model (global flags or a per-case parameter file) against a bench case set
// with the paper's performance index.
#include <filesystem>
#include <iostream>
#include <memory>

#include "client/case_models.h"
#include "client/commands.h"
#include "client/data_root.h"
#include "io/csv.h"
#include "reports/pi_report.h"

namespace pz::client {
namespace {

struct PiArgs {
  ParamFlags flags;
  std::string cases_dir;
  std::string json_file;
  std::string csv_file;
};

int RunPi(const PiArgs& a) {
  const std::filesystem::path dir =
      a.cases_dir.empty() ? DefaultCaseSetDir() : std::filesystem::path(a.cases_dir);
  CheckBundledData(dir, "bimorph-fin/nominal", "--cases DIR");
  const io::CaseSet set = io::LoadCaseSet(dir);
  const std::vector<CaseModel> models = ResolveBenchCases(a.flags, set);
  reports::PiReport report = ScoreCaseSet(set, models, PlantSimulator(a.flags.Solver()));
  report.solver = a.flags.solver;
  report.saturation_mode = a.flags.saturation;
  reports::PrintPiReport(std::cout, report);
  std::cout.flush();
  if (!a.json_file.empty())
    io::WriteFileWith(a.json_file, [&](std::ostream& o) { reports::WritePiJson(o, report); });
  if (!a.csv_file.empty())
    io::WriteFileWith(a.csv_file, [&](std::ostream& o) { reports::WritePiCsv(o, report); });
  return report.failed ? 1 : 0;
}

}  // namespace

void RegisterPi(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<PiArgs>();
  CLI::App* cmd = app.add_subcommand("pi",
                                     "Score a model against a bench case set: per case the paper's "
                                     "PI = sum of squared angle errors "
                                     "[deg^2], RMSE and max |error| [deg], the amplitude x "
                                     "frequency grid of PI, and CF = sum of PI over "
                                     "the training cases.");
  args->flags.Register(
      *cmd,
      "auto: --b1/--b2 or the params file's b1,b2 if given, else fitted from each case's "
      "measured extremes.");
  cmd->add_option("--cases", args->cases_dir,
                  std::string("bench case set folder (cases.csv + one CSV per case); default: "
                              "bimorph-fin/nominal under ") +
                      kDataRootHelp)
      ->type_name("DIR");
  cmd->add_option("--json", args->json_file, "also write the scores as JSON to this file")
      ->type_name("FILE");
  cmd->add_option("--csv", args->csv_file, "also write the per-case table as CSV to this file")
      ->type_name("FILE");
  cmd->callback([args, &exit_code] { exit_code = RunPi(*args); });
}

}  // namespace pz::client
