// `piezoid export`: a trained HGANN network as a standalone C header for a controller. The header
// needs only <math.h> (exp) and holds one entry point,
//
//   static inline void <name>(double amplitude_v, double frequency_hz, double p[7]);
//
// which fills p with μ [1/s], δ [s], α [N/V], β [1/V], γ [1/V], a1 [deg], a2 [deg] (indices
// <NAME>_MU … <NAME>_A2), computed exactly as model::Network::Forward does: the same operations in
// the same order, every weight, bias, normalisation bound and range as an exact hex-float literal
// (with its 17-digit decimal value in a comment), and the eight MATLAB transfer functions in a
// helper <name>_transfer(code, n). Compiled without -ffast-math, its results equal the library's to
// the last bit on machines without fused multiply-add contraction (x86-64), and to within a few
// ulp elsewhere.
#pragma once

#include <string>

#include "io/network_io.h"
#include "model/c_text.h"
#include "model/status.h"

namespace pz::model {
class ModalSimulator;
}

namespace pz::controller {

// CHexLiteral, CDecimal, CUpper and IsCIdentifier: model/c_text.h.

/// The header text. Requires a valid network and a C identifier (kInvalidArgument otherwise).
Status NetworkToCHeader(const io::SavedNetwork& saved, const std::string& name,
                        std::string* header);

/// What the fin plant's part of the header needs besides the network (controller/export_fin_c.h).
struct FinPlantExport {
  double sample_rate_hz = 100.0;  ///< the controller's sample rate (the bench cases' 100 Hz), > 0
  double drive_limit_v = 0.0;     ///< |u| ≤ this [V]; 0 = the largest training amplitude
  int inverse_horizon = 2;  ///< samples over which NAME_inverse_step reaches its target, ≥ 1
  std::string note;  ///< a sentence for the plant's comment (e.g. the job and its saturations)
};

/// The same header with the bimorph-fin plant of `plant` after the network
/// (controller/export_fin_c.h): NAME_params, NAME_init, NAME_step, NAME_inverse_step.
Status NetworkAndFinToCHeader(const io::SavedNetwork& saved, const model::ModalSimulator& plant,
                              const FinPlantExport& options, const std::string& name,
                              std::string* header);

}  // namespace pz::controller
