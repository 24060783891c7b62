// Text of generated C code: the helpers both C exporters use (controller/export_header.h for fitted
// record models, controller/export_c.h for HGANN networks and the fin plant).
#pragma once

#include <cctype>
#include <cstdio>
#include <string>

namespace pz {

/// An exact C literal of x: hex-float, e.g. 0x1.91eb851eb851fp+1.
inline std::string CHexLiteral(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%a", x);
  return buf;
}

/// x to 17 significant digits (the decimal value of CHexLiteral in comments).
inline std::string CDecimal(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

/// s in upper case (macro and include-guard names).
inline std::string CUpper(const std::string& s) {
  std::string u = s;
  for (char& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return u;
}

/// True iff `name` is a C identifier ([A-Za-z_][A-Za-z0-9_]*, ≤ 63 characters).
inline bool IsCIdentifier(const std::string& name) {
  if (name.empty() || name.size() > 63) return false;
  if (!(std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_')) return false;
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

}  // namespace pz
