// An HTTP server (cpp-httplib) that a slow or half-open client cannot stall (issue 24).
//
// cpp-httplib hands every accepted connection to a pool thread that blocks reading the request
// line, each read waiting up to its read timeout: 16 clients that send part of a request line and
// nothing else hold a pool of 8 threads for as long as they like, and every other request waits.
// GuardedServer takes the connection from httplib at once and reads request heads itself:
//
//  - one thread reads the heads of all pending connections with epoll (non-blocking): a head must
//    be complete (the blank line) within `head_timeout` of the connection's arrival and within
//    `max_head_bytes`, else the connection is closed (431 for an oversized head);
//  - at most `per_peer` connections of one address may be reading their head: a new one from that
//    address drops that address's oldest pending one (so a flood cannot shut out a normal client,
//    even from the same address); at most `max_pending` in all, the oldest dropped likewise;
//  - a complete head goes to `workers` threads, which answer it through httplib's routing
//    (one request per connection, `Connection: close`) with the server's read/write timeouts;
//    at most `max_queued` complete requests wait for a worker (beyond: 503 and close).
// Memory is bounded by max_pending × max_head_bytes + max_queued × max_head_bytes.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

// Last in every includer: <resolv.h>, which httplib.h includes, defines a macro `_res`.
#include <httplib.h>

namespace pz::dashboard {

struct HttpGuardOptions {
  std::chrono::milliseconds head_timeout{2000};  ///< the whole request head must arrive within this
  size_t max_head_bytes = 16384;                 ///< larger heads are refused (431)
  int per_peer = 16;                             ///< pending connections per peer address, ≥ 1
  int max_pending = 1024;                        ///< pending connections in all, ≥ per_peer
  int workers = 8;                               ///< threads answering complete requests, ≥ 1
  int max_queued = 256;                          ///< complete requests waiting for a worker, ≥ 1
};

/// What the guard did since it started.
struct HttpGuardCounters {
  uint64_t accepted = 0;   ///< connections taken from httplib
  uint64_t answered = 0;   ///< complete requests handed to httplib's routing
  uint64_t timed_out = 0;  ///< closed: head not complete within head_timeout
  uint64_t dropped = 0;  ///< closed: a newer connection of the same peer (or of all) took its place
  uint64_t oversized = 0;   ///< closed: head longer than max_head_bytes
  uint64_t overloaded = 0;  ///< answered 503: too many complete requests waiting
  uint64_t pending = 0;     ///< connections reading their head now
};

class GuardedServer : public httplib::Server {
 public:
  explicit GuardedServer(HttpGuardOptions options = {});
  ~GuardedServer() override;
  GuardedServer(const GuardedServer&) = delete;
  GuardedServer& operator=(const GuardedServer&) = delete;

  /// Binds like httplib's bind_to_port (port 0: any free port) with a listen backlog of SOMAXCONN
  /// instead of httplib's 5, so a burst of connections is not turned away by the kernel. Returns
  /// the port, or −1.
  int Bind(const std::string& host, int port);
  /// Stops httplib's listener, the head reader and the workers, and closes every pending
  /// connection. Idempotent; the destructor calls it.
  void Shutdown();
  HttpGuardCounters counters() const;

 private:
  struct Pending {
    int fd = -1;
    uint64_t seq = 0;  ///< arrival number: tells a live entry of arrival_ from a reused fd
    std::string peer;
    std::chrono::steady_clock::time_point deadline;
    std::string head;
  };
  struct Ready {
    int fd = -1;
    std::string head;  ///< every byte read so far (the head and possibly the start of a body)
  };

  bool process_and_close_socket(socket_t sock) override;
  void ReaderLoop();
  void WorkerLoop();
  void Serve(Ready r);
  void Drop(int fd, uint64_t HttpGuardCounters::*counter);  // reader thread only
  void ReadFrom(int fd);                                    // reader thread only
  void Wake();

  HttpGuardOptions options_;
  int epoll_fd_ = -1, wake_fd_ = -1;
  std::thread reader_;
  std::vector<std::thread> workers_;
  bool shut_down_ = false;

  mutable std::mutex mu_;  // guards everything below
  std::condition_variable ready_cv_;
  bool stopping_ = false;
  std::vector<int> incoming_;  ///< accepted, not yet seen by the reader
  std::deque<Ready> ready_;
  HttpGuardCounters counters_;

  // Reader thread only.
  using Entry = std::pair<int, uint64_t>;  ///< (fd, seq)
  bool Live(const Entry& e) const;
  std::map<int, Pending> pending_;  ///< by fd
  std::deque<Entry> arrival_;       ///< in arrival order; entries of closed fds are skipped
  std::map<std::string, std::deque<Entry>> by_peer_;
  std::map<std::string, int> peer_count_;  ///< live pending connections per peer
  uint64_t next_seq_ = 0;
};

}  // namespace pz::dashboard
