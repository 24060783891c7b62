#include "records/resonance.h"

namespace pz::records {

model::PowerSpectrum ResidualSpectrum(const io::Record& r, std::span<const double> yhat) {
  std::vector<double> e;
  for (size_t k = r.first_scored; k < r.end_scored && k < yhat.size(); ++k)
    e.push_back(r.y[k] - yhat[k]);
  const double fs = r.t.size() > 1 ? 1 / (r.t[1] - r.t[0]) : 0;
  return model::WelchSpectrum(e, fs);
}

std::optional<ModeStart> FindModeStart(const std::vector<const io::Record*>& records,
                                       const std::vector<std::vector<double>>& yhats,
                                       double f_min) {
  std::optional<ModeStart> best;
  double best_power = 0;
  auto consider = [&](const model::SpectralBand& b, double power, std::string source) {
    if (!b.dominant() || !(power > best_power)) return;
    best_power = power;
    best = ModeStart{b, std::move(source)};
  };
  for (size_t i = 0; i < records.size() && i < yhats.size(); ++i) {
    const model::PowerSpectrum s = ResidualSpectrum(*records[i], yhats[i]);
    const model::SpectralBand b = model::DominantBand(s, f_min);
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
