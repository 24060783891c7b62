#include "controller/export_fin_c.h"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string_view>

#include "model/kernels/kernel_text.h"

namespace pz::controller {
namespace text {
// controller/fin_plant.h, byte for byte (embedded by controller/CMakeLists.txt).
extern const std::string_view k_fin_plant;
}  // namespace text
namespace {

void Replace(std::string& s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
}

/// A table of the plant's constants as a function returning it (no globals), hex literals with the
/// decimal values in a comment.
void WriteTable(std::ostream& o, const std::string& fn, const char* what,
                std::span<const double> v) {
  o << "/* " << what << " */\nstatic inline const double* pzf_" << fn
    << "(void) {\n  static const double v[PZF_MODES] = {";
  for (size_t i = 0; i < v.size(); ++i) o << (i ? ", " : "") << CHexLiteral(v[i]);
  o << "};\n  /* ";
  for (size_t i = 0; i < v.size(); ++i) o << (i ? " " : "") << CDecimal(v[i]);
  o << " */\n  return v;\n}\n";
}

}  // namespace

Status FinPlantToC(const model::ModalSimulator& sim, const model::Network& network,
                   const FinPlantExport& options, const std::string& name, std::string* text) {
  if (!(std::isfinite(options.sample_rate_hz) && options.sample_rate_hz > 0))
    return InvalidArgument(
        FieldError("--sample-rate", options.sample_rate_hz, "must be finite and > 0 [Hz]"));
  if (!(std::isfinite(options.drive_limit_v) && options.drive_limit_v >= 0))
    return InvalidArgument(FieldError("--drive-limit", options.drive_limit_v,
                                      "must be finite and >= 0 [V] (0: the training range)"));
  if (!(options.inverse_horizon >= 1 && options.inverse_horizon <= 100))
    return InvalidArgument(
        FieldError("--inverse-horizon", options.inverse_horizon, "must be in [1, 100] [samples]"));
  const auto& norm = network.normalization;
  const double limit = options.drive_limit_v > 0
                           ? options.drive_limit_v
                           : std::max(std::abs(norm.amplitude_lo_v), std::abs(norm.amplitude_hi_v));
  if (!(limit > 0))
    return InvalidArgument(
        FieldError("--drive-limit", limit, "must be > 0 [V] (the training amplitudes are all 0)"));
  const int n = sim.num_modes();
  const double dt = 1.0 / options.sample_rate_hz;
  std::ostringstream t;
  t << "/* The plant: " << n
    << " modes of the beam (those visible at the tip), fin length L = " << CDecimal(sim.length_m())
    << " m, sampled at " << CDecimal(options.sample_rate_hz) << " Hz.";
  if (!options.note.empty()) {  // wrapped at about 100 columns, "*/" kept out of the comment
    std::string note = options.note;
    Replace(note, "*/", "* /");
    t << "\n *";
    size_t col = 2;
    std::istringstream words(note);
    for (std::string w; words >> w; col += w.size() + 1) {
      if (col + w.size() > 100) t << "\n *", col = 2;
      t << " " << w;
    }
  }
  t << " */\n"
    << "#define PZF_MODES " << n << "\n#define PZF_MODES_PADDED " << (n + 3) / 4 * 4 << "\n"
    << "#define PZF_DT " << CHexLiteral(dt) << " /* " << CDecimal(dt) << " s */\n"
    << "#define PZF_INV_LENGTH " << CHexLiteral(1.0 / sim.length_m())
    << " /* 1/L = " << CDecimal(1.0 / sim.length_m()) << " 1/m */\n"
    << "#define PZF_U_MIN " << CHexLiteral(-limit) << " /* " << CDecimal(-limit)
    << " V: drive limits */\n"
    << "#define PZF_U_MAX " << CHexLiteral(limit) << " /* " << CDecimal(limit) << " V */\n"
    << "#define PZF_AMPLITUDE_LO " << CHexLiteral(norm.amplitude_lo_v) << " /* "
    << CDecimal(norm.amplitude_lo_v) << " V: training range */\n"
    << "#define PZF_AMPLITUDE_HI " << CHexLiteral(norm.amplitude_hi_v) << " /* "
    << CDecimal(norm.amplitude_hi_v) << " V */\n"
    << "#define PZF_FREQUENCY_LO " << CHexLiteral(norm.frequency_lo_hz) << " /* "
    << CDecimal(norm.frequency_lo_hz) << " Hz */\n"
    << "#define PZF_FREQUENCY_HI " << CHexLiteral(norm.frequency_hi_hz) << " /* "
    << CDecimal(norm.frequency_hi_hz) << " Hz */\n"
    << "#define PZF_INVERSE_ITERATIONS 100 /* trials of one pzf_inverse_step, at most */\n"
    << "#define PZF_INVERSE_HORIZON " << options.inverse_horizon << " /* samples */\n"
    << "#define PZF_NETWORK " << name << " /* the network's parameters (above) */\n";
  WriteTable(t, "omega2", "omega_i^2 [1/s^2]", sim.omega2());
  WriteTable(t, "tip_gain_u",
             "tip_i g_u,i: drive to tip deflection, per unit modal acceleration [m/V]",
             sim.tip_gain_u());
  WriteTable(t, "tip_gain_z", "tip_i g_z,i: Bouc-Wen force to tip deflection", sim.tip_gain_z());
  std::string s = t.str() + std::string(text::k_fin_plant);
  Replace(s, "pzf_", name + "_");
  Replace(s, "PZF_", CUpper(name) + "_");
  *text = "\n" + pzk::FinModalSource() + s;
  return Status::Ok();
}

}  // namespace pz::controller
