#include "complete/boucwen_benchmark.h"

#include <stdexcept>

#include "io/csv.h"

namespace pz::complete {

BwSeries LoadBwSeries(const std::filesystem::path& file) {
  const io::CsvTable t = io::ReadCsvFile(file);
  t.RequireColumns({"u_N", "y_m"});
  t.RequireRows();
  const int cu = t.RequireColumn("u_N"), cy = t.RequireColumn("y_m");
  BwSeries s;
  s.u.reserve(t.rows.size());
  s.y.reserve(t.rows.size());
  for (size_t i = 0; i < t.rows.size(); ++i) {
    s.u.push_back(t.Number(i, cu));
    s.y.push_back(t.Number(i, cy));
  }
  return s;
}

BwTrainingRecord MakeBwTrainingRecord(const std::string& name, const BwSeries& s, size_t samples, int substeps,
                                     bool steady_state) {
  model::BwInputOptions o;
  o.sample_rate_hz = kBwSampleRateHz;
  o.substeps = substeps;
  o.interpolation = model::InputInterpolation::kPeriodicFourier;
  o.period_samples = kBwPeriod;
  if (samples % kBwPeriod != 0 || samples == 0) {
    throw InputError(FieldError(name + ": samples", samples, "must be a whole number of 8192-sample periods"));
  }
  const size_t warmup = steady_state ? kBwPeriod : 0;
  BwTrainingRecord r;
  r.name = name;
  r.u.assign(s.u.begin(), s.u.begin() + static_cast<std::ptrdiff_t>(warmup));
  r.u.insert(r.u.end(), s.u.begin(), s.u.begin() + static_cast<std::ptrdiff_t>(samples));
  r.y.assign(warmup, 0.0);
  r.y.insert(r.y.end(), s.y.begin(), s.y.begin() + static_cast<std::ptrdiff_t>(samples));
  r.first_counted = warmup;
  r.input = o;
  return r;
}

std::vector<double> SimulateBwMultisineTest(const model::BwParams& p, const BwSeries& test) {
  std::vector<double> u3;
  for (int k = 0; k < 3; ++k) u3.insert(u3.end(), test.u.begin(), test.u.end());
  model::BwInputOptions o;
  o.sample_rate_hz = kBwSampleRateHz;
  o.substeps = 20;
  o.interpolation = model::InputInterpolation::kPeriodicFourier;
  o.period_samples = test.u.size();
  std::vector<double> y(u3.size());
  Status s = model::SimulateBw(p, model::BwInput(u3, o), y);
  if (!s.ok()) throw std::runtime_error("multisine test: " + s.message());
  return std::vector<double>(y.end() - static_cast<std::ptrdiff_t>(test.u.size()), y.end());
}

std::vector<double> SimulateBwSweepTest(const model::BwParams& p, const BwSeries& test) {
  model::BwInputOptions o;
  o.sample_rate_hz = kBwSampleRateHz;
  o.substeps = 20;
  o.interpolation = model::InputInterpolation::kCubicSpline;
  std::vector<double> y(test.u.size());
  Status s = model::SimulateBw(p, model::BwInput(test.u, o), y);
  if (!s.ok()) throw std::runtime_error("sine-sweep test: " + s.message());
  return y;
}

}  // namespace pz::complete
