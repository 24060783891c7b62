#include "reports/diagnose_report.h"

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "diagnosis.pb.h"
#include "io/csv.h"
#include "io/diagnosis_json.h"
#include "reports/bench_grid.h"
#include "reports/excitation_report.h"
#include "reports/plots.h"
#include "reports/record_windows.h"
#include "reports/residual_spectrum_report.h"
#include "reports/select_report.h"

namespace pz::reports {
namespace fs = std::filesystem;
namespace {

std::string G(double x, int prec = 4) {
  std::ostringstream s;
  s << std::setprecision(prec) << x;
  return s.str();
}

}  // namespace

void WriteDiagnosisMarkdown(std::ostream& os, const io::RecordSet& set,
                            const diagnose::RecordDiagnosis& d,
                            const records::TrainingDriveProposal& proposal,
                            const DiagnosisReport& report) {
  const double settle_s = report.settle_s;
  const records::SelectionResult* selection = report.selection;
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
  if (!d.noise.warning.empty()) os << "\n**Warning:** " << d.noise.warning << ".\n";
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
  WriteResidualSpectrumMarkdown(
      os, set, d.base, d.named >= 0 ? &d.candidates[static_cast<size_t>(d.named)].fit : nullptr);
  if (d.next) {
    os << "\n## Next measurement\n\n" << d.next->description << ".\n";
  }
  if (selection) WriteSelectionMarkdown(os, set, *selection);
  WriteExcitationMarkdown(os, set, d.excitation, proposal, kProposedDriveFile);
  if (report.grid) WriteBenchGridMarkdown(os, *report.grid);
}

void CandidateOf(const diagnose::RecordCandidate& c, const records::FitResult& start,
                 proto::DiagnosisCandidate* out) {
  out->set_effect(records::EffectName(c.kind));
  out->set_score(c.score);
  out->set_closed(c.closed);
  out->set_pattern(c.pattern);
  out->set_qualifies(c.qualifies);
  out->set_note(c.note);
  out->set_z_vs_base(c.z_vs_base);
  out->set_added_parameters(static_cast<int64_t>(c.fit.params.size()) -
                            static_cast<int64_t>(start.params.size()));
  out->set_train_delta_bic(c.train_delta_bic);
  out->set_raw_reduction(c.raw_reduction);
  out->set_weight(c.weight);
}

void DiagnosisOf(const io::RecordSet& set, const diagnose::RecordDiagnosis& d,
                 const records::TrainingDriveProposal& proposal, const DiagnosisReport& report,
                 proto::Diagnosis* out) {
  proto::Diagnosis m;
  m.set_verdict_kind(d.verdict_kind);
  m.set_verdict(d.verdict);
  for (const auto& k : d.named_effects) m.add_named(records::EffectName(k));
  m.set_confidence(d.named_effects.empty() ? NAN : d.confidence);
  m.set_records(set.source.string());
  m.set_family(d.base.model->family().name());
  m.set_initial_state(model::InitialStateName(d.base.model->family().initial_state()));
  m.set_response_unit(set.response_unit);
  proto::NoiseFloor& n = *m.mutable_noise_floor();
  n.set_sigma(d.noise.sigma);
  n.set_used(d.noise.used);
  if (!d.noise.warning.empty()) n.set_warning(d.noise.warning);  // optional: older files unchanged
  for (const auto& e : d.noise.estimates) {
    proto::NoiseEstimate& g = *n.add_estimates();
    g.set_method(e.method);
    g.set_sigma(e.sigma);
    g.set_samples(static_cast<int64_t>(e.samples));
    g.set_from(e.detail);
  }
  m.set_withheld_samples(static_cast<int64_t>(d.withheld_samples));
  m.set_rms_ratio(d.rms_ratio);
  m.set_significant(d.significant);
  for (const auto& c : d.candidates) CandidateOf(c, d.base, m.add_candidates());
  for (const auto& name : d.diverged) m.add_diverged(name);
  if (d.runner_up >= 0) {
    m.mutable_runner_up()->set_effect(
        records::EffectName(d.candidates[static_cast<size_t>(d.runner_up)].kind));
    m.mutable_runner_up()->set_z(d.z_runner_up);
  }
  ExcitationOf(set, d.excitation, proposal, kProposedDriveFile, m.mutable_excitation());
  m.set_excitation_gap_note(d.excitation_note);
  if (d.next) {
    proto::NextMeasurement& g = *m.mutable_next_measurement();
    g.set_waveform(synth::WaveformName(d.next->shape.waveform));
    g.set_amplitude(d.next->shape.amplitude);
    g.set_bias(d.next->shape.bias);
    g.set_frequency_hz(d.next->shape.frequency_hz);
    g.set_duration_s(d.next->shape.duration_s);
    g.set_rms_difference(d.next->rms_difference);
    g.set_ratio_to_noise(d.next->ratio_to_noise);
  }
  if (report.selection) SelectionOf(*report.selection, m.mutable_selection());
  if (report.grid) BenchGridOf(*report.grid, m.mutable_grid());
  *out = std::move(m);
}

void WriteDiagnosisJson(std::ostream& os, const io::RecordSet& set,
                        const diagnose::RecordDiagnosis& d,
                        const records::TrainingDriveProposal& proposal,
                        const DiagnosisReport& report) {
  proto::Diagnosis m;
  DiagnosisOf(set, d, proposal, report, &m);
  os << io::WriteDiagnosisFile(m);
}

std::vector<std::string> WriteDiagnosisFolder(const std::filesystem::path& out,
                                              const io::RecordSet& set,
                                              const diagnose::RecordDiagnosis& d,
                                              const DiagnosisReport& report, bool plots) {
  fs::create_directories(out / "figures");
  const records::TrainingDriveProposal proposal = records::ProposeTrainingDrive(set, d.excitation);
  WriteProposedDrive(out / kProposedDriveFile, set, proposal);
  io::WriteFileWith(out / "report.md", [&](std::ostream& os) {
    WriteDiagnosisMarkdown(os, set, d, proposal, report);
  });
  io::WriteFileWith(out / "diagnosis.json",
                    [&](std::ostream& os) { WriteDiagnosisJson(os, set, d, proposal, report); });
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
  WriteResidualSpectrumFigures(out / "figures", set, d.base, best, scripts);
  if (report.grid) WriteBenchGridFigures(out / "figures", *report.grid, scripts);
  std::vector<std::string> errors;
  if (plots && GnuplotAvailable()) RenderPlots(out / "figures", scripts, &errors);
  return errors;
}

}  // namespace pz::reports
