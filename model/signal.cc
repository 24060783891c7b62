#include "model/signal.h"

#include <algorithm>
#include <sstream>

namespace pz::model {

Status Sinusoid::Validate() const {
  if (!(std::isfinite(amplitude_v) && amplitude_v >= 0))
    return InvalidArgument(FieldError("amplitude_v", amplitude_v, "must be finite and >= 0"));
  if (!(std::isfinite(frequency_hz) && frequency_hz > 0))
    return InvalidArgument(FieldError("frequency_hz", frequency_hz, "must be finite and > 0"));
  if (!(std::isfinite(cycles) && cycles > 0))
    return InvalidArgument(FieldError("cycles", cycles, "must be finite and > 0"));
  if (!(std::isfinite(sample_rate_hz) && sample_rate_hz > 0))
    return InvalidArgument(FieldError("sample_rate_hz", sample_rate_hz, "must be finite and > 0"));
  const double n = cycles * sample_rate_hz / frequency_hz;
  if (n < 2 || n > 1e8)
    return InvalidArgument(FieldError("cycles * sample_rate_hz / frequency_hz", n,
                                      "number of samples must be in [2, 1e8]"));
  return Status::Ok();
}

Status SampledSignal::Validate() const {
  if (t.size() != u.size())
    return InvalidArgument("sampled signal: t has " + std::to_string(t.size()) +
                           " samples but u has " + std::to_string(u.size()));
  if (t.size() < 2)
    return InvalidArgument("sampled signal: needs at least 2 samples, has " +
                           std::to_string(t.size()));
  // A valid signal (every fitness evaluation's) in one branch-free pass; the loop below names the
  // first offending sample otherwise.
  bool ok = std::isfinite(t[0]) & std::isfinite(u[0]);
  for (size_t k = 1; k < t.size(); ++k)
    ok &= std::isfinite(t[k]) & std::isfinite(u[k]) & (t[k] > t[k - 1]);
  if (ok) return Status::Ok();
  for (size_t k = 0; k < t.size(); ++k) {
    if (!std::isfinite(t[k]))
      return InvalidArgument(FieldError("t[" + std::to_string(k) + "]", t[k], "must be finite"));
    if (!std::isfinite(u[k]))
      return InvalidArgument(FieldError("u[" + std::to_string(k) + "]", u[k], "must be finite"));
    if (k > 0 && !(t[k] > t[k - 1]))
      return InvalidArgument(FieldError(
          "t[" + std::to_string(k) + "]", t[k],
          "time must be strictly increasing (previous " + std::to_string(t[k - 1]) + ")"));
  }
  return Status::Ok();
}

namespace {
size_t Segment(const std::vector<double>& t, double time) {
  auto it = std::upper_bound(t.begin(), t.end(), time);
  size_t i = it == t.begin() ? 0 : static_cast<size_t>(it - t.begin()) - 1;
  return std::min(i, t.size() - 2);
}
}  // namespace

double SampledSignal::Value(double time) const {
  if (time <= t.front()) return u.front();
  if (time >= t.back()) return u.back();
  const size_t i = Segment(t, time);
  const double s = (time - t[i]) / (t[i + 1] - t[i]);
  return u[i] + s * (u[i + 1] - u[i]);
}

double SampledSignal::Derivative(double time) const {
  if (time < t.front() || time >= t.back()) return 0.0;
  const size_t i = Segment(t, time);
  return (u[i + 1] - u[i]) / (t[i + 1] - t[i]);
}

Status Validate(const DriveSignal& s) {
  return std::visit([](const auto& x) { return x.Validate(); }, s);
}

std::vector<double> SampleTimes(const DriveSignal& s) {
  if (const auto* sin = std::get_if<Sinusoid>(&s)) {
    std::vector<double> t(sin->NumSamples());
    for (size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) / sin->sample_rate_hz;
    return t;
  }
  return std::get<SampledSignal>(s).t;
}

std::vector<double> SampleValues(const DriveSignal& s) {
  if (const auto* sin = std::get_if<Sinusoid>(&s)) {
    std::vector<double> t = SampleTimes(s);
    for (double& x : t) x = sin->Value(x);
    return t;
  }
  return std::get<SampledSignal>(s).u;
}

std::string Describe(const DriveSignal& s) {
  std::ostringstream os;
  if (const auto* sin = std::get_if<Sinusoid>(&s)) {
    os << "sinusoid " << sin->amplitude_v << " V " << sin->frequency_hz << " Hz x" << sin->cycles
       << " @" << sin->sample_rate_hz << " Hz";
  } else {
    const auto& ss = std::get<SampledSignal>(s);
    os << "sampled input, " << ss.t.size() << " samples";
    if (!ss.t.empty()) os << " over [" << ss.t.front() << ", " << ss.t.back() << "] s";
  }
  return os.str();
}

}  // namespace pz::model
