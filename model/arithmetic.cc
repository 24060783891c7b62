#include "model/arithmetic.h"

#if defined(__GLIBC__)
#include <gnu/libc-version.h>
#endif

#include "pz_build_id.h"  // PIEZOID_BUILD_ID (cmake/build_id.cmake)

namespace pz::model {

std::string InstructionSetLevel() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("x86-64-v3")) return "x86-64-v3";
  if (__builtin_cpu_supports("fma") && __builtin_cpu_supports("avx2")) return "x86-64+fma";
  return "x86-64";
#elif defined(__x86_64__)
  return "x86-64";
#elif defined(__aarch64__)
  return "aarch64";
#else
  return "unknown-architecture";
#endif
}

std::string ArithmeticProfile() {
  std::string p = std::string("piezoid ") + PIEZOID_VERSION + " (" + PIEZOID_BUILD_ID + "); " +
                  InstructionSetLevel();
#if defined(__GLIBC__)
  p += std::string("; glibc ") + gnu_get_libc_version();
#else
  p += "; libc unknown";
#endif
  return p;
}

}  // namespace pz::model
