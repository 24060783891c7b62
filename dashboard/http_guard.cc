#include "dashboard/http_guard.h"  // last: httplib.h

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace pz::dashboard {

namespace {

using Clock = std::chrono::steady_clock;

void CloseSocket(int fd) {
  ::shutdown(fd, SHUT_RDWR);
  ::close(fd);
}

bool SetBlocking(int fd, bool blocking) {
  const int flags = ::fcntl(fd, F_GETFL, 0);
  if (flags < 0) return false;
  return ::fcntl(fd, F_SETFL, blocking ? (flags & ~O_NONBLOCK) : (flags | O_NONBLOCK)) == 0;
}

/// The numeric address of a socket's peer or of its own end ("" and 0 if unknown).
void AddressOf(int fd, bool peer, std::string& ip, int& port) {
  sockaddr_storage addr{};
  socklen_t len = sizeof(addr);
  ip.clear();
  port = 0;
  if ((peer ? ::getpeername(fd, reinterpret_cast<sockaddr*>(&addr), &len)
            : ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len)) != 0)
    return;
  char buf[INET6_ADDRSTRLEN] = {};
  if (addr.ss_family == AF_INET) {
    const auto* a = reinterpret_cast<const sockaddr_in*>(&addr);
    ::inet_ntop(AF_INET, &a->sin_addr, buf, sizeof(buf));
    port = ntohs(a->sin_port);
  } else if (addr.ss_family == AF_INET6) {
    const auto* a = reinterpret_cast<const sockaddr_in6*>(&addr);
    ::inet_ntop(AF_INET6, &a->sin6_addr, buf, sizeof(buf));
    port = ntohs(a->sin6_port);
  }
  ip = buf;
}

/// Writes a whole short reply without blocking for long (the connection is closed after it).
void ReplyAndClose(int fd, const char* reply) {
  SetBlocking(fd, true);
  timeval tv{0, 200000};
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof(tv));
  (void)!::send(fd, reply, std::strlen(reply), MSG_NOSIGNAL);
  // Unread input at close() makes the kernel reset the connection, and the peer may lose the reply:
  // end our side, then read what has already arrived (never wait for more).
  ::shutdown(fd, SHUT_WR);
  char sink[4096];
  for (int i = 0; i < 16 && ::recv(fd, sink, sizeof(sink), MSG_DONTWAIT) > 0; ++i) {
  }
  ::close(fd);
}

/// A socket stream whose first bytes were already read (the request head): httplib's routing reads
/// them, then the socket, with the server's timeouts.
class HeadFirstStream final : public httplib::Stream {
 public:
  HeadFirstStream(int fd, std::string buffered, int read_timeout_ms, int write_timeout_ms)
      : fd_(fd),
        buffered_(std::move(buffered)),
        read_ms_(read_timeout_ms),
        write_ms_(write_timeout_ms) {}

  bool is_readable() const override { return pos_ < buffered_.size() || Wait(POLLIN, read_ms_); }
  bool is_writable() const override { return Wait(POLLOUT, write_ms_); }
  ssize_t read(char* ptr, size_t size) override {
    if (pos_ < buffered_.size()) {
      const size_t n = std::min(size, buffered_.size() - pos_);
      std::memcpy(ptr, buffered_.data() + pos_, n);
      pos_ += n;
      return static_cast<ssize_t>(n);
    }
    if (!Wait(POLLIN, read_ms_)) return -1;
    ssize_t n;
    do n = ::recv(fd_, ptr, size, 0);
    while (n < 0 && errno == EINTR);
    return n;
  }
  ssize_t write(const char* ptr, size_t size) override {
    if (!Wait(POLLOUT, write_ms_)) return -1;
    ssize_t n;
    do n = ::send(fd_, ptr, size, MSG_NOSIGNAL);
    while (n < 0 && errno == EINTR);
    return n;
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    AddressOf(fd_, true, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    AddressOf(fd_, false, ip, port);
  }
  socket_t socket() const override { return fd_; }

 private:
  bool Wait(short events, int timeout_ms) const {
    pollfd p{fd_, events, 0};
    int r;
    do r = ::poll(&p, 1, timeout_ms);
    while (r < 0 && errno == EINTR);
    return r > 0 && (p.revents & (events | POLLHUP)) != 0;
  }
  int fd_;
  std::string buffered_;
  size_t pos_ = 0;
  int read_ms_, write_ms_;
};

}  // namespace

GuardedServer::GuardedServer(HttpGuardOptions options) : options_(options) {
  options_.per_peer = std::max(1, options_.per_peer);
  options_.max_pending = std::max(options_.per_peer, options_.max_pending);
  options_.workers = std::max(1, options_.workers);
  options_.max_queued = std::max(1, options_.max_queued);
  // httplib's own pool only hands connections over: two threads are plenty.
  new_task_queue = [] { return new httplib::ThreadPool(2); };
  epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  epoll_event ev{};
  ev.events = EPOLLIN;
  ev.data.fd = wake_fd_;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &ev);
  reader_ = std::thread([this] { ReaderLoop(); });
  for (int i = 0; i < options_.workers; ++i) workers_.emplace_back([this] { WorkerLoop(); });
}

GuardedServer::~GuardedServer() {
  Shutdown();
  ::close(epoll_fd_);
  ::close(wake_fd_);
}

void GuardedServer::Shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  stop();  // httplib's listener: no new connections
  {
    std::lock_guard lock(mu_);
    stopping_ = true;
  }
  Wake();
  ready_cv_.notify_all();
  if (reader_.joinable()) reader_.join();
  for (std::thread& t : workers_)
    if (t.joinable()) t.join();
  std::lock_guard lock(mu_);
  for (int fd : incoming_) CloseSocket(fd);
  incoming_.clear();
  for (const Ready& r : ready_) CloseSocket(r.fd);
  ready_.clear();
}

int GuardedServer::Bind(const std::string& host, int port) {
  const int bound = port == 0 ? bind_to_any_port(host) : (bind_to_port(host, port) ? port : -1);
  if (bound > 0) ::listen(svr_sock_, SOMAXCONN);  // a second listen() only raises the backlog
  return bound;
}

HttpGuardCounters GuardedServer::counters() const {
  std::lock_guard lock(mu_);
  return counters_;
}

void GuardedServer::Wake() {
  const uint64_t one = 1;
  (void)!::write(wake_fd_, &one, sizeof(one));
}

bool GuardedServer::process_and_close_socket(socket_t sock) {
  {
    std::lock_guard lock(mu_);
    if (stopping_) {
      CloseSocket(sock);
      return false;
    }
    incoming_.push_back(sock);
    ++counters_.accepted;
  }
  Wake();
  return true;
}

bool GuardedServer::Live(const Entry& e) const {
  auto it = pending_.find(e.first);
  return it != pending_.end() && it->second.seq == e.second;
}

void GuardedServer::Drop(int fd, uint64_t HttpGuardCounters::*counter) {
  auto it = pending_.find(fd);
  if (it == pending_.end()) return;
  if (--peer_count_[it->second.peer] == 0) {
    peer_count_.erase(it->second.peer);
    by_peer_.erase(it->second.peer);
  }
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
  pending_.erase(it);
  {
    std::lock_guard lock(mu_);  // counted before the peer can see the close
    if (counter != nullptr) ++(counters_.*counter);
    counters_.pending = pending_.size();
  }
  if (counter == &HttpGuardCounters::oversized)
    ReplyAndClose(fd,
                  "HTTP/1.1 431 Request Header Fields Too Large\r\nConnection: "
                  "close\r\nContent-Length: 0\r\n\r\n");
  else if (counter != nullptr)
    CloseSocket(fd);
}

void GuardedServer::ReadFrom(int fd) {
  auto it = pending_.find(fd);
  if (it == pending_.end()) return;
  Pending& p = it->second;
  char buf[4096];
  for (;;) {
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    if (n > 0) {
      const size_t scan_from = p.head.size() >= 3 ? p.head.size() - 3 : 0;
      p.head.append(buf, static_cast<size_t>(n));
      if (p.head.find("\r\n\r\n", scan_from) != std::string::npos ||
          p.head.find("\n\n", scan_from) != std::string::npos) {
        Ready r{fd, std::move(p.head)};
        Drop(fd, nullptr);  // leaves the socket open
        SetBlocking(fd, true);
        std::unique_lock lock(mu_);
        if (static_cast<int>(ready_.size()) >= options_.max_queued) {
          ++counters_.overloaded;
          lock.unlock();
          ReplyAndClose(
              fd,
              "HTTP/1.1 503 Service Unavailable\r\nConnection: close\r\nContent-Length: 0\r\n\r\n");
          return;
        }
        ready_.push_back(std::move(r));
        lock.unlock();
        ready_cv_.notify_one();
        return;
      }
      if (p.head.size() > options_.max_head_bytes) return Drop(fd, &HttpGuardCounters::oversized);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
    return Drop(
        fd, &HttpGuardCounters::timed_out);  // closed by the peer or an error: nothing to answer
  }
}

void GuardedServer::ReaderLoop() {
  std::vector<epoll_event> events(64);
  for (;;) {
    std::vector<int> incoming;
    {
      std::lock_guard lock(mu_);
      if (stopping_) break;
      incoming.swap(incoming_);
    }
    const Clock::time_point now = Clock::now();
    for (int fd : incoming) {
      Pending p;
      p.fd = fd;
      p.seq = next_seq_++;
      int port = 0;
      AddressOf(fd, true, p.peer, port);
      p.deadline = now + options_.head_timeout;
      // The peer's oldest pending connection (then the oldest of all) makes room for this one.
      if (peer_count_[p.peer] >= options_.per_peer) {
        std::deque<Entry>& q = by_peer_[p.peer];
        while (!q.empty() && !Live(q.front())) q.pop_front();
        if (!q.empty()) Drop(q.front().first, &HttpGuardCounters::dropped);
      }
      while (static_cast<int>(pending_.size()) >= options_.max_pending && !arrival_.empty()) {
        const Entry e = arrival_.front();
        arrival_.pop_front();
        if (Live(e)) Drop(e.first, &HttpGuardCounters::dropped);
      }
      if (!SetBlocking(fd, false)) {
        CloseSocket(fd);
        continue;
      }
      epoll_event ev{};
      ev.events = EPOLLIN | EPOLLRDHUP;
      ev.data.fd = fd;
      if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &ev) != 0) {
        CloseSocket(fd);
        continue;
      }
      arrival_.emplace_back(fd, p.seq);
      by_peer_[p.peer].emplace_back(fd, p.seq);
      ++peer_count_[p.peer];
      pending_.emplace(fd, std::move(p));
      std::lock_guard lock(mu_);
      counters_.pending = pending_.size();
    }
    // Heads that took too long (deadlines grow with arrival).
    while (!arrival_.empty()) {
      const Entry e = arrival_.front();
      if (!Live(e)) {
        arrival_.pop_front();
        continue;
      }
      if (pending_.at(e.first).deadline > Clock::now()) break;
      arrival_.pop_front();
      Drop(e.first, &HttpGuardCounters::timed_out);
    }
    int timeout_ms = 1000;
    if (!arrival_.empty()) {
      const auto left = pending_.at(arrival_.front().first).deadline - Clock::now();
      timeout_ms = static_cast<int>(std::clamp<int64_t>(
          std::chrono::duration_cast<std::chrono::milliseconds>(left).count() + 1, 0, 1000));
    }
    const int n =
        ::epoll_wait(epoll_fd_, events.data(), static_cast<int>(events.size()), timeout_ms);
    for (int i = 0; i < n; ++i) {
      const int fd = events[i].data.fd;
      if (fd == wake_fd_) {
        uint64_t v;
        (void)!::read(wake_fd_, &v, sizeof(v));
        continue;
      }
      ReadFrom(fd);
    }
  }
  for (auto& [fd, p] : pending_) CloseSocket(fd);
  pending_.clear();
  arrival_.clear();
  by_peer_.clear();
  peer_count_.clear();
}

void GuardedServer::WorkerLoop() {
  for (;;) {
    Ready r;
    {
      std::unique_lock lock(mu_);
      ready_cv_.wait(lock, [this] { return stopping_ || !ready_.empty(); });
      if (stopping_) return;
      r = std::move(ready_.front());
      ready_.pop_front();
      ++counters_.answered;
    }
    Serve(std::move(r));
  }
}

void GuardedServer::Serve(Ready r) {
  const int read_ms = static_cast<int>(read_timeout_sec_ * 1000 + read_timeout_usec_ / 1000);
  const int write_ms = static_cast<int>(write_timeout_sec_ * 1000 + write_timeout_usec_ / 1000);
  HeadFirstStream stream(r.fd, std::move(r.head), read_ms, write_ms);
  bool closed = false;
  process_request(stream, /*close_connection=*/true, closed, nullptr);
  CloseSocket(r.fd);
}

}  // namespace pz::dashboard
