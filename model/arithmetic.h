// What decides the last bits of a result this process computes, so that a master can keep the
// workers of one job computing alike (determinism: same seed and data ⇒ same result bit for bit,
// whatever the workers). Two x86-64 machines with and without AVX2/FMA run different copies of the
// kernels compiled twice (target_clones: the AVX2 copy fuses multiply-adds) and of the C library's
// exp/sin/cos/…; a different build or C library may differ too.
#pragma once

#include <string>

namespace pz::model {

/// E.g. "piezoid 0.1.0 (142f992abcde); x86-64-v3; glibc 2.36": the build's version and commit (`git
/// describe --always --dirty` of its checkout, "unknown" outside one), the instruction-set level
/// the cloned kernels and the C library's maths run at on this CPU, and the C library. Processes
/// with equal profiles compute every fitness bit for bit alike.
std::string ArithmeticProfile();

/// The instruction-set part alone: "x86-64-v3", "x86-64+fma" (FMA and AVX2 without the rest of
/// level 3: the C library's FMA variants but the kernels' baseline copy), "x86-64", or the
/// architecture's name elsewhere.
std::string InstructionSetLevel();

}  // namespace pz::model
