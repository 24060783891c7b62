#include "service/liveness.h"

#include <algorithm>

namespace pz::service {

PeerLiveness::PeerLiveness(Duration heartbeat_interval, int liveness)
    : interval_(heartbeat_interval), liveness_(std::max(1, liveness)) {}

void PeerLiveness::Seen(const std::string& id, TimePoint now) { last_seen_[id] = now; }

void PeerLiveness::Remove(const std::string& id) { last_seen_.erase(id); }

std::vector<std::string> PeerLiveness::TakeExpired(TimePoint now) {
  std::vector<std::string> out;
  for (auto it = last_seen_.begin(); it != last_seen_.end();) {
    if (now - it->second > timeout()) {
      out.push_back(it->first);
      it = last_seen_.erase(it);
    } else {
      ++it;
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> PeerLiveness::ids() const {
  std::vector<std::string> out;
  for (const auto& [id, seen] : last_seen_) out.push_back(id);
  std::sort(out.begin(), out.end());
  return out;
}

TimePoint PeerLiveness::NextExpiry() const {
  TimePoint t = TimePoint::max();
  for (const auto& [id, seen] : last_seen_) t = std::min(t, seen + timeout());
  return t;
}

bool PeerLiveness::HeartbeatDue(TimePoint now) {
  if (now < next_heartbeat_) return false;
  next_heartbeat_ = now + interval_;
  return true;
}

Duration Backoff::Next() {
  Duration d = next_;
  next_ = std::min(max_, next_ * 2);
  return d;
}

bool ServerLiveness::HeartbeatDue(TimePoint now) {
  if (now < next_heartbeat_) return false;
  next_heartbeat_ = now + interval_;
  return true;
}

}  // namespace pz::service
