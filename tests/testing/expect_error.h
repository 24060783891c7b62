// Test helpers for error-message assertions (gtest only, no gmock).
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "model/status.h"

/// EXPECT that `needle` occurs in `haystack` (both convertible to std::string).
#define PZ_EXPECT_HAS(haystack, needle) \
  EXPECT_PRED_FORMAT2(::testing::IsSubstring, std::string(needle), std::string(haystack))

namespace pz::testing {

/// Runs f and returns the message of the pz::InputError it throws, or a marker when it throws none.
template <typename F>
std::string InputErrorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no pz::InputError thrown>";
}

}  // namespace pz::testing
