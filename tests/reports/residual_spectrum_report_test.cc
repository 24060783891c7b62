// The residual spectrum in a records report (issue 45, reports/residual_spectrum_report.h): on a
// bench whose truth has a mode, report.md of `diagnose --records` has the section — the band, its
// share, the named resonance's f_n and what it closed — and the figures draw the spectra with the
// mode marked; on the same bench without the mode (share 0) the residual holds no band and the
// report says nothing of it.
#include "reports/residual_spectrum_report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "diagnose/diagnose.h"
#include "records/excitation.h"
#include "reports/diagnose_report.h"
#include "synth/synthetic.h"

namespace pz::reports {
namespace {

diagnose::RecordDiagnoseOptions Quick() {
  diagnose::RecordDiagnoseOptions o;
  o.fit.uncertainty = false;
  o.fit.search.repetitions = 1;
  o.fit.search.pso.particles = 16;
  o.fit.search.pso.iterations = 30;
  o.fit.lm.max_iterations = 30;
  o.propose = false;
  return o;
}

std::string Report(const io::RecordSet& set, const diagnose::RecordDiagnosis& d) {
  std::ostringstream os;
  WriteDiagnosisMarkdown(os, set, d, records::ProposeTrainingDrive(set, d.excitation));
  return os.str();
}

TEST(ResidualSpectrumReport, AModeBenchShowsItsBandAndTheFittedMode) {
  const synth::ModeBench b = synth::MakeModeBench({.train_s = 0.8, .withheld_s = 0.5});
  const diagnose::RecordDiagnosis d = diagnose::DiagnoseRecords(b.set, Quick());
  ASSERT_GE(d.named, 0) << d.verdict;
  const std::string md = Report(b.set, d);
  EXPECT_NE(md.find("## Residual spectrum"), std::string::npos) << md;
  EXPECT_NE(md.find("| withheld | validate |"), std::string::npos) << md;
  EXPECT_NE(md.find(" | yes | "), std::string::npos) << md;  // a mode's band
  EXPECT_NE(md.find("The named model's mode: f_n 7"), std::string::npos) << md;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("pz_residual_spectrum_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::vector<std::filesystem::path> scripts;
  const records::FitResult& named = d.candidates[static_cast<size_t>(d.named)].fit;
  WriteResidualSpectrumFigures(dir, b.set, d.base, &named, scripts);
  EXPECT_EQ(scripts.size(), 2u);  // training and withheld both hold the band
  EXPECT_TRUE(std::filesystem::exists(dir / "residual_spectrum_withheld.csv"));
  std::ifstream marker(dir / "residual_mode_withheld.csv");
  std::string header, row;
  std::getline(marker, header);
  std::getline(marker, row);
  EXPECT_EQ(header, "f_hz,power");
  EXPECT_NEAR(std::stod(row.substr(0, row.find(','))), 740, 7.4) << row;
  std::filesystem::remove_all(dir);
}

TEST(ResidualSpectrumReport, NoBandNoSection) {
  const synth::ModeBench b = synth::MakeModeBench({.share = 0, .train_s = 0.8, .withheld_s = 0.5});
  const diagnose::RecordDiagnosis d = diagnose::DiagnoseRecords(b.set, Quick());
  for (const auto& c : d.candidates)
    EXPECT_NE(c.kind, records::EffectKind::Named("resonance")) << "tried without a band";
  EXPECT_EQ(Report(b.set, d).find("## Residual spectrum"), std::string::npos);
}

}  // namespace
}  // namespace pz::reports
