// Liveness after zguide's Paranoid Pirate (conventions 10, 11): pure bookkeeping that takes `now`
// as an argument, so tests need no sleeps. Any message from a peer counts as a heartbeat.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace pz::service {

using Clock = std::chrono::steady_clock;
using TimePoint = Clock::time_point;
using Duration = Clock::duration;

/// The master's view of many peers (workers): a peer silent for `liveness` heartbeat intervals
/// is expired.
class PeerLiveness {
 public:
  PeerLiveness(Duration heartbeat_interval, int liveness);

  /// Records that `id` was heard from (adds it if new).
  void Seen(const std::string& id, TimePoint now);
  void Remove(const std::string& id);
  bool Contains(const std::string& id) const { return last_seen_.count(id) > 0; }
  size_t size() const { return last_seen_.size(); }
  /// The peers, sorted.
  std::vector<std::string> ids() const;

  /// Removes and returns the peers not heard from for longer than interval × liveness.
  std::vector<std::string> TakeExpired(TimePoint now);
  /// Earliest time at which some peer could expire (TimePoint::max() if none).
  TimePoint NextExpiry() const;

  /// True when heartbeats are due to all peers; then schedules the next ones.
  bool HeartbeatDue(TimePoint now);
  TimePoint next_heartbeat() const { return next_heartbeat_; }

  Duration timeout() const { return interval_ * liveness_; }

 private:
  Duration interval_;
  int liveness_;
  std::unordered_map<std::string, TimePoint> last_seen_;
  TimePoint next_heartbeat_{};
};

/// Exponential reconnect back-off: initial, 2×, 4× … capped at max; Reset() after success.
class Backoff {
 public:
  Backoff(Duration initial, Duration max) : initial_(initial), max_(max), next_(initial) {}
  Duration Next();
  void Reset() { next_ = initial_; }

 private:
  Duration initial_, max_, next_;
};

/// A worker's view of its master: expired after `liveness` silent intervals; heartbeats due
/// every interval.
class ServerLiveness {
 public:
  ServerLiveness(Duration heartbeat_interval, int liveness)
      : interval_(heartbeat_interval), liveness_(liveness) {}
  void Reset(TimePoint now) {
    last_seen_ = now;
    next_heartbeat_ = now + interval_;
  }
  void Seen(TimePoint now) { last_seen_ = now; }
  bool Expired(TimePoint now) const { return now - last_seen_ > interval_ * liveness_; }
  /// True when a heartbeat should be sent now; schedules the next one.
  bool HeartbeatDue(TimePoint now);
  TimePoint next_heartbeat() const { return next_heartbeat_; }

 private:
  Duration interval_;
  int liveness_;
  TimePoint last_seen_{}, next_heartbeat_{};
};

}  // namespace pz::service
