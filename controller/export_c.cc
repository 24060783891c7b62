#include "controller/export_c.h"

#include <cctype>
#include <cstdio>
#include <sstream>

#include "controller/export_fin_c.h"

namespace pz::controller {

namespace {

const char* kOutputMacro[model::kNetworkOutputs] = {"MU",    "DELTA", "ALPHA", "BETA",
                                                    "GAMMA", "A1",    "A2"};

/// The header's comment (provenance, the entry point, the outputs' ranges and units, the inputs'
/// normalisation), its include guard and the output macros.
void WriteHeaderStart(std::ostream& o, const io::SavedNetwork& saved, const std::string& name,
                      bool plant) {
  const model::Network& n = saved.network;
  const std::string up = CUpper(name);
  const auto& prov = saved.provenance;
  o << "/* " << name << ".h: HGANN network " << n.Describe() << "\n"
    << " * exported by piezoid 0.1.0 (piezoid export) from job '" << prov.job_id << "', seed "
    << prov.seed << ", generation " << prov.generation << ", fitness " << CDecimal(prov.fitness)
    << " deg^2.\n"
    << " *\n"
    << " * Standalone: needs only <math.h> (link with -lm). One entry point:\n"
    << " *\n"
    << " *   " << name << "(amplitude_v, frequency_hz, p);\n"
    << " *\n"
    << " * fills p[7] with the bimorph-fin parameters for a drive V sin(2 pi f t) of amplitude V "
       "[V] and\n"
    << " * frequency f [Hz] (finite):\n"
    << " *   p[" << up << "_MU]    mu    [1/s]  in [" << CDecimal(n.ranges.mu.lower) << ", "
    << CDecimal(n.ranges.mu.upper) << "]\n"
    << " *   p[" << up << "_DELTA] delta [s]    in [" << CDecimal(n.ranges.delta.lower) << ", "
    << CDecimal(n.ranges.delta.upper) << "]\n"
    << " *   p[" << up << "_ALPHA] alpha [N/V]  in [" << CDecimal(n.ranges.alpha.lower) << ", "
    << CDecimal(n.ranges.alpha.upper) << "]\n"
    << " *   p[" << up << "_BETA]  beta  [1/V]  in [" << CDecimal(n.ranges.beta.lower) << ", "
    << CDecimal(n.ranges.beta.upper) << "]\n"
    << " *   p[" << up << "_GAMMA] gamma [1/V]  in [" << CDecimal(n.ranges.gamma.lower) << ", "
    << CDecimal(n.ranges.gamma.upper) << "]\n"
    << " *   p[" << up << "_A1]    a1    [deg]  in [" << CDecimal(n.ranges.a1.lower) << ", "
    << CDecimal(n.ranges.a1.upper) << "]\n"
    << " *   p[" << up << "_A2]    a2    [deg]  in [" << CDecimal(n.ranges.a2.lower) << ", "
    << CDecimal(n.ranges.a2.upper) << "]\n"
    << " * Inputs are normalised over the training cases: x_V = (V - "
    << CDecimal(n.normalization.amplitude_lo_v) << ") / ("
    << CDecimal(n.normalization.amplitude_hi_v) << " - " << CDecimal(n.normalization.amplitude_lo_v)
    << "), x_f = (f - " << CDecimal(n.normalization.frequency_lo_hz) << ") / ("
    << CDecimal(n.normalization.frequency_hi_hz) << " - "
    << CDecimal(n.normalization.frequency_lo_hz) << ");\n"
    << " * outside that box the network extrapolates.\n"
    << " *\n"
    << " * The computation is model::Network::Forward's, operation for operation, with every "
       "constant an\n"
    << " * exact hex-float literal: compiled without -ffast-math it reproduces piezoid's "
       "predictions (bit\n"
    << " * for bit where the compiler does not contract a*b+c into fused multiply-adds).\n";
  if (plant)
    o << " *\n"
      << " * With it, the bimorph-fin plant as a per-sample recursion (see the plant's part "
         "below):\n"
      << " *\n"
      << " *   double p[7]; " << name << "_state s;\n"
      << " *   int st = " << name
      << "_params(V, f, p);      range-checked network (0 = inside the training box)\n"
      << " *   st = " << name
      << "_init(&s, p, b1, b2, u0);  b1 > 0 > b2: the fin's saturations [deg]\n"
      << " *   y = " << name
      << "_step(&s, u);               forward: drive [V] -> angle [deg] at the next sample\n"
      << " *   u = " << name
      << "_inverse_step(&s, y_ref);   inverse: desired angle -> drive (and the step)\n"
      << " *\n"
      << " * The state is a plain struct of fixed size: no allocation, no global, only <math.h>.\n";
  o << " */\n"
    << "#ifndef " << up << "_H_\n#define " << up << "_H_\n\n#include <math.h>\n\n";
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    o << "#define " << up << "_" << kOutputMacro[k] << " " << k << "  /* " << model::OutputName(k)
      << " [" << model::OutputUnit(k) << "] */\n";
  o << "#define " << up << "_OUTPUTS 7\n\n";
}

/// NAME_transfer: the eight transfer functions.
void WriteTransferFunction(std::ostream& o, const std::string& name) {
  o << "/* The eight MATLAB transfer functions by their 3-bit code: 0 hardlim, 1 hardlims, 2 "
       "satlin,\n"
       " * 3 satlins, 4 tribas, 5 tansig, 6 logsig, 7 radbas. */\n"
    << "static inline double " << name << "_transfer(int code, double n) {\n"
    << "  switch (code) {\n"
    << "    case 0: return n >= 0 ? 1.0 : 0.0;\n"
    << "    case 1: return n >= 0 ? 1.0 : -1.0;\n"
    << "    case 2: return n <= 0 ? 0.0 : (n >= 1 ? 1.0 : n);\n"
    << "    case 3: return n <= -1 ? -1.0 : (n >= 1 ? 1.0 : n);\n"
    << "    case 4: return (n >= -1 && n <= 1) ? 1.0 - fabs(n) : 0.0;\n"
    << "    case 5: return 2.0 / (1.0 + exp(-2.0 * n)) - 1.0;\n"
    << "    case 6: return 1.0 / (1.0 + exp(-n));\n"
    << "    default: return exp(-n * n);\n"
    << "  }\n"
    << "}\n\n";
}

/// The network's constants as static tables of the predictor: normalisation, transfer-function
/// codes, weights, biases and output ranges (exact literals, decimal values in comments).
void WriteConstants(std::ostream& o, const model::Network& n) {
  const int h = n.hidden();
  auto tf_list = [](auto begin, auto end) {
    std::ostringstream s;
    for (auto it = begin; it != end; ++it) s << (it == begin ? "" : ", ") << static_cast<int>(*it);
    return s.str();
  };
  auto tf_names = [](auto begin, auto end) {
    std::ostringstream s;
    for (auto it = begin; it != end; ++it)
      s << (it == begin ? "" : " ") << model::TransferFunctionName(*it);
    return s.str();
  };

  o << "  /* normalisation of the inputs: [lo, hi] of amplitude [V] and frequency [Hz] */\n"
    << "  static const double norm_lo[2] = {" << CHexLiteral(n.normalization.amplitude_lo_v) << ", "
    << CHexLiteral(n.normalization.frequency_lo_hz) << "}; /* "
    << CDecimal(n.normalization.amplitude_lo_v) << ", " << CDecimal(n.normalization.frequency_lo_hz)
    << " */\n"
    << "  static const double norm_hi[2] = {" << CHexLiteral(n.normalization.amplitude_hi_v) << ", "
    << CHexLiteral(n.normalization.frequency_hi_hz) << "}; /* "
    << CDecimal(n.normalization.amplitude_hi_v) << ", " << CDecimal(n.normalization.frequency_hi_hz)
    << " */\n"
    << "  /* transfer-function codes: input (" << tf_names(n.input_tf.begin(), n.input_tf.end())
    << "), hidden (" << tf_names(n.hidden_tf.begin(), n.hidden_tf.end()) << "), output ("
    << tf_names(n.output_tf.begin(), n.output_tf.end()) << ") */\n"
    << "  static const int tf_in[2] = {" << tf_list(n.input_tf.begin(), n.input_tf.end()) << "};\n"
    << "  static const int tf_hidden[" << h << "] = {"
    << tf_list(n.hidden_tf.begin(), n.hidden_tf.end()) << "};\n"
    << "  static const int tf_out[7] = {" << tf_list(n.output_tf.begin(), n.output_tf.end())
    << "};\n";
  o << "  /* w1[i][j]: input i to hidden j; c1[j]: hidden biases */\n"
    << "  static const double w1[2][" << h << "] = {\n";
  for (int i = 0; i < model::kNetworkInputs; ++i) {
    o << "    {";
    for (int j = 0; j < h; ++j) o << (j ? ", " : "") << CHexLiteral(n.w1(i, j));
    o << "}, /* ";
    for (int j = 0; j < h; ++j) o << (j ? " " : "") << CDecimal(n.w1(i, j));
    o << " */\n";
  }
  o << "  };\n  static const double c1[" << h << "] = {";
  for (int j = 0; j < h; ++j) o << (j ? ", " : "") << CHexLiteral(n.c1(j));
  o << "}; /* ";
  for (int j = 0; j < h; ++j) o << (j ? " " : "") << CDecimal(n.c1(j));
  o << " */\n";
  o << "  /* w2[j][k]: hidden j to output k; c2[k]: output biases */\n"
    << "  static const double w2[" << h << "][7] = {\n";
  for (int j = 0; j < h; ++j) {
    o << "    {";
    for (int k = 0; k < model::kNetworkOutputs; ++k)
      o << (k ? ", " : "") << CHexLiteral(n.w2(j, k));
    o << "}, /* ";
    for (int k = 0; k < model::kNetworkOutputs; ++k) o << (k ? " " : "") << CDecimal(n.w2(j, k));
    o << " */\n";
  }
  o << "  };\n  static const double c2[7] = {";
  for (int k = 0; k < model::kNetworkOutputs; ++k) o << (k ? ", " : "") << CHexLiteral(n.c2(k));
  o << "}; /* ";
  for (int k = 0; k < model::kNetworkOutputs; ++k) o << (k ? " " : "") << CDecimal(n.c2(k));
  o << " */\n";
  o << "  /* output ranges [lower, upper] of mu, delta, alpha, beta, gamma, a1, a2 */\n"
    << "  static const double lower[7] = {";
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    o << (k ? ", " : "") << CHexLiteral(n.ranges[k].lower);
  o << "};\n  static const double upper[7] = {";
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    o << (k ? ", " : "") << CHexLiteral(n.ranges[k].upper);
  o << "};\n";
}

/// The predictor's computation, model::Network::Forward's operation for operation.
void WriteForward(std::ostream& o, const std::string& name, int h) {
  o << "  double a[2], b[" << h << "];\n"
    << "  int i, j, k;\n"
    << "  a[0] = " << name
    << "_transfer(tf_in[0], (amplitude_v - norm_lo[0]) / (norm_hi[0] - norm_lo[0]));\n"
    << "  a[1] = " << name
    << "_transfer(tf_in[1], (frequency_hz - norm_lo[1]) / (norm_hi[1] - norm_lo[1]));\n"
    << "  for (j = 0; j < " << h << "; ++j) {\n"
    << "    double n = c1[j];\n"
    << "    for (i = 0; i < 2; ++i) n += a[i] * w1[i][j];\n"
    << "    b[j] = " << name << "_transfer(tf_hidden[j], n);\n"
    << "  }\n"
    << "  for (k = 0; k < 7; ++k) {\n"
    << "    double n = c2[k], o, lo, hi, s;\n"
    << "    for (j = 0; j < " << h << "; ++j) n += b[j] * w2[j][k];\n"
    << "    o = " << name << "_transfer(tf_out[k], n);\n"
    << "    /* the TF's output range: [-1, 1] for hardlims, satlins, tansig; else [0, 1] */\n"
    << "    lo = (tf_out[k] == 1 || tf_out[k] == 3 || tf_out[k] == 5) ? -1.0 : 0.0;\n"
    << "    hi = 1.0;\n"
    << "    s = (o - lo) / (hi - lo);\n"
    << "    p[k] = lower[k] + s * (upper[k] - lower[k]);\n"
    << "  }\n";
}

}  // namespace

namespace {

/// The header; with the fin plant after the network when `plant` is given.
Status WriteHeader(const io::SavedNetwork& saved, const std::string& name,
                   const model::ModalSimulator* plant, const FinPlantExport& options,
                   std::string* header) {
  if (!IsCIdentifier(name))
    return InvalidArgument(FieldError("--name", "\"" + name + "\"",
                                      "must be a C identifier ([A-Za-z_][A-Za-z0-9_]*)"));
  const model::Network& n = saved.network;
  if (Status s = n.Validate(); !s.ok()) return InvalidArgument("network: " + s.message());
  std::string plant_text;
  if (plant) {
    if (Status s = FinPlantToC(*plant, n, options, name, &plant_text); !s.ok()) return s;
  }
  std::ostringstream o;
  WriteHeaderStart(o, saved, name, plant != nullptr);
  WriteTransferFunction(o, name);
  o << "/* p[7] = the seven parameters for amplitude_v [V] and frequency_hz [Hz]. */\n"
    << "static inline void " << name
    << "(double amplitude_v, double frequency_hz, double p[7]) {\n";
  WriteConstants(o, n);
  WriteForward(o, name, n.hidden());
  o << "}\n" << plant_text << "\n#endif /* " << CUpper(name) << "_H_ */\n";
  *header = o.str();
  return Status::Ok();
}

}  // namespace

Status NetworkToCHeader(const io::SavedNetwork& saved, const std::string& name,
                        std::string* header) {
  return WriteHeader(saved, name, nullptr, {}, header);
}

Status NetworkAndFinToCHeader(const io::SavedNetwork& saved, const model::ModalSimulator& plant,
                              const FinPlantExport& options, const std::string& name,
                              std::string* header) {
  return WriteHeader(saved, name, &plant, options, header);
}

}  // namespace pz::controller
