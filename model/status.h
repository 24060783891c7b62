// Error tiers (docs/architecture.md): bugs abort through PZ_CHECK; bad configuration or input is a
// pz::Status (or a thrown pz::InputError carrying one); expected runtime failures are values.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace pz {

/// Status codes. 0 = kOk. kInvalidArgument is deterministic (never retry); kUnavailable is
/// transient.
enum class StatusCode : int {
  kOk = 0,
  kInvalidArgument = 1,
  kNotFound = 2,
  kFailedPrecondition = 3,
  kOutOfRange = 4,
  kInternal = 5,
  kUnavailable = 6,
  kCancelled = 7,
  kDataLoss = 8,
};

const char* StatusCodeName(StatusCode code);

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return {}; }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  std::string ToString() const;

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

inline Status InvalidArgument(std::string msg) {
  return {StatusCode::kInvalidArgument, std::move(msg)};
}
inline Status NotFound(std::string msg) { return {StatusCode::kNotFound, std::move(msg)}; }
inline Status OutOfRange(std::string msg) { return {StatusCode::kOutOfRange, std::move(msg)}; }
inline Status Internal(std::string msg) { return {StatusCode::kInternal, std::move(msg)}; }

/// Exception carrying a Status: thrown for bad configuration or input at API boundaries
/// (never across a process boundary or a SUNDIALS callback).
class InputError : public std::runtime_error {
 public:
  explicit InputError(Status s) : std::runtime_error(s.message()), status_(std::move(s)) {}
  explicit InputError(const std::string& msg)
      : InputError(Status(StatusCode::kInvalidArgument, msg)) {}
  const Status& status() const { return status_; }

 private:
  Status status_;
};

/// Throws InputError if !s.ok().
inline void ThrowIfError(const Status& s) {
  if (!s.ok()) throw InputError(s);
}

/// Formats "field = value: rule" messages used by every Validate().
template <typename T>
std::string FieldError(const std::string& field, const T& value, const std::string& rule) {
  std::ostringstream os;
  os.precision(17);
  os << field << " = " << value << ": " << rule;
  return os.str();
}

[[noreturn]] void CheckFailed(const char* expr, const char* file, int line, const std::string& msg);

}  // namespace pz

/// Always-on invariant check: a failure is a bug and aborts with the location.
#define PZ_CHECK(cond)                                                        \
  do {                                                                        \
    if (!(cond)) ::pz::CheckFailed(#cond, __FILE__, __LINE__, std::string()); \
  } while (0)
#define PZ_CHECK_MSG(cond, msg)                                       \
  do {                                                                \
    if (!(cond)) ::pz::CheckFailed(#cond, __FILE__, __LINE__, (msg)); \
  } while (0)
