// What decides the last bits of a result this process computes, measured, so that a master keeps
// the workers of a job computing alike (determinism: same seed and data ⇒ same result bit for bit,
// whatever the workers) by what they compute, not by what they are called.
//
// The same build computes different bits on different x86-64 machines through what is chosen at
// run time from the CPU: the C library's exp / log / pow / sin / … (glibc's FMA and non-FMA
// variants, chosen by ifunc), the kernels this project compiles twice (target_clones: the
// x86-64-v3 copy fuses multiply-adds), and the BLAS kernels of the dense backend (OpenBLAS picks
// its kernels by CPU core: OPENBLAS_CORETYPE). Eigen's products are NOT among them: Eigen sized its
// product blocks from the cache sizes it read with CPUID (a 48 KiB L1 sums Jᵀ J in another order
// than a 32 KiB one), which the build turns off (EIGEN_NO_CPUID, top-level CMakeLists.txt), so
// every machine uses the same blocks. docs/architecture.md, "Arithmetic".
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace pz::model {

/// One measured part of the arithmetic: a fixed computation whose result bits are hashed.
struct ArithmeticPart {
  std::string name;     ///< "libm", "eigen", "dense", "fin", "cvode", "tansig"
  std::string what;     ///< what it computes, for `piezoid doctor`
  uint64_t digest = 0;  ///< FNV-1a over the result's bits
};

/// The parts, computed once per process (≈ 20 ms) on first use; thread-safe.
const std::vector<ArithmeticPart>& MeasuredArithmetic();

/// "libm=… eigen=… dense=… fin=… cvode=… tansig=…" (16 hex digits each): two processes with the
/// same fingerprint compute these kernels bit for bit alike.
std::string ArithmeticFingerprint();

/// One 16-hex-digit digest of the whole fingerprint (what regression pins name: tests/testing).
std::string ArithmeticDigest();

/// E.g. "piezoid 0.1.0 (142f992abcde); libm=… eigen=… …": the build's version and commit (`git
/// describe --always --dirty` of its checkout, "unknown" outside one) and the measured
/// fingerprint. Processes with equal profiles compute every fitness bit for bit alike; a master
/// serves one profile (master/broker.h).
std::string ArithmeticProfile();

/// The parts in which two profiles differ, named with both values, e.g. "libm (3f2a… here,
/// 91c0… there)"; "the build (…)" when the builds differ; "" when they are equal. A profile of
/// another format (an older build's) differs as a whole.
std::string ArithmeticDifference(const std::string& ours, const std::string& theirs);

/// The instruction-set part alone: "x86-64-v3", "x86-64+fma" (FMA and AVX2 without the rest of
/// level 3: the C library's FMA variants but the kernels' baseline copy), "x86-64", or the
/// architecture's name elsewhere.
std::string InstructionSetLevel();

/// `piezoid doctor`'s lines as (key, value): build, instruction-set level, C library, dense
/// backend and its core, Eigen and its blocking, each measured part, the digest. One line each, so
/// two machines are compared by diffing two outputs.
std::vector<std::pair<std::string, std::string>> ArithmeticReport();

/// Test hook: PIEZOID_ARITHMETIC_SKEW=<part> makes this process compute as another machine would:
/// that part's digest differs, and a worker nudges every fitness it returns by one ulp
/// (worker/worker.cc). Empty when unset. Never set it outside tests.
const std::string& ArithmeticSkew();

}  // namespace pz::model
