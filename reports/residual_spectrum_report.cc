#include "reports/residual_spectrum_report.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "io/csv.h"
#include "records/resonance.h"
#include "reports/plots.h"

namespace pz::reports {
namespace {

std::string G(double x, int prec = 4) {
  std::ostringstream s;
  s << std::setprecision(prec) << x;
  return s.str();
}

/// The fitted mode of a fit holding `resonance`: {share, f_n, ζ}, or empty.
std::vector<double> FittedMode(const records::FitResult* f) {
  if (f == nullptr) return {};
  const auto [first, count] = f->model->EffectParams(records::EffectKind::Named("resonance"));
  if (count != 3) return {};
  return {f->params[first], f->params[first + 1], f->params[first + 2]};
}

/// The base residual's band of record i (lower bound: the resonance's range of f_n on the data).
model::SpectralBand BandOf(const io::RecordSet& set, const records::FitResult& base, size_t i,
                           model::PowerSpectrum* spectrum) {
  const double f_min =
      records::EffectKind::Named("resonance")->Params(base.model->scale())[1].lower;
  return records::ResidualBand(set.records[i], base.yhat[i], f_min, spectrum);
}

std::string FileStem(const std::string& name) {
  std::string s = name;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  return s;
}

}  // namespace

void WriteResidualSpectrumMarkdown(std::ostream& os, const io::RecordSet& set,
                                   const records::FitResult& base,
                                   const records::FitResult* after) {
  const std::vector<double> mode = FittedMode(after);
  bool header = false;
  for (size_t i = 0; i < set.records.size() && i < base.yhat.size(); ++i) {
    model::PowerSpectrum s;
    const model::SpectralBand b = BandOf(set, base, i, &s);
    if (!b.dominant()) continue;
    if (!header) {
      os << "\n## Residual spectrum\n\nThe base model's residual of these records has a dominant "
            "band (half of its power or more, at least "
         << G(model::SpectralBand::kDominantContrast, 2)
         << " × the power per bin elsewhere): a mode of the structure, or a drive content the "
            "model cannot follow. Figures: `figures/residual_spectrum_<record>.png`"
         << (mode.empty() ? "" : ", the fitted mode marked") << ".\n\n"
         << "| record | role | band [Hz] | peak [Hz] | share of the residual's power | "
            "ζ from its width | a mode's (ζ < "
         << G(model::SpectralBand::kModeZeta, 2)
         << ": the diagnosis tries `resonance`) | after: share of the band closed |\n"
         << "|---|---|---|---|---|---|---|---|\n";
      header = true;
    }
    std::string closed = "—";
    if (after != nullptr) {
      const model::PowerSpectrum sa = records::ResidualSpectrum(set.records[i], after->yhat[i]);
      const double before = model::BandPower(s, b.f_lo, b.f_hi),
                   left = model::BandPower(sa, b.f_lo, b.f_hi);
      if (before > 0) closed = G(100 * (1 - left / before), 3) + " %";
    }
    os << "| " << set.records[i].name << " | " << model::CaseRoleName(set.records[i].role) << " | "
       << G(b.f_lo, 4) << "–" << G(b.f_hi, 4) << " | " << G(b.f_peak, 4) << " | "
       << G(100 * b.share, 3) << " % | " << G(b.zeta, 2) << " | "
       << (b.mode_like() ? "yes" : "no: wider (harmonics of the drive, or a lag)") << " | "
       << closed << " |\n";
  }
  if (header && !mode.empty()) {
    os << "\nThe named model's mode: f_n " << G(mode[1], 5) << " Hz, ζ " << G(mode[2], 3)
       << ", share " << G(mode[0], 3) << " of the output";
    if (!after->mode_start.empty()) os << " (started at " << after->mode_start << ")";
    os << ".\n";
  }
}

void WriteFittedModeMarkdown(std::ostream& os, const io::RecordSet& set,
                             const records::FitResult& fit) {
  const std::vector<double> mode = FittedMode(&fit);
  if (mode.empty()) return;
  double floor = 0;
  for (const io::Record* r : set.WithRole(model::CaseRole::kTrain))
    floor = std::max(floor, records::ModeBandFloor(*r, 0));
  os << "\n## Resonance\n\nThe fitted mode: f_n " << G(mode[1], 5) << " Hz, ζ " << G(mode[2], 3)
     << ", share " << G(mode[0], 3) << " of the output"
     << (fit.mode_start.empty() ? " (no dominant band in the training residual nor a ringing rest: "
                                  "started by the search alone)"
                                : " (started at " + fit.mode_start + ")")
     << ".\n";
  if (mode[1] < floor)
    os << "\nIts f_n lies among the periodic training drive's first five harmonics (below "
       << G(floor, 3)
       << " Hz), where a hysteresis model's own error lies: the fit uses it as a linear dynamics "
          "of the output (a lag or lead the family lacks), not as a mode of the structure — "
          "compare it with `delay`, `driver-lowpass` or `rate-dependence`, and identify a mode on "
          "a "
          "drive with content near it (band-limited noise, steps).\n";
}

void WriteResidualSpectrumFigures(const std::filesystem::path& dir, const io::RecordSet& set,
                                  const records::FitResult& base, const records::FitResult* after,
                                  std::vector<std::filesystem::path>& scripts) {
  const std::vector<double> mode = FittedMode(after);
  for (size_t i = 0; i < set.records.size() && i < base.yhat.size(); ++i) {
    model::PowerSpectrum s;
    if (!BandOf(set, base, i, &s).dominant()) continue;
    const io::Record& r = set.records[i];
    const std::string stem = "residual_spectrum_" + FileStem(r.name);
    model::PowerSpectrum sa;
    if (after != nullptr) sa = records::ResidualSpectrum(r, after->yhat[i]);
    io::WriteFileWith(dir / (stem + ".csv"), [&](std::ostream& out) {
      out << "f_hz,base,after\n";
      for (size_t k = 1; k < s.p.size(); ++k)
        out << io::FormatNumber(s.f[k]) << "," << io::FormatNumber(s.p[k]) << ","
            << io::FormatNumber(k < sa.p.size() ? sa.p[k] : 0.0) << "\n";
    });
    Plot p{stem,     r.name + ": residual power spectrum",
           "f [Hz]", "power per bin [" + set.response_unit + "^2]",
           true,     {{stem + ".csv", 1, 2, base.model->Describe(), "lines"}}};
    if (after != nullptr)
      p.series.push_back({stem + ".csv", 1, 3, after->model->Describe(), "lines"});
    if (!mode.empty()) {
      const std::string marker = "residual_mode_" + FileStem(r.name) + ".csv";
      const double df = s.df;
      const size_t k = std::min(s.p.size() - 1, static_cast<size_t>(std::lround(mode[1] / df)));
      io::WriteFileWith(dir / marker, [&](std::ostream& out) {
        out << "f_hz,power\n"
            << io::FormatNumber(mode[1]) << "," << io::FormatNumber(s.p[k]) << "\n";
      });
      p.series.push_back({marker, 1, 2, "fitted mode f_n " + G(mode[1], 4) + " Hz", "points"});
    }
    scripts.push_back(WritePlotScript(dir, p));
  }
}

}  // namespace pz::reports
