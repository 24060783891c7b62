#include "master/broker.h"

#include <pthread.h>

#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cstring>
#include <deque>
#include <map>
#include <random>
#include <set>
#include <zmq.hpp>

#include "master/log_throttle.h"
#include "model/arithmetic.h"
#include "service/liveness.h"
#include "service/wire_codec.h"

namespace pz::master {

using job::JobLimits;
using opt::EvalBatch;
using opt::FitnessResult;
using opt::FitnessStatus;
using opt::Genome;
using service::BatchResultMsg;
using service::ClientReplyMsg;
using service::ClientRequestMsg;
using service::Clock;
using service::ContentHash;
using service::DecodeClientRequest;
using service::DecodeFailureCode;
using service::DecodeWorkerToMaster;
using service::EncodeClientReply;
using service::EncodeMasterToWorker;
using service::IsFinal;
using service::IsTransient;
using service::JobEvent;
using service::kZapDomainClients;
using service::kZapDomainWorkers;
using service::PeerLiveness;
using service::TimePoint;
using service::WireCode;
using service::WorkerMsg;
using service::ZapHandler;
namespace {

struct Command {
  enum class Type { kRegister, kUnregister, kSubmit, kPublish };
  Type type = Type::kPublish;
  std::string job_id, spec_bytes;
  JobLimits limits;
  std::shared_ptr<EvalTicket> ticket;
  uint64_t generation = 0;
  service::PackedTasks tasks;  ///< packed by the submitting thread
  std::vector<int> indices;
  JobEvent event;
};

void Finish(const std::shared_ptr<EvalTicket>& t, bool interrupted, std::string error = {}) {
  {
    std::lock_guard lock(t->mu);
    t->finished = true;
    t->interrupted = interrupted;
    t->error = std::move(error);
  }
  t->cv.notify_all();
}

std::string Hex(const std::string& id) {
  static const char* d = "0123456789abcdef";
  std::string s;
  for (unsigned char c : id) {
    s += d[c >> 4];
    s += d[c & 15];
  }
  return s;
}

/// A message's metadata property, or "" (zmq_msg_gets fails when the transport has none).
std::string Property(const zmq::message_t& m, const char* name) {
  const char* v = zmq_msg_gets(m.handle(), name);
  return v ? v : "";
}

}  // namespace

/// The dispatcher's quiet window is at least two liveness timeouts: deaths are seen up to one
/// timeout late, so two kills a moment apart may be noticed that far apart.
DispatchOptions WithQuietWindow(const BrokerOptions& o) {
  DispatchOptions d = o.dispatch;
  d.quiet_window_s = std::max(d.quiet_window_s, 2.0 * o.heartbeat_ms * o.liveness / 1000.0);
  return d;
}

struct Broker::Impl {
  explicit Impl(BrokerOptions o)
      : options(std::move(o)),
        workers(ctx, zmq::socket_type::router),
        clients(ctx, zmq::socket_type::router),
        liveness(std::chrono::milliseconds(options.heartbeat_ms), options.liveness),
        dispatcher(WithQuietWindow(options),
                   std::random_device{}() | (uint64_t{std::random_device{}()} << 32)) {
    if (!options.allow_mixed_arithmetic && !options.pinned_arithmetic.empty())
      Serve(options.pinned_arithmetic);
  }

  void Serve(const std::string& profile) {
    arithmetic = profile;
    std::lock_guard lock(served_mu);
    served = profile;
  }

  // ---- shared with other threads
  BrokerOptions options;
  std::mutex mu;
  std::deque<Command> inbox;
  int wake_fd = -1;
  std::atomic<bool> stop{false};
  bool stopped = false;  // under mu: the loop has ended
  mutable std::mutex stats_mu;
  BrokerStats stats;

  // ---- broker thread only
  zmq::context_t ctx{1};
  zmq::socket_t workers, clients;
  std::unique_ptr<ZapHandler> zap;  // destroyed before ctx
  ClientHandler* handler = nullptr;
  std::thread thread;
  PeerLiveness liveness;
  Dispatcher dispatcher;
  struct Job {
    std::string spec_bytes, context_hash;
    JobLimits limits;
    std::shared_ptr<EvalTicket> ticket;  // the generation being evaluated, if any
    uint64_t generation = 0;
    service::PackedTasks tasks;  // the generation's tasks as wire bytes (leases copy from them)
    std::vector<int> indices;
  };
  std::map<std::string, Job> jobs;
  std::map<std::string, std::string> contexts;  // hash → job id
  /// A client watching a job: where to push its events, and the request_id of its Watch, which
  /// every pushed event echoes.
  struct Watcher {
    std::vector<std::string> envelope;
    uint64_t request_id = 0;
    uint64_t registered = 0;  ///< registration order (the oldest makes room at the maximum)
  };
  uint64_t next_watcher = 0;
  /// Watchers by job, kept apart from `jobs` (a job's registration by its thread comes after the
  /// Submit reply, and ends before its final event): a Watch sent right after Submit, or a cancel,
  /// loses nothing. A job's watchers are dropped with its final event.
  std::map<std::string, std::map<std::string, Watcher>> watchers;  // job → envelope key → watcher
  std::map<std::string, std::set<std::string>> jobs_of_client;     // client identity → job ids
  BrokerStats local;
  LogThrottle log_throttle{std::chrono::seconds(10)};
  /// What the workers announced, for the Workers request (dashboards); departures kept: the
  /// last 32.
  struct WorkerMeta {
    std::string host, key;
    int64_t pid = 0;
    double connected_unix_s = 0;
    uint64_t tasks_done = 0;
    std::string arithmetic;
  };
  std::optional<std::string>
      arithmetic;  // the profile served (the first worker's), unless mixing is allowed
  mutable std::mutex served_mu;  // the served profile for other threads
  std::string served;
  std::map<std::string, WorkerMeta> worker_meta;
  std::deque<service::WorkerDepartureView> departed;
  const TimePoint started = Clock::now();

  static double UnixNow() {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
        .count();
  }
  void Departed(const std::string& id, const std::string& why) {
    auto it = worker_meta.find(id);
    service::WorkerDepartureView d;
    d.id = Hex(id);
    d.reason = why;
    d.at_unix_s = UnixNow();
    if (it != worker_meta.end()) {
      d.host = it->second.host;
      d.pid = it->second.pid;
      d.tasks_done = it->second.tasks_done;
      worker_meta.erase(it);
    }
    Remember(std::move(d));
  }
  void Remember(service::WorkerDepartureView d) {
    departed.push_back(std::move(d));
    while (departed.size() > 32) departed.pop_front();
  }
  service::WorkersSnapshot Workers() const {
    service::WorkersSnapshot w;
    for (const Dispatcher::WorkerLoad& l : dispatcher.Workers()) {
      service::WorkerView v;
      v.id = Hex(l.id);
      v.threads = l.threads;
      v.item_seconds = l.item_s;
      v.leases = l.leases;
      v.tasks_in_flight = l.items;
      v.solo = l.solo;
      if (auto it = worker_meta.find(l.id); it != worker_meta.end()) {
        v.host = it->second.host;
        v.key = it->second.key;
        v.pid = it->second.pid;
        v.connected_unix_s = it->second.connected_unix_s;
        v.tasks_done = it->second.tasks_done;
        v.arithmetic = it->second.arithmetic;
      }
      w.workers.push_back(std::move(v));
    }
    w.departed.assign(departed.begin(), departed.end());
    w.leases_sent = local.leases_sent;
    w.tasks_done = local.tasks_done;
    w.results_ignored = local.results_ignored;
    w.bad_frames = local.bad_frames;
    w.speculative_leases = local.speculative_leases;
    w.speculative_wins = local.speculative_wins;
    w.uptime_s = std::chrono::duration<double>(Clock::now() - started).count();
    return w;
  }

  void Wake() {
    uint64_t one = 1;
    (void)!::write(wake_fd, &one, sizeof one);
  }

  void Post(Command c) {
    {
      std::lock_guard lock(mu);
      if (stopped) {
        if (c.ticket) Finish(c.ticket, true);
        return;
      }
      inbox.push_back(std::move(c));
    }
    Wake();
  }

  void SendToWorker(const std::string& id, const WorkerMsg& m) {
    const std::string payload = EncodeMasterToWorker(m);
    workers.send(zmq::buffer(id), zmq::send_flags::sndmore | zmq::send_flags::dontwait);
    workers.send(zmq::buffer(payload), zmq::send_flags::dontwait);
  }

  void SendToClient(const std::vector<std::string>& envelope, const ClientReplyMsg& m) {
    const std::string payload = EncodeClientReply(m);
    for (const auto& f : envelope)
      clients.send(zmq::buffer(f), zmq::send_flags::sndmore | zmq::send_flags::dontwait);
    clients.send(zmq::buffer(payload), zmq::send_flags::dontwait);
  }

  void BadFrame(const char* where, const std::string& why) {
    ++local.bad_frames;
    uint64_t suppressed = 0;  // a flood is one line every 10 s per endpoint, with its count
    if (log_throttle.Allow(where, Clock::now(), &suppressed))
      spdlog::warn(
          "broker: bad {} frame ({}), ignored{}", where, why,
          suppressed ? " (" + std::to_string(suppressed) + " more since the last line)" : "");
  }

  // ------------------------------------------------------------------ commands from job threads
  void Drain() {
    std::deque<Command> cmds;
    {
      std::lock_guard lock(mu);
      cmds.swap(inbox);
    }
    for (Command& c : cmds) {
      switch (c.type) {
        case Command::Type::kRegister: {
          Job& j = jobs[c.job_id];
          j.spec_bytes = std::move(c.spec_bytes);
          j.context_hash = ContentHash(j.spec_bytes);
          j.limits = c.limits;
          contexts[j.context_hash] = c.job_id;
          break;
        }
        case Command::Type::kUnregister: {
          auto it = jobs.find(c.job_id);
          if (it == jobs.end()) break;
          if (it->second.ticket) Finish(it->second.ticket, true);
          contexts.erase(it->second.context_hash);
          dispatcher.RemoveJob(c.job_id);
          jobs.erase(it);
          break;
        }
        case Command::Type::kSubmit: {
          auto it = jobs.find(c.job_id);
          if (it == jobs.end()) {
            Finish(c.ticket, true);
            break;
          }
          Job& j = it->second;
          if (j.ticket) Finish(j.ticket, true);
          j.ticket = c.ticket;
          j.generation = c.generation;
          j.tasks = std::move(c.tasks);
          j.indices = std::move(c.indices);
          j.ticket->results.assign(j.indices.size(), FitnessResult{});
          dispatcher.StartGeneration(c.job_id, c.generation, static_cast<int>(j.indices.size()),
                                     j.limits.task_timeout_s, j.limits.quarantine_after);
          if (j.indices.empty()) CompleteGeneration(c.job_id, j);
          break;
        }
        case Command::Type::kPublish:
          PublishEvent(c.event);
          break;
      }
    }
  }

  void PublishEvent(const JobEvent& e) {
    auto it = watchers.find(e.job_id);
    if (it == watchers.end()) return;
    ClientReplyMsg m;
    m.type = ClientReplyMsg::Type::kEvent;
    m.code = WireCode::kOk;
    m.event = e;
    m.event.workers = dispatcher.worker_count();
    m.event.worker_threads = dispatcher.total_threads();
    for (const auto& [key, w] : it->second) {
      m.request_id = w.request_id;
      SendToClient(w.envelope, m);
    }
    if (IsFinal(e.state)) watchers.erase(it);
  }

  void CompleteGeneration(const std::string& job_id, Job& j) {
    if (!j.ticket) return;
    Finish(j.ticket, false);
    j.ticket.reset();
    j.tasks = {};
    j.indices.clear();
  }

  void Quarantine(const std::vector<Quarantined>& qs) {
    for (const Quarantined& q : qs) {
      auto it = jobs.find(q.job_id);
      if (it == jobs.end() || !it->second.ticket || it->second.generation != q.generation) continue;
      Job& j = it->second;
      const int index = j.indices[q.position];
      {
        std::lock_guard lock(j.ticket->mu);
        j.ticket->results[q.position] = {j.limits.penalty_cost, FitnessStatus::kError,
                                         "quarantined"};
        j.ticket->quarantined.push_back({q.generation, index, static_cast<uint32_t>(q.strikes)});
      }
      spdlog::warn(
          "job {}: individual {} of generation {} quarantined: it killed or hung {} workers that "
          "ran it alone while the rest of the cluster was healthy",
          q.job_id, index, q.generation, q.strikes);
      if (dispatcher.remaining(q.job_id) == 0) CompleteGeneration(q.job_id, j);
    }
  }

  // ------------------------------------------------------------------ workers
  void RemoveWorker(const std::string& id, bool lost, const char* why) {
    if (!dispatcher.HasWorker(id)) return;
    spdlog::info("worker {} removed ({})", Hex(id), why);
    Departed(id, why);
    liveness.Remove(id);
    dispatcher.RemoveWorker(id, lost, Clock::now());
  }

  // A worker whose arithmetic differs from the one served: told why, never added, kept among the
  // departures (the dashboard shows it).
  void RefuseWorker(const std::string& id, const WorkerMsg& m) {
    const std::string theirs = m.arithmetic.empty() ? "(not announced)" : m.arithmetic;
    const std::string pinned = options.pinned_by.empty() ? "" : " (" + options.pinned_by + ")";
    // Named by what differs (model::ArithmeticDifference: the measured parts, "here" the served
    // profile's, "there" this worker's), then both profiles whole.
    const std::string why =
        "worker on host " + m.host + " pid " + std::to_string(m.pid) +
        " computes differently from this master's workers in " +
        model::ArithmeticDifference(*arithmetic, theirs) + "; served '" + *arithmetic + "'" +
        pinned + ", this one '" + theirs +
        "': results would differ in their last bits (start the master with "
        "--allow-mixed-arithmetic to accept both)";
    uint64_t suppressed = 0;
    if (log_throttle.Allow("refused " + m.host, Clock::now(), &suppressed))
      spdlog::warn("worker {} (host {} pid {}) refused: {}{}", Hex(id), m.host, m.pid, why,
                   suppressed ? " (" + std::to_string(suppressed) + " more refusals)" : "");
    WorkerMsg answer;
    answer.type = WorkerMsg::Type::kDisconnect;
    answer.code = WireCode::kInvalidArgument;
    answer.reason = why;
    SendToWorker(id, answer);
    service::WorkerDepartureView d;
    d.id = Hex(id);
    d.host = m.host;
    d.pid = m.pid;
    d.reason = "refused: another arithmetic (" + theirs + "): differs in " +
               model::ArithmeticDifference(*arithmetic, theirs);
    d.at_unix_s = UnixNow();
    Remember(std::move(d));
  }

  void OnWorkerFrame(const std::string& id, std::string_view payload, TimePoint now,
                     const std::string& user = {}) {
    WorkerMsg m;
    Status s = DecodeWorkerToMaster(payload, &m);
    if (!s.ok()) {
      BadFrame("worker", s.message());
      WorkerMsg answer;
      answer.type = WorkerMsg::Type::kDisconnect;
      answer.code = DecodeFailureCode(s);
      answer.reason = s.message();
      SendToWorker(id, answer);
      return;
    }
    const bool known = dispatcher.HasWorker(id);
    if (known) liveness.Seen(id, now);
    switch (m.type) {
      case WorkerMsg::Type::kReady:
        if (known) RemoveWorker(id, false, "re-announced");
        if (!options.allow_mixed_arithmetic) {
          if (arithmetic && m.arithmetic != *arithmetic) {
            RefuseWorker(id, m);
            return;
          }
          if (!arithmetic) {
            Serve(m.arithmetic);
            spdlog::info("serving workers of arithmetic profile '{}'", *arithmetic);
          }
        }
        dispatcher.AddWorker(id, m.threads);
        worker_meta[id] = {m.host, user, m.pid, UnixNow(), 0, m.arithmetic};
        liveness.Seen(id, now);
        spdlog::info("worker {} ready: {} threads, host {} pid {}{}", Hex(id), m.threads, m.host,
                     m.pid, user.empty() ? "" : ", key " + user);
        return;
      case WorkerMsg::Type::kDisconnect:
        RemoveWorker(id, false, "disconnected");
        return;
      default:
        break;
    }
    if (!known) {  // e.g. after a master restart: ask it to announce itself
      WorkerMsg answer;
      answer.type = WorkerMsg::Type::kDisconnect;
      answer.code = WireCode::kFailedPrecondition;
      answer.reason = "unknown worker: reconnect and send READY";
      SendToWorker(id, answer);
      return;
    }
    if (m.type == WorkerMsg::Type::kContextRequest) {
      WorkerMsg answer;
      answer.type = WorkerMsg::Type::kContext;
      answer.context_hash = m.context_hash;
      auto c = contexts.find(m.context_hash);
      if (c != contexts.end() && jobs.count(c->second)) {
        answer.context_spec = jobs[c->second].spec_bytes;
        answer.code = WireCode::kOk;
      } else {
        answer.code = WireCode::kNotFound;
      }
      SendToWorker(id, answer);
    } else if (m.type == WorkerMsg::Type::kResult) {
      OnResult(id, m.result);
    }
  }

  void OnResult(const std::string& id, const BatchResultMsg& r) {
    auto lease = dispatcher.Complete(id, r.lease_id, r.eval_seconds);
    if (!lease) {
      ++local.results_ignored;
      return;
    }
    auto it = jobs.find(lease->job_id);
    if (it == jobs.end() || !it->second.ticket || it->second.generation != lease->generation) {
      ++local.results_ignored;
      return;
    }
    Job& j = it->second;
    if (r.code != WireCode::kOk) {
      if (IsTransient(r.code)) {
        Quarantine(dispatcher.Requeue(*lease, RequeueCause::kTransient, Clock::now()));
      } else {
        spdlog::error("job {}: worker reports a deterministic error: {}", lease->job_id, r.error);
        dispatcher.RemoveJob(lease->job_id);
        Finish(j.ticket, false, r.error.empty() ? "worker error" : r.error);
        j.ticket.reset();
      }
      return;
    }
    bool consistent = r.indices.size() == lease->positions.size() && r.job_id == lease->job_id &&
                      r.generation == lease->generation;
    for (size_t i = 0; consistent && i < r.indices.size(); ++i)
      consistent = r.indices[i] == j.indices[lease->positions[i]];
    if (!consistent) {
      BadFrame("result", "does not match its lease");
      Quarantine(dispatcher.Requeue(*lease, RequeueCause::kTransient, Clock::now()));
      return;
    }
    ++local.results_accepted;
    local.eval_seconds += r.eval_seconds;
    {
      std::lock_guard lock(j.ticket->mu);
      bool counted = false;
      for (size_t i = 0; i < r.indices.size(); ++i) {
        const int pos = lease->positions[i];
        if (dispatcher.MarkDone(lease->job_id, lease->generation, pos)) {
          if (lease->speculative && !counted) ++local.speculative_wins;
          counted = true;
          j.ticket->results[pos] = r.results[i];
          ++local.tasks_done;
          if (auto m = worker_meta.find(id); m != worker_meta.end()) ++m->second.tasks_done;
        }
      }
    }
    if (dispatcher.remaining(lease->job_id) == 0) CompleteGeneration(lease->job_id, j);
  }

  void Dispatch(TimePoint now) {
    while (auto lease = dispatcher.NextLease(now)) {
      const Job& j = jobs.at(lease->job_id);
      service::TaskBatchMsg head;
      head.lease_id = lease->id;
      head.job_id = lease->job_id;
      head.generation = lease->generation;
      head.context_hash = j.context_hash;
      head.deadline_s = std::chrono::duration<double>(lease->deadline - now).count();
      // Written straight into the frame from the generation's packed tasks: no genome is copied.
      const size_t task_bytes = j.tasks.Bytes(lease->positions);
      const std::string prefix = service::PackedBatchHead(head, task_bytes);
      zmq::message_t payload(prefix.size() + task_bytes);
      char* out = static_cast<char*>(payload.data());
      std::memcpy(out, prefix.data(), prefix.size());
      j.tasks.Write(lease->positions, out + prefix.size());
      workers.send(zmq::buffer(lease->worker),
                   zmq::send_flags::sndmore | zmq::send_flags::dontwait);
      workers.send(payload, zmq::send_flags::dontwait);
      ++local.leases_sent;
      if (lease->speculative) {
        ++local.speculative_leases;
        spdlog::debug("job {}: a copy of a straggling lease to worker {}", lease->job_id,
                      Hex(lease->worker));
      }
    }
  }

  // ------------------------------------------------------------------ clients
  /// Who submitted: the CURVE key's name given by the ZAP handler, else the peer's IP address.
  static std::string ClientIdentity(const zmq::message_t& m) {
    std::string user = Property(m, "User-Id");
    if (!user.empty()) return user;
    const std::string addr = Property(m, "Peer-Address");
    return addr.empty() ? "local" : "address:" + addr;
  }

  /// Running jobs submitted by `client` (forgets its jobs that have ended).
  int RunningJobsOf(const std::string& client) {
    auto it = jobs_of_client.find(client);
    if (it == jobs_of_client.end()) return 0;
    int running = 0;
    for (auto j = it->second.begin(); j != it->second.end();) {
      ClientRequestMsg q;
      q.type = ClientRequestMsg::Type::kStatus;
      q.job_id = *j;
      const ClientReplyMsg r = handler->Handle(q);
      if (r.code == WireCode::kOk && !IsFinal(r.info.state)) {
        ++running;
        ++j;
      } else {
        j = it->second.erase(j);
      }
    }
    if (it->second.empty()) jobs_of_client.erase(it);
    return running;
  }

  /// The submission limits; false with *reply filled when the request is refused.
  bool AdmitSubmission(const ClientRequestMsg& req, const std::string& client,
                       ClientReplyMsg* reply) {
    const auto bytes = static_cast<int64_t>(req.spec_bytes.size());
    if (bytes > options.max_spec_bytes) {
      reply->code = WireCode::kInvalidArgument;
      reply->error =
          "spec: " + std::to_string(bytes) +
          " bytes serialised, above the master's maximum data size per job (--max-spec-bytes = " +
          std::to_string(options.max_spec_bytes) + ")";
      reply->violations.push_back({"spec", reply->error});
      return false;
    }
    // A retry of a submission that was accepted is answered as such, whatever the limit.
    ClientRequestMsg q;
    q.type = ClientRequestMsg::Type::kStatus;
    q.job_id = service::JobIdOf(req.spec_bytes, req.client_token);
    if (handler->Handle(q).code == WireCode::kOk) return true;
    const int running = RunningJobsOf(client);
    if (running >= options.max_jobs_per_client) {
      reply->code = WireCode::kResourceExhausted;
      reply->error = "client " + client + " already has " + std::to_string(running) +
                     " running jobs: the maximum jobs per client is " +
                     std::to_string(options.max_jobs_per_client) +
                     " (--max-jobs-per-client); retry when one has ended";
      return false;
    }
    return true;
  }

  void OnClientFrames(std::vector<zmq::message_t>& frames) {
    std::vector<std::string> envelope;
    for (size_t i = 0; i + 1 < frames.size(); ++i) envelope.push_back(frames[i].to_string());
    const auto& last = frames.back();
    ClientRequestMsg req;
    Status s = DecodeClientRequest({static_cast<const char*>(last.data()), last.size()}, &req);
    ClientReplyMsg reply;
    reply.request_id = req.request_id;
    if (!s.ok()) {
      BadFrame("client", s.message());
      reply.code = DecodeFailureCode(s);
      reply.error = s.message();
      SendToClient(envelope, reply);
      return;
    }
    if (req.type == ClientRequestMsg::Type::kPing) {
      reply.code = WireCode::kOk;
    } else if (req.type == ClientRequestMsg::Type::kWorkers) {
      reply.code = WireCode::kOk;
      reply.type = ClientReplyMsg::Type::kWorkers;
      reply.workers_snapshot = Workers();
    } else if (req.type == ClientRequestMsg::Type::kWatch) {
      ClientRequestMsg status = req;
      status.type = ClientRequestMsg::Type::kStatus;
      reply = handler->Handle(status);
      reply.request_id = req.request_id;
      // Recorded whenever the store has the job and it has not ended, registered with the
      // broker yet or not. Its final event cannot be missed: the job thread saves the final state
      // (what this status reads) before it publishes the final event, which the broker thread
      // handles after this request.
      if (reply.code == WireCode::kOk && !IsFinal(reply.info.state)) {
        auto& of_job = watchers[req.job_id];
        std::string key;
        for (const auto& f : envelope) key += f + '\0';
        // At the maximum, the watcher registered longest ago makes room: a watcher that stopped
        // reading (or went) cannot shut out a new one, and a live one re-registers after a quiet
        // spell of its watch (svcclient/service_client.h).
        if (!of_job.count(key) && static_cast<int>(of_job.size()) >= options.max_watchers_per_job) {
          auto oldest =
              std::min_element(of_job.begin(), of_job.end(), [](const auto& a, const auto& b) {
                return a.second.registered < b.second.registered;
              });
          spdlog::debug("job {}: {} watchers, the maximum; the oldest is dropped", req.job_id,
                        of_job.size());
          of_job.erase(oldest);
          ++local.dropped_watchers;
        }
        of_job[key] = Watcher{envelope, req.request_id, next_watcher++};
      }
    } else if (req.type == ClientRequestMsg::Type::kSubmit &&
               !AdmitSubmission(req, ClientIdentity(last), &reply)) {
      ++local.refused_submissions;
      spdlog::warn("submission refused: {}", reply.error);
    } else {
      reply = handler->Handle(req);
      reply.request_id = req.request_id;
      if (req.type == ClientRequestMsg::Type::kSubmit && reply.code == WireCode::kOk &&
          !reply.existed)
        jobs_of_client[ClientIdentity(last)].insert(reply.job_id);
      if (req.type == ClientRequestMsg::Type::kList ||
          req.type == ClientRequestMsg::Type::kEvaluate) {
        reply.workers = dispatcher.worker_count();
        reply.worker_threads = dispatcher.total_threads();
      }
    }
    SendToClient(envelope, reply);
  }

  // ------------------------------------------------------------------ the loop
  bool RecvFrames(zmq::socket_t& sock, std::vector<zmq::message_t>& frames) {
    frames.clear();
    for (int i = 0; i < 64; ++i) {
      zmq::message_t msg;
      if (!sock.recv(msg, zmq::recv_flags::dontwait)) return !frames.empty();
      const bool more = msg.more();
      frames.push_back(std::move(msg));
      if (!more) return true;
    }
    // Too many frames: drain the rest of the message.
    for (int guard = 0; guard < 1000000; ++guard) {
      zmq::message_t msg;
      if (!sock.recv(msg, zmq::recv_flags::dontwait) || !msg.more()) break;
    }
    frames.clear();
    BadFrame("multipart", "more than 64 frames");
    return false;
  }

  void Run() {
    std::vector<zmq::message_t> frames;
    while (!stop.load()) {
      const TimePoint before = Clock::now();
      TimePoint next =
          std::min({liveness.next_heartbeat(), liveness.NextExpiry(), dispatcher.NextDeadline(),
                    before + std::chrono::milliseconds(200)});
      const long timeout_ms = std::max<long>(
          0, std::chrono::duration_cast<std::chrono::milliseconds>(next - before).count() + 1);
      zmq::pollitem_t items[] = {{workers.handle(), 0, ZMQ_POLLIN, 0},
                                 {clients.handle(), 0, ZMQ_POLLIN, 0},
                                 {nullptr, wake_fd, ZMQ_POLLIN, 0}};
      try {
        zmq::poll(items, 3, std::chrono::milliseconds(timeout_ms));
      } catch (const zmq::error_t& e) {
        if (e.num() == EINTR) continue;
        throw;
      }
      if (items[2].revents & ZMQ_POLLIN) {
        uint64_t v;
        (void)!::read(wake_fd, &v, sizeof v);
      }
      Drain();
      TimePoint now = Clock::now();
      for (int n = 0; n < 10000 && RecvFrames(workers, frames); ++n) {
        if (frames.size() != 2 || frames[0].size() == 0) {
          BadFrame("worker", std::to_string(frames.size()) + " frames");
          continue;
        }
        OnWorkerFrame(frames[0].to_string(),
                      {static_cast<const char*>(frames[1].data()), frames[1].size()}, now,
                      options.curve ? Property(frames[1], "User-Id") : std::string());
      }
      for (int n = 0; n < 1000 && RecvFrames(clients, frames); ++n) {
        if (frames.size() < 2) {
          BadFrame("client", "no envelope");
          continue;
        }
        OnClientFrames(frames);
      }
      now = Clock::now();
      for (const std::string& id : liveness.TakeExpired(now)) {
        spdlog::warn("worker {} missed its heartbeats", Hex(id));
        Departed(id, "lost (missed its heartbeats)");
        dispatcher.RemoveWorker(id, /*lost=*/true, now);
      }
      Quarantine(dispatcher.ExpireLeases(now));
      Quarantine(dispatcher.ConfirmStrikes(now));
      if (liveness.HeartbeatDue(now)) {
        WorkerMsg hb;
        hb.type = WorkerMsg::Type::kHeartbeat;
        for (const auto& id : liveness.ids()) SendToWorker(id, hb);
      }
      Dispatch(now);
      std::lock_guard lock(stats_mu);
      stats = local;
      stats.workers = dispatcher.worker_count();
      stats.worker_threads = dispatcher.total_threads();
    }
    for (auto& [id, j] : jobs)
      if (j.ticket) Finish(j.ticket, true);
    std::lock_guard lock(mu);
    stopped = true;
    for (auto& c : inbox)
      if (c.ticket) Finish(c.ticket, true);
    inbox.clear();
  }
};

Broker::Broker(BrokerOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}

Broker::~Broker() { Stop(); }

std::string Broker::served_arithmetic() const {
  std::lock_guard lock(impl_->served_mu);
  return impl_->served;
}

Status Broker::Start(ClientHandler* handler) {
  Impl& m = *impl_;
  m.handler = handler;
  if (m.options.curve) {
    m.zap = std::make_unique<ZapHandler>(m.ctx, *m.options.curve);
    if (Status s = m.zap->Start(); !s.ok()) return s;
  }
  try {
    for (zmq::socket_t* s : {&m.workers, &m.clients}) {
      s->set(zmq::sockopt::linger, 0);
      s->set(zmq::sockopt::maxmsgsize, m.options.max_message_bytes);
      s->set(zmq::sockopt::sndhwm, s == &m.clients ? m.options.client_queue : 100000);
      s->set(zmq::sockopt::rcvhwm, 100000);
      if (m.options.curve) {
        s->set(zmq::sockopt::curve_server, true);
        s->set(zmq::sockopt::curve_secretkey, m.options.curve->keys.secret_z85);
        s->set(zmq::sockopt::zap_domain, s == &m.workers ? kZapDomainWorkers : kZapDomainClients);
      }
    }
    m.workers.bind(m.options.worker_endpoint);
    m.clients.bind(m.options.client_endpoint);
    worker_endpoint_ = m.workers.get(zmq::sockopt::last_endpoint);
    client_endpoint_ = m.clients.get(zmq::sockopt::last_endpoint);
  } catch (const zmq::error_t& e) {
    return {StatusCode::kUnavailable, std::string("cannot bind: ") + e.what()};
  }
  m.wake_fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (m.wake_fd < 0) return Internal("eventfd failed");
  m.thread = std::thread([&m] {
    ::pthread_setname_np(::pthread_self(), "pz-broker");  // `top -H`, and bench_broker's CPU count
    m.Run();
  });
  return Status::Ok();
}

void Broker::Stop() {
  Impl& m = *impl_;
  if (!m.thread.joinable()) return;
  m.stop = true;
  m.Wake();
  m.thread.join();
  m.workers.close();
  m.clients.close();
  if (m.zap) m.zap->Stop();
  ::close(m.wake_fd);
}

void Broker::RegisterJob(const std::string& job_id, const std::string& spec_bytes,
                         const JobLimits& limits) {
  Command c;
  c.type = Command::Type::kRegister;
  c.job_id = job_id;
  c.spec_bytes = spec_bytes;
  c.limits = limits;
  impl_->Post(std::move(c));
}

void Broker::UnregisterJob(const std::string& job_id) {
  Command c;
  c.type = Command::Type::kUnregister;
  c.job_id = job_id;
  impl_->Post(std::move(c));
}

std::shared_ptr<EvalTicket> Broker::Submit(const std::string& job_id, uint64_t generation,
                                           std::span<const Genome> genomes,
                                           std::span<const int> indices) {
  Command c;
  c.type = Command::Type::kSubmit;
  c.job_id = job_id;
  c.generation = generation;
  c.tasks = service::PackedTasks(genomes, indices);  // on the job's thread, not the broker's
  c.indices.assign(indices.begin(), indices.end());
  c.ticket = std::make_shared<EvalTicket>();
  auto t = c.ticket;
  impl_->Post(std::move(c));
  return t;
}

void Broker::Publish(const JobEvent& event) {
  Command c;
  c.type = Command::Type::kPublish;
  c.job_id = event.job_id;
  c.event = event;
  impl_->Post(std::move(c));
}

BrokerStats Broker::stats() const {
  std::lock_guard lock(impl_->stats_mu);
  return impl_->stats;
}

void BrokerEvaluator::Evaluate(const EvalBatch& batch, std::span<FitnessResult> out) {
  interrupted_ = false;
  error_.clear();
  auto t = broker_.Submit(job_id_, batch.generation, batch.genomes, batch.indices);
  std::unique_lock lock(t->mu);
  t->cv.wait(lock, [&] { return t->finished; });
  interrupted_ = t->interrupted || !t->error.empty();
  error_ = t->error;
  if (interrupted_) {
    for (auto& r : out) r = {0, FitnessStatus::kError, "interrupted"};
    return;
  }
  for (size_t i = 0; i < out.size() && i < t->results.size(); ++i) out[i] = t->results[i];
  quarantined_.insert(quarantined_.end(), t->quarantined.begin(), t->quarantined.end());
}

int BrokerEvaluator::concurrency() const { return std::max(1, broker_.stats().worker_threads); }

}  // namespace pz::master
