#include "records/resonance.h"

#include <algorithm>

namespace pz::records {

model::PowerSpectrum ResidualSpectrum(const io::Record& r, std::span<const double> yhat) {
  std::vector<double> e;
  for (size_t k = r.first_scored; k < r.end_scored && k < yhat.size(); ++k)
    e.push_back(r.y[k] - yhat[k]);
  const double fs = r.t.size() > 1 ? 1 / (r.t[1] - r.t[0]) : 0;
  return model::WelchSpectrum(e, fs);
}

double ModeBandFloor(const io::Record& r, double f_min) {
  if (r.t.size() < 2 || r.end_scored <= r.first_scored) return f_min;
  const std::span<const double> u(r.u.data() + r.first_scored, r.end_scored - r.first_scored);
  const model::PowerSpectrum s = model::WelchSpectrum(u, 1 / (r.t[1] - r.t[0]));
  if (s.p.size() < 4) return f_min;
  size_t peak = 1;
  double total = 0;
  for (size_t k = 1; k < s.p.size(); ++k) {
    total += s.p[k];
    if (s.p[k] > s.p[peak]) peak = k;
  }
  double line = 0;  // the Hann window's main lobe: two bins each side
  for (size_t k = peak > 2 ? peak - 2 : 1; k <= peak + 2 && k < s.p.size(); ++k) line += s.p[k];
  return total > 0 && line >= 0.5 * total ? std::max(f_min, 5.5 * s.f[peak]) : f_min;
}

model::SpectralBand ResidualBand(const io::Record& r, std::span<const double> yhat, double f_min,
                                 model::PowerSpectrum* spectrum) {
  model::PowerSpectrum s = ResidualSpectrum(r, yhat);
  const model::SpectralBand b = model::DominantBand(s, ModeBandFloor(r, f_min));
  if (spectrum) *spectrum = std::move(s);
  return b;
}

std::optional<ModeStart> FindModeStart(const std::vector<const io::Record*>& records,
                                       const std::vector<std::vector<double>>& yhats,
                                       double f_min) {
  std::optional<ModeStart> best;
  double best_power = 0;
  auto consider = [&](const model::SpectralBand& b, double power, std::string source) {
    if (!b.mode_like() || !(power > best_power)) return;
    best_power = power;
    best = ModeStart{b, std::move(source)};
  };
  for (size_t i = 0; i < records.size() && i < yhats.size(); ++i) {
    model::PowerSpectrum s;
    const model::SpectralBand b = ResidualBand(*records[i], yhats[i], f_min, &s);
    consider(b, model::BandPower(s, b.f_lo, b.f_hi), "the residual of '" + records[i]->name + "'");
  }
  if (best) return best;
  for (const io::Record* r : records) {
    if (r->rest_samples < 64 || r->t.size() < 2) continue;
    const std::span<const double> rest(r->y.data(), r->rest_samples);
    const model::SpectralBand b = model::RingingBand(rest, 1 / (r->t[1] - r->t[0]), f_min);
    consider(b, b.share, "the ringing of the rest of '" + r->name + "'");
  }
  return best;
}

}  // namespace pz::records
