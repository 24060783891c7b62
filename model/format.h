// Numbers in messages and reports: printf's %g with a given number of significant digits (the
// same text as an ostream with that precision). One helper for the error messages of model/ and
// the reports above it, which cannot reach io/'s CSV formatting from model/.
#pragma once

#include <cstdio>
#include <string>

namespace pz {

inline std::string FormatG(double x, int significant) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*g", significant, x);
  return buf;
}

}  // namespace pz
