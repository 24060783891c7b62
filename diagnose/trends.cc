#include "diagnose/trends.h"

#include <algorithm>
#include <cmath>

#include "model/saturation.h"
#include "model/status.h"

namespace pz::diagnose {

ParamTrend TrendOver(std::string name, std::string unit, std::vector<double> per_case,
                     const std::vector<double>& amplitude,
                     const std::vector<double>& frequency_hz) {
  ParamTrend t;
  t.name = std::move(name);
  t.unit = std::move(unit);
  t.per_case = std::move(per_case);
  const size_t nc = t.per_case.size();
  double lo = INFINITY, hi = -INFINITY, mean = 0;
  for (double x : t.per_case) {
    lo = std::min(lo, x);
    hi = std::max(hi, x);
    mean += x / static_cast<double>(nc);
  }
  t.relative_range = std::abs(mean) > 0 ? (hi - lo) / std::abs(mean) : 0;
  try {
    const model::PlaneFit pf = model::FitPlane(amplitude, frequency_hz, t.per_case);
    t.slope_v = pf.v.coef;
    t.slope_f = pf.f.coef;
    t.p_v = std::isfinite(pf.v.p_value) ? pf.v.p_value : 1;
    t.p_f = std::isfinite(pf.f.p_value) ? pf.f.p_value : 1;
    t.r2 = pf.r2;
  } catch (const InputError&) {
    // collinear or too few cases: no trend
  }
  t.significant = std::min(t.p_v, t.p_f) < 0.01 && t.relative_range > 0.1;
  return t;
}

double DriveAmplitude(const io::Record& r) {
  if (r.sinusoid.stated()) return r.sinusoid.amplitude_v;
  if (r.end_scored <= r.first_scored) return 0;
  const auto [lo, hi] = std::minmax_element(r.u.begin() + static_cast<long>(r.first_scored),
                                            r.u.begin() + static_cast<long>(r.end_scored));
  return (*hi - *lo) / 2;
}

std::vector<ParamTrend> RecordTrends(const io::RecordSet& set, const records::FitResult& from,
                                     const records::FitOptions& options, int iterations,
                                     int64_t* evaluations) {
  if (set.records.size() < 4) {
    throw InputError(set.source.string() + ": the V x f trends need at least 4 records (" +
                     std::to_string(set.records.size()) + " given): a plane over amplitude and " +
                     "frequency has 3 coefficients");
  }
  if (iterations < 1) throw InputError(FieldError("trend iterations", iterations, "must be >= 1"));
  std::vector<double> amplitude, frequency;
  for (const io::Record& r : set.records) {
    if (!(r.frequency_hz > 0)) {
      throw InputError(r.Label() + ": states no frequency (frequency_Hz), which the V x f " +
                       "trends regress over");
    }
    amplitude.push_back(DriveAmplitude(r));
    frequency.push_back(r.frequency_hz);
  }
  records::FitOptions fo = options;
  fo.polish_from = from.params;
  fo.lm.max_iterations = iterations;
  fo.uncertainty = false;
  fo.extra_starts.clear();
  fo.progress = nullptr;
  const size_t np = from.params.size();
  std::vector<std::vector<double>> per(np);
  for (const io::Record& r : set.records) {
    io::RecordSet one;
    one.source = set.source;
    one.format = set.format;
    one.drive_unit = set.drive_unit;
    one.response_unit = set.response_unit;
    one.records.push_back(r);
    one.records.back().role = model::CaseRole::kTrain;
    const records::FitResult f = records::FitModel(one, from.model, fo);
    if (evaluations) *evaluations += f.evaluations;
    for (size_t i = 0; i < np; ++i) per[i].push_back(f.params[i]);
  }
  std::vector<ParamTrend> trends;
  const auto& info = from.model->params();
  for (size_t i = 0; i < np; ++i)
    trends.push_back(TrendOver(info[i].name, info[i].unit, per[i], amplitude, frequency));
  return trends;
}

}  // namespace pz::diagnose
