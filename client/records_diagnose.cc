#include "client/records_diagnose.h"

#include "client/search_flags.h"
#include "client/select_report.h"

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "client/excitation_report.h"
#include "client/json_values.h"
#include "client/plots.h"
#include "client/record_windows.h"
#include "client/search_flags.h"
#include "io/csv.h"

namespace pz::client {
namespace fs = std::filesystem;
namespace {

std::string G(double x, int prec = 4) {
  std::ostringstream s;
  s << std::setprecision(prec) << x;
  return s.str();
}

}  // namespace

void WriteRecordsDiagnosisMarkdown(std::ostream& os, const io::RecordSet& set,
                                   const records::RecordDiagnosis& d,
                                   const records::TrainingDriveProposal& proposal, double settle_s,
                                   const records::SelectionResult* selection) {
  const std::string u = set.response_unit;
  os << "# piezoid diagnose: " << d.base.model->family().name() << " on `" << set.source.string()
     << "`\n\n"
     << "**Verdict (" << d.verdict_kind << "):** " << d.verdict << "\n\n";
  if (settle_s > 0) os << SettlingSentence(settle_s) << "\n\n";
  if (const std::string s = InitialStateSentence(d.base.model->family()); !s.empty())
    os << s << "\n\n";
  os << "## Noise floor\n\n| estimate | σ [" << u << "] | samples | from |\n|---|---|---|---|\n";
  for (const auto& e : d.noise.estimates) {
    os << "| " << e.method << (e.method == d.noise.used ? " (used)" : "") << " | " << G(e.sigma)
       << " | " << e.samples << " | " << e.detail << " |\n";
  }
  os << "\nWithheld: " << d.withheld_samples << " samples; training: " << d.train_samples
     << ". Base model " << d.base.model->Describe() << ": withheld RMS "
     << G(std::sqrt(d.s0 / d.withheld_samples)) << " " << u << " = " << G(d.rms_ratio, 3)
     << " × the floor (significant above 1.25: " << (d.significant ? "yes" : "no") << ").\n\n"
     << "## Candidates (ranked by score)\n\n"
     << "| effect | withheld RMS [" << u
     << "] | score | train ΔBIC | closed | pattern | z vs base | qualifies |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : d.candidates) {
    os << "| " << records::EffectName(c.kind) << " | "
       << G(std::sqrt(c.s_withheld / d.withheld_samples)) << " | " << G(c.score, 5) << " | "
       << G(c.train_delta_bic, 5) << " | "
       << (std::isfinite(c.closed) ? G(100 * c.closed, 3) + " %" : "—") << " | "
       << G(100 * c.pattern, 3) << " % | " << G(c.z_vs_base, 3) << " | "
       << (c.qualifies ? "yes" : c.note) << " |\n";
  }
  if (d.named >= 0) {
    const auto& c = d.candidates[static_cast<size_t>(d.named)];
    os << "\n## The named model: " << c.fit.model->Describe()
       << "\n\n| parameter | value | unit |\n|---|---|---|\n";
    for (size_t i = 0; i < c.fit.params.size(); ++i) {
      os << "| " << c.fit.model->params()[i].name << " | " << G(c.fit.params[i], 6) << " | "
         << c.fit.model->params()[i].unit << " |\n";
    }
    os << "\n| record | role | RMSE before | RMSE after | NRMSE after |\n|---|---|---|---|---|\n";
    for (size_t i = 0; i < set.records.size(); ++i) {
      os << "| " << set.records[i].name << " | " << model::CaseRoleName(set.records[i].role)
         << " | " << G(d.base.metrics[i].rmse) << " | " << G(c.fit.metrics[i].rmse) << " | "
         << (std::isfinite(c.fit.metrics[i].nrmse_pct) ? G(c.fit.metrics[i].nrmse_pct, 3) + " %"
                                                       : "— (constant response)")
         << " |\n";
    }
  }
  if (d.next) {
    os << "\n## Next measurement\n\n" << d.next->description << ".\n";
  }
  if (selection) WriteSelectionMarkdown(os, set, *selection);
  WriteExcitationMarkdown(os, set, d.excitation, proposal, kProposedDriveFile);
}

void WriteRecordsDiagnosisJson(std::ostream& os, const io::RecordSet& set,
                               const records::RecordDiagnosis& d,
                               const records::TrainingDriveProposal& proposal,
                               const records::SelectionResult* selection) {
  using namespace json;  // NOLINT
  Struct root;
  auto& f = *root.mutable_fields();
  f["records"] = Text(set.source.string());
  f["family"] = Text(d.base.model->family().name());
  f["initial_state"] = Text(model::InitialStateName(d.base.model->family().initial_state()));
  f["response_unit"] = Text(set.response_unit);
  Struct noise;
  auto& n = *noise.mutable_fields();
  n["sigma"] = Num(d.noise.sigma);
  n["used"] = Text(d.noise.used);
  std::vector<Value> estimates;
  for (const auto& e : d.noise.estimates) {
    Struct x;
    auto& g = *x.mutable_fields();
    g["method"] = Text(e.method);
    g["sigma"] = Num(e.sigma);
    g["samples"] = Num(static_cast<double>(e.samples));
    g["from"] = Text(e.detail);
    estimates.push_back(Obj(x));
  }
  n["estimates"] = List(estimates);
  f["noise_floor"] = Obj(noise);
  f["withheld_samples"] = Num(static_cast<double>(d.withheld_samples));
  f["rms_ratio"] = Num(d.rms_ratio);
  f["significant"] = Bool(d.significant);
  std::vector<Value> candidates;
  for (const auto& c : d.candidates) {
    Struct x;
    auto& g = *x.mutable_fields();
    g["effect"] = Text(records::EffectName(c.kind));
    g["score"] = Num(c.score);
    g["closed"] = Num(c.closed);
    g["pattern"] = Num(c.pattern);
    g["z_vs_base"] = Num(c.z_vs_base);
    g["qualifies"] = Bool(c.qualifies);
    g["note"] = Text(c.note);
    candidates.push_back(Obj(x));
  }
  f["candidates"] = List(candidates);
  std::vector<Value> diverged;
  for (const auto& n : d.diverged) diverged.push_back(Text(n));
  f["diverged"] =
      List(diverged);  // candidates left out: their prediction diverges on withheld records
  f["named"] = d.named >= 0
                   ? Text(records::EffectName(d.candidates[static_cast<size_t>(d.named)].kind))
                   : Null();
  f["confidence"] = Num(d.confidence);
  f["verdict_kind"] = Text(d.verdict_kind);
  f["verdict"] = Text(d.verdict);
  f["excitation"] = ExcitationJson(set, d.excitation, proposal, kProposedDriveFile);
  f["excitation_gap_note"] = Text(d.excitation_note);
  if (d.next) {
    Struct x;
    auto& g = *x.mutable_fields();
    g["waveform"] = Text(records::WaveformName(d.next->shape.waveform));
    g["amplitude"] = Num(d.next->shape.amplitude);
    g["bias"] = Num(d.next->shape.bias);
    g["frequency_hz"] = Num(d.next->shape.frequency_hz);
    g["duration_s"] = Num(d.next->shape.duration_s);
    g["rms_difference"] = Num(d.next->rms_difference);
    g["ratio_to_noise"] = Num(d.next->ratio_to_noise);
    f["next_measurement"] = Obj(x);
  }
  if (selection) f["selection"] = SelectionJson(*selection);
  os << Print(root, "diagnosis.json");
}

int RunRecordsDiagnose(const RecordsDiagnoseRequest& a) {
  const io::RecordSet set = LoadRecordSetWithWindows(a.records, a.train_windows, a.validate_windows,
                                                     a.test_windows, a.settle_s);
  records::RecordDiagnoseOptions o;
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
    PrintSelection(std::cout, set, selection);
    o.family = selection.fit_options.family;
    o.fit.family_options = selection.fit_options.family_options;
    if (a.service) o.fit.evaluator_factory = a.service(o.fit.family_options);
  }
  if (!a.quiet) o.fit.progress = [](const std::string& s) { std::cerr << s << std::endl; };
  const records::RecordDiagnosis d = records::DiagnoseRecords(set, o);
  std::cout << d.verdict << "\n";
  const fs::path out =
      a.out.empty() ? fs::path("diagnose_" + fs::path(a.records).stem().string()) : fs::path(a.out);
  PrintExcitationSummary(std::cout, set, d.excitation);
  fs::create_directories(out / "figures");
  const records::TrainingDriveProposal proposal = records::ProposeTrainingDrive(set, d.excitation);
  WriteProposedDrive(out / kProposedDriveFile, set, proposal);
  io::WriteFileWith(out / "report.md", [&](std::ostream& os) {
    WriteRecordsDiagnosisMarkdown(os, set, d, proposal, a.settle_s, select ? &selection : nullptr);
  });
  io::WriteFileWith(out / "diagnosis.json", [&](std::ostream& os) {
    WriteRecordsDiagnosisJson(os, set, d, proposal, select ? &selection : nullptr);
  });
  // Withheld traces: measured, base, named model.
  std::vector<fs::path> scripts;
  const records::FitResult* best =
      d.named >= 0 ? &d.candidates[static_cast<size_t>(d.named)].fit : nullptr;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    const std::string stem = "withheld_" + r.name;
    if (r.role == model::CaseRole::kTrain) continue;
    io::WriteFileWith(out / "figures" / (stem + ".csv"), [&](std::ostream& os) {
      os << "t_s,measured,base_error,named_error\n";
      for (size_t k = r.first_scored; k < r.end_scored; ++k) {
        os << io::FormatNumber(r.t[k]) << "," << io::FormatNumber(r.y[k]) << ","
           << io::FormatNumber(r.y[k] - d.base.yhat[i][k]) << ","
           << io::FormatNumber(best ? r.y[k] - best->yhat[i][k] : 0.0) << "\n";
      }
    });
    Plot p{stem,    r.name + ": error of the base and the named model",
           "t [s]", "error [" + set.response_unit + "]",
           false,   {{stem + ".csv", 1, 3, d.base.model->Describe(), "lines"}}};
    if (best) p.series.push_back({stem + ".csv", 1, 4, best->model->Describe(), "lines"});
    scripts.push_back(WritePlotScript(out / "figures", p));
  }
  std::vector<std::string> errors;
  if (!a.no_plots && GnuplotAvailable()) RenderPlots(out / "figures", scripts, &errors);
  for (const auto& e : errors) std::cerr << "piezoid diagnose: warning: " << e << "\n";
  std::cout << "written: " << (out / "report.md").string() << ", "
            << (out / "diagnosis.json").string() << "\n";
  return 0;
}

}  // namespace pz::client
