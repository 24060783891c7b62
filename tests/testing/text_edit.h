// Test helpers that edit a stored file's text (to plant one bad value in an otherwise valid file).
#pragma once

#include <gtest/gtest.h>

#include <string>

namespace pz::testing {

/// `text` with the first `from` after the first `after` replaced by `to` (a failure if not found).
inline std::string Replaced(std::string text, const std::string& after, const std::string& from,
                            const std::string& to) {
  const size_t at = text.find(from, text.find(after));
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

/// `text` with the value after the first `key` (up to its comma or line end) replaced by `to`.
inline std::string ValueReplaced(std::string text, const std::string& key, const std::string& to) {
  const size_t at = text.find(key);
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return text;
  const size_t from = at + key.size(), end = text.find_first_of(",\n", from);
  return text.replace(from, end - from, to);
}

}  // namespace pz::testing
