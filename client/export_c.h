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
#include "model/status.h"

namespace pz::client {

/// True iff `name` is a C identifier ([A-Za-z_][A-Za-z0-9_]*, ≤ 63 characters).
bool IsCIdentifier(const std::string& name);

/// The header text. Requires a valid network and a C identifier (kInvalidArgument otherwise).
Status NetworkToCHeader(const io::SavedNetwork& saved, const std::string& name, std::string* header);

}  // namespace pz::client
