#include "svcclient/service_client.h"

#include <optional>
#include <random>
#include <thread>
#include <zmq.hpp>

#include "service/wire_codec.h"

namespace pz::svcclient {

using service::ClientReplyMsg;
using service::ClientRequestMsg;
using service::WireCode;

Status StatusFromWire(WireCode code, const std::string& error) {
  switch (code) {
    case WireCode::kOk:
      return Status::Ok();
    case WireCode::kInvalidArgument:
      return {StatusCode::kInvalidArgument, error};
    case WireCode::kNotFound:
      return {StatusCode::kNotFound, error};
    case WireCode::kFailedPrecondition:
    case WireCode::kVersionMismatch:
      return {StatusCode::kFailedPrecondition, error};
    case WireCode::kMalformed:
      return {StatusCode::kDataLoss, error};
    case WireCode::kInternal:
      return {StatusCode::kInternal, error};
    default:
      return {StatusCode::kUnavailable, error.empty() ? "master unavailable" : error};
  }
}

struct ServiceClient::Impl {
  explicit Impl(ServiceClientOptions o) : options(std::move(o)), rng(std::random_device{}()) {
    options.retries = std::max(1, options.retries);
  }
  ServiceClientOptions options;
  zmq::context_t ctx{1};
  std::unique_ptr<zmq::socket_t> sock;
  std::unique_ptr<service::HandshakeMonitor> monitor;  // of sock
  std::string refused;                                 // the master refused the handshake: why
  std::mt19937_64 rng;
  uint64_t next_id = 1;

  void Open() {
    sock = std::make_unique<zmq::socket_t>(ctx, zmq::socket_type::dealer);
    sock->set(zmq::sockopt::linger, 0);
    if (options.curve) service::SetCurveClient(*sock, *options.curve, options.master_public);
    monitor = std::make_unique<service::HandshakeMonitor>(ctx, *sock, "client");
    sock->connect(options.endpoint);
  }

  /// Receives the next reply within `timeout`; false on timeout.
  bool Receive(ClientReplyMsg* reply, std::chrono::milliseconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    for (int guard = 0; guard < 100000; ++guard) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          until - std::chrono::steady_clock::now());
      if (left.count() < 0) return false;
      zmq::pollitem_t items[] = {{sock->handle(), 0, ZMQ_POLLIN, 0},
                                 {monitor->handle(), 0, ZMQ_POLLIN, 0}};
      zmq::poll(items, monitor->handle() ? 2 : 1, left);
      if (items[1].revents & ZMQ_POLLIN) {
        if (auto why = monitor->Poll()) {
          refused = *why;
          return false;
        }
      }
      if (!(items[0].revents & ZMQ_POLLIN)) {
        if (items[1].revents & ZMQ_POLLIN) continue;
        return false;
      }
      zmq::message_t msg;
      if (!sock->recv(msg, zmq::recv_flags::dontwait)) continue;
      if (service::DecodeClientReply({static_cast<const char*>(msg.data()), msg.size()}, reply)
              .ok())
        return true;
    }
    return false;
  }

  /// A request of `type` about one job (status, cancel, close).
  Status CallOnJob(ClientRequestMsg::Type type, const std::string& job_id, ClientReplyMsg* reply) {
    ClientRequestMsg req;
    req.type = type;
    req.job_id = job_id;
    return Call(req, reply);
  }

  Status Call(ClientRequestMsg& req, ClientReplyMsg* reply) {
    size_t sent_bytes = 0;
    std::string handshake;  // a handshake failure seen meanwhile
    refused.clear();
    for (int attempt = 0; attempt < options.retries; ++attempt) {
      if (!sock) Open();
      req.request_id = next_id++;
      const std::string payload = service::EncodeClientRequest(req);
      sent_bytes = payload.size();
      if (static_cast<int64_t>(payload.size()) > options.max_message_bytes)
        return InvalidArgument("request of " + std::to_string(payload.size()) +
                               " bytes: above the maximum message size (max_message_bytes = " +
                               std::to_string(options.max_message_bytes) + ")");
      sock->send(zmq::buffer(payload), zmq::send_flags::dontwait);
      const auto until =
          std::chrono::steady_clock::now() + std::chrono::milliseconds(options.timeout_ms);
      while (std::chrono::steady_clock::now() < until) {
        if (!Receive(reply, std::chrono::duration_cast<std::chrono::milliseconds>(
                                until - std::chrono::steady_clock::now())))
          break;
        if (reply->request_id == req.request_id && reply->type != ClientReplyMsg::Type::kEvent)
          return StatusFromWire(reply->code, reply->error);
      }
      if (!refused.empty()) break;  // retrying cannot help
      if (monitor && !monitor->last_transient().empty()) handshake = monitor->last_transient();
      sock.reset();  // Lazy Pirate: a fresh socket for the retry
      monitor.reset();
    }
    if (!refused.empty()) {
      sock.reset();
      monitor.reset();
      return {StatusCode::kUnavailable, refused};
    }
    std::string hint =
        options.curve
            ? "; or it refused this client's CURVE key, or --master-public is not its key"
            : "; the master may require CURVE keys (--curve-secret and --master-public, or "
              "PIEZOID_CURVE_SECRET and PIEZOID_MASTER_PUBLIC)";
    if (!handshake.empty()) hint += " (" + handshake + ")";
    if (sent_bytes > (1u << 20))
      hint += "; the request was " + std::to_string(sent_bytes) +
              " bytes: a master drops the connection of a request above its --max-message-bytes";
    return {StatusCode::kUnavailable,
            "cannot reach the master at " + options.endpoint +
                ": is piezoid-master running? (no answer to " + std::to_string(options.retries) +
                (options.retries == 1 ? " attempt" : " attempts") + " of " +
                std::to_string(options.timeout_ms) + " ms)" + hint};
  }
};

ServiceClient::ServiceClient(ServiceClientOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}

ServiceClient::~ServiceClient() = default;

Status ServiceClient::Submit(const job::JobSpec& spec, SubmitResult* out,
                             std::vector<job::FieldViolation>* violations,
                             std::string client_token) {
  if (client_token.empty()) client_token = service::ContentHash(std::to_string(impl_->rng()));
  ClientRequestMsg req;
  req.type = ClientRequestMsg::Type::kSubmit;
  req.spec = spec;
  req.client_token = client_token;
  ClientReplyMsg reply;
  Status s = impl_->Call(req, &reply);
  if (violations) *violations = reply.violations;
  if (!s.ok()) return s;
  out->job_id = reply.job_id;
  out->existed = reply.existed;
  return s;
}

Status ServiceClient::SubmitJson(const std::string& json, SubmitResult* out,
                                 std::vector<job::FieldViolation>* violations,
                                 std::string client_token) {
  job::JobSpec spec;
  std::vector<job::FieldViolation> decode;
  if (Status s = service::JobSpecFromJson(json, &spec, &decode); !s.ok()) return s;
  if (!decode.empty()) {
    if (violations) *violations = decode;
    return InvalidArgument(decode.front().description);
  }
  return Submit(spec, out, violations, std::move(client_token));
}

Status ServiceClient::GetStatus(const std::string& job_id, service::JobInfo* info) {
  ClientReplyMsg reply;
  Status s = impl_->CallOnJob(ClientRequestMsg::Type::kStatus, job_id, &reply);
  if (s.ok()) *info = reply.info;
  return s;
}

Status ServiceClient::List(std::vector<service::JobInfo>* jobs, int* workers, int* threads) {
  ClientRequestMsg req;
  req.type = ClientRequestMsg::Type::kList;
  ClientReplyMsg reply;
  Status s = impl_->Call(req, &reply);
  if (!s.ok()) return s;
  *jobs = reply.jobs;
  if (workers) *workers = reply.workers;
  if (threads) *threads = reply.worker_threads;
  return s;
}

Status ServiceClient::Workers(service::WorkersSnapshot* out) {
  ClientRequestMsg req;
  req.type = ClientRequestMsg::Type::kWorkers;
  ClientReplyMsg reply;
  Status s = impl_->Call(req, &reply);
  if (!s.ok()) return s;
  if (reply.type != ClientReplyMsg::Type::kWorkers)
    return Status(StatusCode::kUnavailable,
                  "the master did not answer the workers request (an older version?)");
  *out = std::move(reply.workers_snapshot);
  return s;
}

Status ServiceClient::FetchLog(const std::string& job_id, uint64_t from_generation,
                               service::JobInfo* info,
                               std::vector<service::GenerationRecord>* log) {
  ClientRequestMsg req;
  req.type = ClientRequestMsg::Type::kFetch;
  req.job_id = job_id;
  req.log_only = true;
  req.log_from = from_generation;
  ClientReplyMsg reply;
  Status s = impl_->Call(req, &reply);
  if (!s.ok()) return s;
  // A master without log_only answers the whole log: keep the asked part.
  log->clear();
  for (auto& r : reply.log)
    if (r.generation >= from_generation) log->push_back(std::move(r));
  if (info) *info = std::move(reply.info);
  return s;
}

Status ServiceClient::Cancel(const std::string& job_id) {
  ClientReplyMsg reply;
  return impl_->CallOnJob(ClientRequestMsg::Type::kCancel, job_id, &reply);
}

Status ServiceClient::Prune(const std::vector<std::string>& job_ids, double older_than_s, int keep,
                            bool dry_run, std::vector<std::string>* pruned,
                            std::vector<job::FieldViolation>* refused) {
  ClientRequestMsg req;
  req.type = ClientRequestMsg::Type::kPrune;
  req.job_ids = job_ids;
  req.older_than_s = older_than_s;
  req.keep = keep;
  req.dry_run = dry_run;
  ClientReplyMsg reply;
  Status s = impl_->Call(req, &reply);
  if (!s.ok()) return s;
  *pruned = std::move(reply.pruned);
  *refused = std::move(reply.refused);
  return s;
}

Status ServiceClient::Fetch(const std::string& job_id, int count,
                            std::vector<service::ScoredGenome>* best,
                            std::vector<service::GenerationRecord>* log, service::JobInfo* info,
                            job::JobSpec* spec, std::vector<io::SavedNetwork>* networks,
                            std::optional<job::LawCommittee>* committee) {
  ClientRequestMsg req;
  req.type = ClientRequestMsg::Type::kFetch;
  req.job_id = job_id;
  req.count = count;
  ClientReplyMsg reply;
  Status s = impl_->Call(req, &reply);
  if (!s.ok()) return s;
  if (best) *best = reply.best;
  if (log) *log = reply.log;
  if (info) *info = reply.info;
  if (networks) *networks = std::move(reply.networks);
  if (committee) *committee = std::move(reply.committee);
  if (spec) {
    if (!reply.spec) return {StatusCode::kDataLoss, "the master's fetch reply has no job spec"};
    *spec = *reply.spec;
  }
  return s;
}

Status ServiceClient::Watch(const std::string& job_id,
                            const std::function<bool(const service::JobEvent&)>& on_event,
                            std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const auto quiet = std::chrono::milliseconds(std::max(200, impl_->options.timeout_ms));
  std::optional<std::chrono::steady_clock::time_point> unreachable_since;
  while (std::chrono::steady_clock::now() < deadline) {
    ClientRequestMsg req;
    req.type = ClientRequestMsg::Type::kWatch;
    req.job_id = job_id;
    ClientReplyMsg reply;
    Status s = impl_->Call(req, &reply);
    if (s.code() == StatusCode::kUnavailable) {  // master restarting: try again, for a while
      if (!impl_->refused.empty()) return s;
      const auto now = std::chrono::steady_clock::now();
      if (!unreachable_since) unreachable_since = now;
      if (std::chrono::duration<double>(now - *unreachable_since).count() >=
          impl_->options.watch_reconnect_s)
        return s;
      continue;
    }
    unreachable_since.reset();
    if (!s.ok()) return s;
    if (service::IsFinal(reply.info.state)) {
      service::JobEvent e;
      e.job_id = job_id;
      e.state = reply.info.state;
      e.message = reply.info.message;
      e.storage_error = reply.info.storage_error;
      on_event(e);
      return Status::Ok();
    }
    // Events until the job ends; a quiet spell re-registers (e.g. after a master restart).
    for (;;) {
      const auto left = std::min(quiet, std::chrono::duration_cast<std::chrono::milliseconds>(
                                            deadline - std::chrono::steady_clock::now()));
      if (left.count() <= 0) break;
      ClientReplyMsg ev;
      if (!impl_->Receive(&ev, left)) break;
      if (ev.type != ClientReplyMsg::Type::kEvent || ev.event.job_id != job_id) continue;
      if (!on_event(ev.event)) return Status::Ok();
      if (service::IsFinal(ev.event.state)) return Status::Ok();
    }
  }
  return {StatusCode::kUnavailable, "watch of " + job_id + " timed out"};
}

Status ServiceClient::Evaluate(const std::string& job_id, uint64_t batch_seq,
                               const std::vector<opt::Genome>& genomes, bool* done,
                               std::vector<opt::FitnessResult>* results, int* worker_threads) {
  ClientRequestMsg req;
  req.type = ClientRequestMsg::Type::kEvaluate;
  req.job_id = job_id;
  req.batch_seq = batch_seq;
  req.genomes = genomes;
  ClientReplyMsg reply;
  Status s = impl_->Call(req, &reply);
  if (!s.ok()) return s;
  if (reply.type != ClientReplyMsg::Type::kEvaluate || reply.batch_seq != batch_seq)
    return {StatusCode::kDataLoss,
            "the master's evaluate reply does not answer batch " + std::to_string(batch_seq)};
  *done = reply.done;
  if (reply.done) *results = std::move(reply.results);
  if (worker_threads) *worker_threads = reply.worker_threads;
  return s;
}

Status ServiceClient::Close(const std::string& job_id) {
  ClientReplyMsg reply;
  return impl_->CallOnJob(ClientRequestMsg::Type::kClose, job_id, &reply);
}

Status ServiceClient::WaitFinal(const std::string& job_id, std::chrono::milliseconds timeout,
                                service::JobInfo* info) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  service::JobInfo i;
  while (std::chrono::steady_clock::now() < deadline) {
    Status s = GetStatus(job_id, &i);
    if (s.ok() && service::IsFinal(i.state)) {
      if (info) *info = i;
      return s;
    }
    if (!s.ok() && s.code() != StatusCode::kUnavailable) return s;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (info) *info = i;
  return {StatusCode::kUnavailable, "job " + job_id + " not final in time"};
}

}  // namespace pz::svcclient
