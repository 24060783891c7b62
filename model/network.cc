#include "model/network.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace pz::model {
namespace {

constexpr const char* kTfNames[kNumTransferFunctions] = {"hardlim", "hardlims", "satlin", "satlins",
                                                         "tribas",  "tansig",   "logsig", "radbas"};
constexpr const char* kOutputNames[kNetworkOutputs] = {"mu",    "delta", "alpha", "beta",
                                                       "gamma", "a1",    "a2"};
constexpr const char* kOutputUnits[kNetworkOutputs] = {"1/s", "s",   "N/V", "1/V",
                                                       "1/V", "deg", "deg"};

std::string Index2(const char* name, int i, int j) {
  std::ostringstream os;
  os << name << "(" << i << ", " << j << ")";
  return os.str();
}

std::string Index1(const char* name, int i) {
  std::ostringstream os;
  os << name << "(" << i << ")";
  return os.str();
}

Status CheckFinite(const Eigen::MatrixXd& m, const char* name) {
  for (int i = 0; i < m.rows(); ++i) {
    for (int j = 0; j < m.cols(); ++j) {
      if (!std::isfinite(m(i, j))) {
        return InvalidArgument(FieldError(m.cols() == 1 ? Index1(name, i) : Index2(name, i, j),
                                          m(i, j), "must be finite"));
      }
    }
  }
  return Status::Ok();
}

Status CheckTf(TransferFunction tf, const std::string& field) {
  if (!IsValidTransferCode(static_cast<int>(tf))) {
    return InvalidArgument(
        FieldError(field, static_cast<int>(tf), "transfer-function code must be 0 … 7"));
  }
  return Status::Ok();
}

Status CheckInterval(double lo, double hi, const std::string& lo_name, const std::string& hi_name,
                     bool strict) {
  if (!std::isfinite(lo)) return InvalidArgument(FieldError(lo_name, lo, "must be finite"));
  if (!std::isfinite(hi)) return InvalidArgument(FieldError(hi_name, hi, "must be finite"));
  if (strict ? !(hi > lo) : !(hi >= lo)) {
    std::ostringstream rule;
    rule.precision(17);
    rule << "must be " << (strict ? ">" : ">=") << " " << lo_name << " (" << lo << ")";
    return InvalidArgument(FieldError(hi_name, hi, rule.str()));
  }
  return Status::Ok();
}

}  // namespace

const char* TransferFunctionName(TransferFunction tf) {
  const int code = static_cast<int>(tf);
  return IsValidTransferCode(code) ? kTfNames[code] : "invalid";
}

bool ParseTransferFunction(const std::string& name, TransferFunction* tf) {
  for (int c = 0; c < kNumTransferFunctions; ++c) {
    if (name == kTfNames[c]) {
      *tf = static_cast<TransferFunction>(c);
      return true;
    }
  }
  return false;
}

bool IsValidTransferCode(int code) { return code >= 0 && code < kNumTransferFunctions; }

TransferFunction TransferFromCode(int code) {
  PZ_CHECK_MSG(IsValidTransferCode(code), "transfer-function code " + std::to_string(code));
  return static_cast<TransferFunction>(code);
}

double ApplyTransfer(TransferFunction tf, double n) {
  switch (tf) {
    case TransferFunction::kHardlim:
      return n >= 0 ? 1.0 : 0.0;
    case TransferFunction::kHardlims:
      return n >= 0 ? 1.0 : -1.0;
    case TransferFunction::kSatlin:
      return n <= 0 ? 0.0 : (n >= 1 ? 1.0 : n);
    case TransferFunction::kSatlins:
      return n <= -1 ? -1.0 : (n >= 1 ? 1.0 : n);
    case TransferFunction::kTribas:
      return (n >= -1 && n <= 1) ? 1.0 - std::abs(n) : 0.0;
    case TransferFunction::kTansig:
      return 2.0 / (1.0 + std::exp(-2.0 * n)) - 1.0;
    case TransferFunction::kLogsig:
      return 1.0 / (1.0 + std::exp(-n));
    case TransferFunction::kRadbas:
      return std::exp(-n * n);
  }
  PZ_CHECK_MSG(false, "transfer-function code " + std::to_string(static_cast<int>(tf)));
  return 0;
}

TransferRange RangeOf(TransferFunction tf) {
  switch (tf) {
    case TransferFunction::kHardlims:
    case TransferFunction::kSatlins:
    case TransferFunction::kTansig:
      return {-1.0, 1.0};
    default:
      return {0.0, 1.0};
  }
}

const char* OutputName(int k) {
  PZ_CHECK(k >= 0 && k < kNetworkOutputs);
  return kOutputNames[k];
}

const char* OutputUnit(int k) {
  PZ_CHECK(k >= 0 && k < kNetworkOutputs);
  return kOutputUnits[k];
}

const char* InputName(int i) {
  PZ_CHECK(i >= 0 && i < kNetworkInputs);
  return i == 0 ? "amplitude" : "frequency";
}

const char* InputUnit(int i) {
  PZ_CHECK(i >= 0 && i < kNetworkInputs);
  return i == 0 ? "V" : "Hz";
}

ParameterRanges ParameterRanges::PaperTable3() {
  ParameterRanges r;
  r.mu = {0, 300};
  r.delta = {0, 1};
  r.alpha = {-0.1, 0};
  r.beta = {-0.1, 0};
  r.gamma = {-0.1, 0};
  r.a1 = {0, 2};
  r.a2 = {0, 2};
  return r;
}

const ParameterRange& ParameterRanges::operator[](int k) const {
  PZ_CHECK(k >= 0 && k < kNetworkOutputs);
  const ParameterRange* fields[kNetworkOutputs] = {&mu, &delta, &alpha, &beta, &gamma, &a1, &a2};
  return *fields[k];
}

ParameterRange& ParameterRanges::operator[](int k) {
  return const_cast<ParameterRange&>(static_cast<const ParameterRanges&>(*this)[k]);
}

Status ParameterRanges::Validate() const {
  for (int k = 0; k < kNetworkOutputs; ++k) {
    const std::string base = std::string("ranges.") + kOutputNames[k];
    Status s =
        CheckInterval((*this)[k].lower, (*this)[k].upper, base + ".lower", base + ".upper", false);
    if (!s.ok()) return s;
  }
  return Status::Ok();
}

InputNormalization InputNormalization::FromCases(std::span<const double> amplitudes_v,
                                                 std::span<const double> frequencies_hz) {
  if (amplitudes_v.empty()) throw InputError("normalization: no training cases");
  if (amplitudes_v.size() != frequencies_hz.size()) {
    throw InputError(FieldError(
        "normalization: frequencies", frequencies_hz.size(),
        "must have as many entries as amplitudes (" + std::to_string(amplitudes_v.size()) + ")"));
  }
  auto span_of = [](std::span<const double> v, const char* name, double* lo, double* hi) {
    *lo = v[0];
    *hi = v[0];
    for (size_t i = 0; i < v.size(); ++i) {
      if (!std::isfinite(v[i])) {
        throw InputError(
            FieldError(std::string("normalization: ") + name + "[" + std::to_string(i) + "]", v[i],
                       "must be finite"));
      }
      *lo = std::min(*lo, v[i]);
      *hi = std::max(*hi, v[i]);
    }
    if (*hi == *lo) *hi = *lo + 1;
  };
  InputNormalization n;
  span_of(amplitudes_v, "amplitudes", &n.amplitude_lo_v, &n.amplitude_hi_v);
  span_of(frequencies_hz, "frequencies", &n.frequency_lo_hz, &n.frequency_hi_hz);
  return n;
}

Status InputNormalization::Validate() const {
  Status s = CheckInterval(amplitude_lo_v, amplitude_hi_v, "normalization.amplitude_lo_v",
                           "normalization.amplitude_hi_v", true);
  if (!s.ok()) return s;
  return CheckInterval(frequency_lo_hz, frequency_hi_hz, "normalization.frequency_lo_hz",
                       "normalization.frequency_hi_hz", true);
}

NetworkParameters NetworkParameters::FromArray(const std::array<double, kNetworkOutputs>& p) {
  return {p[0], p[1], p[2], p[3], p[4], p[5], p[6]};
}

Status Network::Validate() const {
  const int h = hidden();
  if (h < kMinHidden || h > kMaxHidden) {
    return InvalidArgument(FieldError("hidden_tf.size()", h, "hidden-node count must be 2 … 9"));
  }
  for (int i = 0; i < kNetworkInputs; ++i) {
    Status s = CheckTf(input_tf[i], "input_tf[" + std::to_string(i) + "]");
    if (!s.ok()) return s;
  }
  for (int j = 0; j < h; ++j) {
    Status s = CheckTf(hidden_tf[j], "hidden_tf[" + std::to_string(j) + "]");
    if (!s.ok()) return s;
  }
  for (int k = 0; k < kNetworkOutputs; ++k) {
    Status s = CheckTf(output_tf[k], "output_tf[" + std::to_string(k) + "]");
    if (!s.ok()) return s;
  }
  auto shape = [](const Eigen::MatrixXd& m, const char* name, int rows, int cols) -> Status {
    if (m.rows() == rows && m.cols() == cols) return Status::Ok();
    std::ostringstream os;
    os << m.rows() << "x" << m.cols();
    return InvalidArgument(
        FieldError(std::string(name) + " shape", os.str(),
                   "must be " + std::to_string(rows) + "x" + std::to_string(cols)));
  };
  for (Status s : {shape(w1, "w1", kNetworkInputs, h), shape(c1, "c1", h, 1),
                   shape(w2, "w2", h, kNetworkOutputs), shape(c2, "c2", kNetworkOutputs, 1),
                   CheckFinite(w1, "w1"), CheckFinite(c1, "c1"), CheckFinite(w2, "w2"),
                   CheckFinite(c2, "c2"), normalization.Validate(), ranges.Validate()}) {
    if (!s.ok()) return s;
  }
  return Status::Ok();
}

NetworkActivations Network::Forward(double amplitude_v, double frequency_hz) const {
  const int h = hidden();
  PZ_CHECK_MSG(w1.rows() == kNetworkInputs && w1.cols() == h && c1.size() == h && w2.rows() == h &&
                   w2.cols() == kNetworkOutputs && c2.size() == kNetworkOutputs,
               "network shapes inconsistent: Validate() it before use");
  if (!std::isfinite(amplitude_v))
    throw InputError(FieldError("amplitude_v", amplitude_v, "must be finite"));
  if (!std::isfinite(frequency_hz))
    throw InputError(FieldError("frequency_hz", frequency_hz, "must be finite"));
  NetworkActivations act;
  act.x << normalization.NormalizeAmplitude(amplitude_v),
      normalization.NormalizeFrequency(frequency_hz);
  for (int i = 0; i < kNetworkInputs; ++i) act.a(i) = ApplyTransfer(input_tf[i], act.x(i));
  act.b.resize(h);
  for (int j = 0; j < h; ++j) {
    double n = c1(j);
    for (int i = 0; i < kNetworkInputs; ++i) n += act.a(i) * w1(i, j);
    act.b(j) = ApplyTransfer(hidden_tf[j], n);
  }
  std::array<double, kNetworkOutputs> p;
  for (int k = 0; k < kNetworkOutputs; ++k) {
    double n = c2(k);
    for (int j = 0; j < h; ++j) n += act.b(j) * w2(j, k);
    act.o(k) = ApplyTransfer(output_tf[k], n);
    const TransferRange r = RangeOf(output_tf[k]);
    act.s(k) = (act.o(k) - r.lo) / (r.hi - r.lo);
    const ParameterRange& pr = ranges[k];
    p[k] = pr.lower + act.s(k) * (pr.upper - pr.lower);
  }
  act.parameters = NetworkParameters::FromArray(p);
  return act;
}

std::string Network::Describe() const {
  std::ostringstream os;
  auto list = [&os](const char* label, auto begin, auto end) {
    os << " " << label << "[";
    for (auto it = begin; it != end; ++it)
      os << (it == begin ? "" : ",") << TransferFunctionName(*it);
    os << "]";
  };
  os << kNetworkInputs << "-" << hidden() << "-" << kNetworkOutputs;
  list("in", input_tf.begin(), input_tf.end());
  list("hidden", hidden_tf.begin(), hidden_tf.end());
  list("out", output_tf.begin(), output_tf.end());
  return os.str();
}

bool Network::operator==(const Network& o) const {
  auto same = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    return a.rows() == b.rows() && a.cols() == b.cols() && (a.array() == b.array()).all();
  };
  return input_tf == o.input_tf && hidden_tf == o.hidden_tf && output_tf == o.output_tf &&
         same(w1, o.w1) && same(c1, o.c1) && same(w2, o.w2) && same(c2, o.c2) &&
         normalization == o.normalization && ranges == o.ranges;
}

}  // namespace pz::model
