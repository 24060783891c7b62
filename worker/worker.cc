#include "worker/worker.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <cmath>
#include <deque>
#include <limits>
#include <list>
#include <map>
#include <mutex>
#include <span>
#include <thread>
#include <unordered_map>
#include <zmq.hpp>

#include "model/arithmetic.h"
#include "opt/inline_evaluator.h"
#include "service/liveness.h"
#include "service/wire_codec.h"

namespace pz::worker {
namespace {

using service::Clock;
using service::TimePoint;
using service::WireCode;
using service::WorkerMsg;

struct Context {
  job::JobSpec spec;
  std::unique_ptr<opt::FitnessFunction> fitness;
};

struct LocalLease {
  service::TaskBatchMsg batch;
  std::shared_ptr<const Context> context;
  std::vector<opt::FitnessResult> results;
  // The compute threads take its tasks one at a time (a task per fetch_add; a fitness with lanes:
  // that many consecutive ones), so a thread runs on to the next task without a round trip
  // through anyone, and the lease's tail is shared to the last task (group).
  std::atomic<int> next{0};            // next task not yet taken by a thread
  std::atomic<bool> abandoned{false};  // its threads take no more tasks
  // Under Handout::mu:
  bool queued = false;  // in Handout::queue (threads may still join it)
  int in_progress = 0;  // threads working on it (it lives until they are all back)
  int done = 0;         // tasks evaluated
  double eval_s = 0;    // their summed evaluation time [s]
};

/// The leases the compute threads take work from, in arrival order. A thread that runs out of
/// tasks in one lease goes straight on to the next one queued, without the I/O thread; the I/O
/// thread hears of a lease once, from the last thread to leave it when nobody can join it any more
/// (its tasks all taken, or abandoned).
struct Handout {
  std::mutex mu;
  std::condition_variable cv;
  std::deque<LocalLease*> queue;
  bool stop = false;
};

// inproc messages from a compute thread to the I/O thread carry this POD (same process).
struct Done {
  LocalLease* lease;  ///< the lease nobody works on any more; nullptr = the thread has stopped
};

void ComputeLoop(zmq::context_t& ctx, const std::string& endpoint, int id, Handout& h) {
  zmq::socket_t s(ctx, zmq::socket_type::dealer);
  s.set(zmq::sockopt::routing_id, "c" + std::to_string(id));
  s.set(zmq::sockopt::linger, 0);
  s.connect(endpoint);
  std::unique_lock lock(h.mu);
  for (;;) {
    h.cv.wait(lock, [&h] { return h.stop || !h.queue.empty(); });
    if (h.stop) break;
    LocalLease& l = *h.queue.front();
    l.in_progress += 1;
    lock.unlock();
    const auto& f = *l.context->fitness;
    const double penalty = l.context->spec.limits.penalty_cost;
    const int total = static_cast<int>(l.batch.genomes.size());
    int tasks = 0;
    double eval_s = 0;
    // A fitness with lanes takes that many consecutive tasks of the lease at a time, side by side
    // (opt::EvaluateGroupGuarded: each genome's result the single path's, bit for bit).
    const int lanes = std::max(1, f.lanes());
    const bool skewed = !model::ArithmeticSkew().empty();
    const std::span<const opt::Genome> genomes = l.batch.genomes;
    const std::span<opt::FitnessResult> results = l.results;
    while (!l.abandoned.load(std::memory_order_relaxed)) {
      const int i = l.next.fetch_add(lanes, std::memory_order_relaxed);
      if (i >= total) break;
      const int m = std::min(lanes, total - i);
      const auto t0 = Clock::now();
      opt::EvaluateGroupGuarded(f, genomes.subspan(i, m), results.subspan(i, m), penalty);
      if (skewed)  // the test hook: computes as another machine would (model/arithmetic.h)
        for (opt::FitnessResult& r : results.subspan(i, m))
          r.cost = std::nextafter(r.cost, std::numeric_limits<double>::infinity());
      eval_s += std::chrono::duration<double>(Clock::now() - t0).count();
      tasks += m;
    }
    lock.lock();
    if (l.queued) {  // nothing left to take (or abandoned: then the I/O thread dequeued it)
      l.queued = false;
      std::erase(h.queue, &l);
    }
    l.in_progress -= 1;
    l.done += tasks;
    l.eval_s += eval_s;
    if (l.in_progress == 0) {  // the last one out: the I/O thread replies and frees it
      lock.unlock();
      Done d{&l};
      s.send(zmq::buffer(&d, sizeof d));
      lock.lock();
    }
  }
  lock.unlock();
  Done bye{nullptr};
  s.send(zmq::buffer(&bye, sizeof bye));
}

}  // namespace

struct Worker::Impl {
  Impl(WorkerOptions o, const job::JobKindRegistry& k)
      : options(std::move(o)),
        kinds(k),
        inproc(ctx, zmq::socket_type::router),
        server(std::chrono::milliseconds(options.heartbeat_ms), options.liveness),
        backoff(std::chrono::milliseconds(options.backoff_initial_ms),
                std::chrono::milliseconds(options.backoff_max_ms)) {}

  WorkerOptions options;
  const job::JobKindRegistry& kinds;
  zmq::context_t ctx{1};
  zmq::socket_t inproc;
  std::unique_ptr<zmq::socket_t> master;
  std::unique_ptr<service::HandshakeMonitor> monitor;  // of `master`
  std::string last_handshake_error;
  std::string inproc_endpoint;
  std::vector<std::thread> threads;
  Handout handout;
  std::unordered_map<LocalLease*, std::unique_ptr<LocalLease>> leases;
  std::map<std::string, std::vector<std::unique_ptr<LocalLease>>> parked;  // by context hash
  std::list<std::pair<std::string, std::shared_ptr<const Context>>>
      contexts;  // LRU, front = newest
  service::ServerLiveness server;
  service::Backoff backoff;
  WorkerStats stats;
  int stopped_threads = 0;  // compute threads that have left their loop

  void Send(const WorkerMsg& m) {
    const std::string payload = service::EncodeWorkerToMaster(m);
    master->send(zmq::buffer(payload), zmq::send_flags::dontwait);
  }

  void Connect() {
    master = std::make_unique<zmq::socket_t>(ctx, zmq::socket_type::dealer);
    master->set(zmq::sockopt::linger, 0);
    master->set(zmq::sockopt::maxmsgsize, options.max_message_bytes);
    master->set(zmq::sockopt::reconnect_ivl, options.backoff_initial_ms);
    master->set(zmq::sockopt::reconnect_ivl_max, options.backoff_max_ms);
    if (options.curve) service::SetCurveClient(*master, *options.curve, options.master_public);
    monitor = std::make_unique<service::HandshakeMonitor>(ctx, *master, "worker");
    master->connect(options.master);
    WorkerMsg ready_msg;
    ready_msg.type = WorkerMsg::Type::kReady;
    ready_msg.threads = options.threads;
    char host[256] = {0};
    ::gethostname(host, sizeof host - 1);
    ready_msg.host = host;
    ready_msg.pid = ::getpid();
    ready_msg.arithmetic =
        options.arithmetic.empty() ? model::ArithmeticProfile() : options.arithmetic;
    Send(ready_msg);
    server.Reset(Clock::now());
  }

  /// Drops every lease (the master re-queues them) and the parked ones. A lease a thread still
  /// works on is freed when its last thread reports (OnDone).
  void AbandonAll() {
    parked.clear();
    std::lock_guard lock(handout.mu);
    handout.queue.clear();
    for (auto it = leases.begin(); it != leases.end();) {
      LocalLease& l = *it->second;
      l.abandoned = true;
      const bool was_queued = l.queued;
      l.queued = false;
      // Not queued with nobody on it: its last thread's report is on its way.
      if (was_queued && l.in_progress == 0)
        it = leases.erase(it);
      else
        ++it;
    }
  }

  void Reconnect(const std::atomic<bool>& stop, const char* why) {
    spdlog::warn("master {}: {}; reconnecting", options.master, why);
    AbandonAll();
    master.reset();
    monitor.reset();
    ++stats.reconnects;
    const auto delay = backoff.Next();
    const auto until = Clock::now() + delay;
    // Keep serving compute threads (finishing their tasks) while waiting.
    while (!stop.load() && Clock::now() < until) {
      PollInproc(std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()));
    }
    if (!stop.load()) Connect();
  }

  std::shared_ptr<const Context> FindContext(const std::string& hash) {
    for (auto it = contexts.begin(); it != contexts.end(); ++it) {
      if (it->first == hash) {
        contexts.splice(contexts.begin(), contexts, it);
        return it->second;
      }
    }
    return nullptr;
  }

  void Reply(LocalLease& l, WireCode code, const std::string& error) {
    WorkerMsg m;
    m.type = WorkerMsg::Type::kResult;
    m.result.lease_id = l.batch.lease_id;
    m.result.job_id = l.batch.job_id;
    m.result.generation = l.batch.generation;
    m.result.code = code;
    m.result.error = error;
    if (code == WireCode::kOk) {
      m.result.indices = l.batch.indices;
      m.result.results = l.results;
      std::lock_guard lock(handout.mu);
      m.result.eval_seconds = l.eval_s;
    }
    Send(m);
  }

  void Enqueue(std::unique_ptr<LocalLease> l, std::shared_ptr<const Context> c) {
    l->context = std::move(c);
    l->results.resize(l->batch.genomes.size());
    ++stats.leases;
    if (l->batch.genomes.empty()) {
      Reply(*l, WireCode::kOk, {});
      return;
    }
    LocalLease* p = l.get();
    leases[p] = std::move(l);
    {
      std::lock_guard lock(handout.mu);
      p->queued = true;
      handout.queue.push_back(p);
    }
    handout.cv.notify_all();
  }

  void OnMaster(std::string_view payload, const std::atomic<bool>& stop) {
    WorkerMsg m;
    pz::Status s = service::DecodeMasterToWorker(payload, &m);
    if (!s.ok()) {
      spdlog::warn("bad frame from the master ignored: {}", s.message());
      return;
    }
    server.Seen(Clock::now());
    backoff.Reset();
    switch (m.type) {
      case WorkerMsg::Type::kBatch: {
        auto l = std::make_unique<LocalLease>();
        l->batch = std::move(m.batch);
        const std::string hash = l->batch.context_hash;
        if (auto c = FindContext(hash)) {
          Enqueue(std::move(l), c);
        } else {
          auto& waiting = parked[hash];
          if (waiting.empty()) {
            WorkerMsg req;
            req.type = WorkerMsg::Type::kContextRequest;
            req.context_hash = hash;
            Send(req);
          }
          waiting.push_back(std::move(l));
        }
        break;
      }
      case WorkerMsg::Type::kContext:
        OnContext(m);
        break;
      case WorkerMsg::Type::kDisconnect:
        if (m.code == WireCode::kInvalidArgument) {  // refused for good: retrying cannot help
          spdlog::error("master {} refused this worker: {}", options.master, m.reason);
          stats.refused = m.reason.empty() ? "refused" : m.reason;
          AbandonAll();
          master.reset();
          monitor.reset();
          break;
        }
        Reconnect(stop, ("master says: " + m.reason).c_str());
        break;
      default:
        break;
    }
  }

  void OnContext(const WorkerMsg& m) {
    auto waiting = parked.find(m.context_hash);
    if (waiting == parked.end()) return;
    auto leases_waiting = std::move(waiting->second);
    parked.erase(waiting);
    WireCode code = WireCode::kOk;
    std::string error;
    auto c = std::make_shared<Context>();
    if (m.code != WireCode::kOk) {
      code = WireCode::kUnavailable;
      error = "context " + m.context_hash + " not available";
    } else if (service::ContentHash(m.context_spec) != m.context_hash) {
      code = WireCode::kUnavailable;
      error = "context does not match its hash";
    } else {
      std::vector<job::FieldViolation> violations;
      pz::Status s = service::DecodeJobSpec(m.context_spec, &c->spec, &violations);
      for (auto& v : kinds.Validate(c->spec)) violations.push_back(v);
      if (s.ok() && violations.empty()) s = kinds.MakeFitness(c->spec, &c->fitness);
      if (!s.ok() || !violations.empty()) {
        code = WireCode::kInvalidArgument;
        error = !s.ok() ? s.message() : violations.front().description;
      }
    }
    if (code != WireCode::kOk) {
      spdlog::error("job context {}: {}", m.context_hash, error);
      for (auto& l : leases_waiting) Reply(*l, code, error);
      return;
    }
    ++stats.contexts_fetched;
    contexts.emplace_front(m.context_hash, c);
    while (static_cast<int>(contexts.size()) > std::max(1, options.max_contexts))
      contexts.pop_back();
    for (auto& l : leases_waiting) Enqueue(std::move(l), c);
  }

  /// A compute thread's report: nobody works on `d.lease` any more (reply with its results unless
  /// it was abandoned, and free it), or (nullptr) the thread has stopped.
  void OnDone(const Done& d) {
    if (!d.lease) {
      ++stopped_threads;
      return;
    }
    auto it = leases.find(d.lease);
    if (it == leases.end()) return;
    LocalLease& l = *it->second;
    int done = 0;
    {
      std::lock_guard lock(handout.mu);
      if (l.queued || l.in_progress > 0) return;  // cannot happen: the last one out reports
      done = l.done;
    }
    stats.tasks += static_cast<uint64_t>(done);
    if (!l.abandoned && done == static_cast<int>(l.batch.genomes.size()))
      Reply(l, WireCode::kOk, {});
    leases.erase(it);
  }

  bool RecvInproc() {
    zmq::message_t id, body;
    if (!inproc.recv(id, zmq::recv_flags::dontwait)) return false;
    if (!inproc.recv(body) || body.size() != sizeof(Done)) return true;
    Done d;
    std::memcpy(&d, body.data(), sizeof d);
    OnDone(d);
    return true;
  }

  void PollInproc(std::chrono::milliseconds timeout) {
    zmq::pollitem_t items[] = {{inproc.handle(), 0, ZMQ_POLLIN, 0}};
    zmq::poll(items, 1, std::max(std::chrono::milliseconds(0), timeout));
    while (RecvInproc()) {
    }
  }

  WorkerStats Run(const std::atomic<bool>& stop) {
    inproc_endpoint = "inproc://pz-worker-" + std::to_string(reinterpret_cast<uintptr_t>(this));
    inproc.set(zmq::sockopt::linger, 0);
    inproc.bind(inproc_endpoint);
    for (int i = 0; i < options.threads; ++i)
      threads.emplace_back([this, i] { ComputeLoop(ctx, inproc_endpoint, i, handout); });
    Connect();
    while (!stop.load()) {
      const TimePoint now = Clock::now();
      const auto wait =
          std::chrono::duration_cast<std::chrono::milliseconds>(server.next_heartbeat() - now);
      zmq::pollitem_t items[] = {{master->handle(), 0, ZMQ_POLLIN, 0},
                                 {inproc.handle(), 0, ZMQ_POLLIN, 0},
                                 {monitor->handle(), 0, ZMQ_POLLIN, 0}};
      try {
        zmq::poll(items, monitor->handle() ? 3 : 2,
                  std::clamp(wait, std::chrono::milliseconds(0), std::chrono::milliseconds(100)) +
                      std::chrono::milliseconds(1));
      } catch (const zmq::error_t& e) {
        if (e.num() != EINTR) throw;
      }
      if (auto why = monitor->Poll()) {  // logged when it changes (ZeroMQ retries on its own)
        ++stats.handshake_failures;
        if (*why != last_handshake_error) spdlog::error("{}", *why);
        last_handshake_error = *why;
      }
      for (int n = 0; n < 1000; ++n) {
        zmq::message_t msg;
        if (!master->recv(msg, zmq::recv_flags::dontwait)) break;
        OnMaster({static_cast<const char*>(msg.data()), msg.size()}, stop);
        if (!master) break;
      }
      if (!stats.refused.empty()) break;
      while (RecvInproc()) {
      }
      const TimePoint after = Clock::now();
      if (server.Expired(after)) {
        Reconnect(stop, "no heartbeat");
        continue;
      }
      if (server.HeartbeatDue(after)) {
        WorkerMsg hb;
        hb.type = WorkerMsg::Type::kHeartbeat;
        Send(hb);
      }
    }
    if (master) {
      WorkerMsg bye;
      bye.type = WorkerMsg::Type::kDisconnect;
      bye.reason = "worker stopping";
      Send(bye);
    }
    AbandonAll();
    // Let the compute threads finish the task each one is running (bounded), then stop them.
    {
      std::lock_guard lock(handout.mu);
      handout.stop = true;
    }
    handout.cv.notify_all();
    const TimePoint give_up =
        Clock::now() + std::chrono::milliseconds(std::max(0, options.stop_grace_ms));
    while (stopped_threads < options.threads && Clock::now() < give_up)
      PollInproc(std::chrono::milliseconds(50));
    const int stopped = stopped_threads;
    for (auto& t : threads) {
      if (stopped >= options.threads)
        t.join();
      else
        t.detach();
    }
    if (stopped < options.threads) {  // a computation would not end: see WorkerStats::stuck_threads
      stats.stuck_threads = options.threads - stopped;
      spdlog::warn("{} compute thread(s) still inside an evaluation after {} ms",
                   stats.stuck_threads, options.stop_grace_ms);
      return stats;
    }
    threads.clear();
    master.reset();
    monitor.reset();
    return stats;
  }
};

Worker::Worker(WorkerOptions options, const job::JobKindRegistry& kinds)
    : impl_(std::make_unique<Impl>(std::move(options), kinds)) {
  impl_->options.threads = std::clamp(impl_->options.threads, 1, 4096);
}

Worker::~Worker() {
  // Threads still computing use the Impl (its ZeroMQ context, the fitness of their job): it must
  // outlive them, and a ZeroMQ context with their sockets open would block its destruction.
  if (impl_ && impl_->stats.stuck_threads > 0) (void)impl_.release();
}

WorkerStats Worker::Run(const std::atomic<bool>& stop) { return impl_->Run(stop); }

}  // namespace pz::worker
