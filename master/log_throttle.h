// Repeated log lines at most once per interval and key (a flood of garbage frames, a disk that
// stays full): the first line of a key is logged, later ones within `interval` are only counted,
// and the next line logged says how many were left out. Thread-safe; takes `now` (liveness.h).
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>

#include "service/liveness.h"

namespace pz::master {

class LogThrottle {
 public:
  explicit LogThrottle(service::Duration interval) : interval_(interval) {}

  /// Whether a line of `key` may be logged at `now`; then *suppressed is the number of lines of
  /// that key not logged since the last one (0 when none).
  bool Allow(const std::string& key, service::TimePoint now, uint64_t* suppressed) {
    std::lock_guard lock(mu_);
    if (keys_.size() > 4096) keys_.clear();  // bounded: keys are a few kinds of event
    auto [it, fresh] = keys_.try_emplace(key);
    Entry& e = it->second;
    if (!fresh && now - e.last < interval_) {
      ++e.suppressed;
      return false;
    }
    *suppressed = e.suppressed;
    e.suppressed = 0;
    e.last = now;
    return true;
  }

 private:
  struct Entry {
    service::TimePoint last{};
    uint64_t suppressed = 0;
  };
  service::Duration interval_;
  std::mutex mu_;
  std::map<std::string, Entry> keys_;
};

}  // namespace pz::master
