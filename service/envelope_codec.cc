// The envelope codec: worker ↔ master and client ↔ master frames (wire.proto), decoded into a
// status, never trusted.
#include "service/codec_detail.h"

#include <cmath>
#include <cstring>

#include <google/protobuf/io/coded_stream.h>

#include "network.pb.h"

namespace pz::service {
using namespace detail;
namespace {

// ---------------------------------------------------------------- worker protocol

void BatchToProto(const TaskBatchMsg& b, pw::TaskBatch* p) {
  p->set_lease_id(b.lease_id);
  p->set_job_id(b.job_id);
  p->set_generation(b.generation);
  p->set_context_hash(b.context_hash);
  p->set_deadline_s(b.deadline_s);
  for (size_t i = 0; i < b.indices.size(); ++i) {
    auto* t = p->add_tasks();
    t->set_index(b.indices[i]);
    ToProto(b.genomes[i], t->mutable_genome());
  }
}

Status BatchFromProto(const pw::TaskBatch& p, TaskBatchMsg* b) {
  b->lease_id = p.lease_id();
  b->job_id = p.job_id();
  b->generation = p.generation();
  b->context_hash = p.context_hash();
  b->deadline_s = p.deadline_s();
  b->indices.resize(p.tasks_size());
  b->genomes.resize(p.tasks_size());
  for (int i = 0; i < p.tasks_size(); ++i) {
    b->indices[i] = p.tasks(i).index();
    if (Status s = FromProto(p.tasks(i).genome(), &b->genomes[i]); !s.ok()) return s;
  }
  return Status::Ok();
}

void ResultToProto(const BatchResultMsg& r, pw::BatchResult* p) {
  p->set_lease_id(r.lease_id);
  p->set_job_id(r.job_id);
  p->set_generation(r.generation);
  p->set_code(static_cast<pw::Code>(r.code));
  p->set_error(r.error);
  p->set_eval_seconds(r.eval_seconds);
  for (size_t i = 0; i < r.indices.size(); ++i)
    ToProto(r.results[i], r.indices[i], p->add_results());
}

Status CodeFromProto(int c, WireCode* out) {
  if (!pw::Code_IsValid(c) || c == 0) return Malformed("code unspecified or unknown");
  *out = static_cast<WireCode>(c);
  return Status::Ok();
}

Status ResultFromProto(const pw::BatchResult& p, BatchResultMsg* r) {
  r->lease_id = p.lease_id();
  r->job_id = p.job_id();
  r->generation = p.generation();
  r->error = p.error();
  r->eval_seconds = p.eval_seconds();
  if (Status s = CodeFromProto(p.code(), &r->code); !s.ok()) return s;
  r->indices.resize(p.results_size());
  r->results.resize(p.results_size());
  for (int i = 0; i < p.results_size(); ++i) {
    const auto& t = p.results(i);
    r->indices[i] = t.index();
    if (Status s = FromProto(t, &r->results[i]); !s.ok()) return s;
  }
  return Status::Ok();
}

}  // namespace

std::string EncodeWorkerToMaster(const WorkerMsg& m) {
  pw::WorkerToMaster p;
  p.set_version(kProtocolVersion);
  switch (m.type) {
    case WorkerMsg::Type::kReady: {
      auto* r = p.mutable_ready();
      r->set_threads(static_cast<uint32_t>(m.threads));
      r->set_host(m.host);
      r->set_pid(m.pid);
      r->set_arithmetic(m.arithmetic);
      break;
    }
    case WorkerMsg::Type::kDisconnect:
      p.mutable_disconnect()->set_reason(m.reason);
      break;
    case WorkerMsg::Type::kContextRequest:
      p.mutable_context_request()->set_context_hash(m.context_hash);
      break;
    case WorkerMsg::Type::kResult:
      ResultToProto(m.result, p.mutable_result());
      break;
    default:
      p.mutable_heartbeat();
      break;
  }
  return p.SerializeAsString();
}

Status DecodeWorkerToMaster(std::string_view bytes, WorkerMsg* m) {
  pw::WorkerToMaster p;
  if (!Parse(bytes, &p)) return Malformed("worker message does not decode");
  if (Status s = VersionCheck(p.version()); !s.ok()) return s;
  *m = WorkerMsg{};
  switch (p.body_case()) {
    case pw::WorkerToMaster::kReady:
      m->type = WorkerMsg::Type::kReady;
      if (p.ready().threads() < 1 || p.ready().threads() > 4096)
        return Malformed("ready.threads must be in [1, 4096]");
      m->threads = static_cast<int>(p.ready().threads());
      m->host = p.ready().host();
      m->pid = p.ready().pid();
      m->arithmetic = p.ready().arithmetic();
      return Status::Ok();
    case pw::WorkerToMaster::kHeartbeat:
      m->type = WorkerMsg::Type::kHeartbeat;
      return Status::Ok();
    case pw::WorkerToMaster::kDisconnect:
      m->type = WorkerMsg::Type::kDisconnect;
      m->reason = p.disconnect().reason();
      return Status::Ok();
    case pw::WorkerToMaster::kContextRequest:
      m->type = WorkerMsg::Type::kContextRequest;
      m->context_hash = p.context_request().context_hash();
      return Status::Ok();
    case pw::WorkerToMaster::kResult:
      m->type = WorkerMsg::Type::kResult;
      return ResultFromProto(p.result(), &m->result);
    default:
      return Malformed("worker message has no body");
  }
}

// ---------------------------------------------------------------- packed leases

namespace {

using google::protobuf::io::CodedOutputStream;

/// The key of a length-delimited field (wire type 2).
constexpr uint8_t LengthDelimited(int field) { return static_cast<uint8_t>(field << 3 | 2); }
constexpr int kTaskBatchTasks = pw::TaskBatch::kTasksFieldNumber;
constexpr int kMasterToWorkerBatch = pw::MasterToWorker::kBatchFieldNumber;
static_assert(kTaskBatchTasks < 16 && kMasterToWorkerBatch < 16, "one-byte field keys");

}  // namespace

PackedTasks::PackedTasks(std::span<const Genome> genomes, std::span<const int> indices) {
  PZ_CHECK(genomes.size() == indices.size());
  pw::Task task;  // reused: its genome's strings keep their capacity
  ends_.reserve(genomes.size());
  for (size_t i = 0; i < genomes.size(); ++i) {
    task.set_index(indices[i]);
    ToProto(genomes[i], task.mutable_genome());
    const size_t length = task.ByteSizeLong();
    const size_t at = bytes_.size();
    if (i == 1) bytes_.reserve(at * genomes.size() + (at + 8) * 64);  // all alike, as a rule
    bytes_.resize(at + 1 + CodedOutputStream::VarintSize64(length) + length);
    auto* out = reinterpret_cast<uint8_t*>(bytes_.data() + at);
    *out++ = LengthDelimited(kTaskBatchTasks);
    out = CodedOutputStream::WriteVarint64ToArray(length, out);
    task.SerializeWithCachedSizesToArray(out);
    ends_.push_back(bytes_.size());
  }
}

std::string_view PackedTasks::Entry(int position) const {
  PZ_CHECK(position >= 0 && position < size());
  const size_t begin = position == 0 ? 0 : ends_[position - 1];
  return {bytes_.data() + begin, ends_[position] - begin};
}

size_t PackedTasks::Bytes(std::span<const int> positions) const {
  size_t total = 0;
  for (int p : positions) total += Entry(p).size();
  return total;
}

char* PackedTasks::Write(std::span<const int> positions, char* out) const {
  for (int p : positions) {
    const std::string_view e = Entry(p);
    std::memcpy(out, e.data(), e.size());
    out += e.size();
  }
  return out;
}

std::string PackedBatchHead(const TaskBatchMsg& header, size_t task_bytes) {
  TaskBatchMsg fields = header;
  fields.indices.clear();
  fields.genomes.clear();
  pw::TaskBatch batch;
  BatchToProto(fields, &batch);
  const std::string batch_fields = batch.SerializeAsString();
  pw::MasterToWorker envelope;  // what EncodeMasterToWorker sets besides the body
  envelope.set_version(kProtocolVersion);
  envelope.set_code(static_cast<pw::Code>(WorkerMsg{}.code));
  std::string out = envelope.SerializeAsString();
  const uint64_t length = batch_fields.size() + task_bytes;
  const size_t at = out.size();
  out.resize(at + 1 + CodedOutputStream::VarintSize64(length));
  auto* p = reinterpret_cast<uint8_t*>(out.data() + at);
  *p++ = LengthDelimited(kMasterToWorkerBatch);
  CodedOutputStream::WriteVarint64ToArray(length, p);
  return out + batch_fields;
}

std::string EncodeMasterToWorker(const WorkerMsg& m) {
  pw::MasterToWorker p;
  p.set_version(kProtocolVersion);
  p.set_code(static_cast<pw::Code>(m.code));
  switch (m.type) {
    case WorkerMsg::Type::kBatch:
      BatchToProto(m.batch, p.mutable_batch());
      break;
    case WorkerMsg::Type::kContext: {
      auto* c = p.mutable_context();
      c->set_context_hash(m.context_hash);
      c->set_spec(m.context_spec);
      c->set_code(static_cast<pw::Code>(m.code));
      break;
    }
    case WorkerMsg::Type::kDisconnect:
      p.mutable_disconnect()->set_reason(m.reason);
      p.set_error(m.reason);
      break;
    default:
      p.mutable_heartbeat();
      break;
  }
  return p.SerializeAsString();
}

Status DecodeMasterToWorker(std::string_view bytes, WorkerMsg* m) {
  pw::MasterToWorker p;
  if (!Parse(bytes, &p)) return Malformed("master message does not decode");
  if (Status s = VersionCheck(p.version()); !s.ok()) return s;
  *m = WorkerMsg{};
  m->code = pw::Code_IsValid(p.code()) ? static_cast<WireCode>(p.code()) : WireCode::kUnspecified;
  switch (p.body_case()) {
    case pw::MasterToWorker::kBatch:
      m->type = WorkerMsg::Type::kBatch;
      return BatchFromProto(p.batch(), &m->batch);
    case pw::MasterToWorker::kContext:
      m->type = WorkerMsg::Type::kContext;
      m->context_hash = p.context().context_hash();
      m->context_spec = p.context().spec();
      m->code = pw::Code_IsValid(p.context().code()) ? static_cast<WireCode>(p.context().code())
                                                     : WireCode::kUnspecified;
      return Status::Ok();
    case pw::MasterToWorker::kHeartbeat:
      m->type = WorkerMsg::Type::kHeartbeat;
      return Status::Ok();
    case pw::MasterToWorker::kDisconnect:
      m->type = WorkerMsg::Type::kDisconnect;
      m->reason = p.disconnect().reason();
      return Status::Ok();
    default:
      return Malformed("master message has no body");
  }
}

std::string EncodeClientRequest(const ClientRequestMsg& m) {
  pw::ClientRequest p;
  p.set_version(kProtocolVersion);
  p.set_request_id(m.request_id);
  using T = ClientRequestMsg::Type;
  switch (m.type) {
    case T::kSubmit:
      ToProto(m.spec, p.mutable_submit()->mutable_spec());
      p.mutable_submit()->set_client_token(m.client_token);
      break;
    case T::kStatus:
      p.mutable_status()->set_job_id(m.job_id);
      break;
    case T::kWatch:
      p.mutable_watch()->set_job_id(m.job_id);
      break;
    case T::kCancel:
      p.mutable_cancel()->set_job_id(m.job_id);
      break;
    case T::kList:
      p.mutable_list();
      break;
    case T::kFetch:
      p.mutable_fetch()->set_job_id(m.job_id);
      p.mutable_fetch()->set_count(static_cast<uint32_t>(std::max(0, m.count)));
      p.mutable_fetch()->set_log_only(m.log_only);
      p.mutable_fetch()->set_log_from(m.log_from);
      break;
    case T::kWorkers:
      p.mutable_workers();
      break;
    case T::kPing:
      p.mutable_ping();
      break;
    case T::kEvaluate: {
      auto* e = p.mutable_evaluate();
      e->set_job_id(m.job_id);
      e->set_batch_seq(m.batch_seq);
      for (const Genome& g : m.genomes) ToProto(g, e->add_genomes());
      break;
    }
    case T::kClose:
      p.mutable_close()->set_job_id(m.job_id);
      break;
    case T::kPrune: {
      auto* q = p.mutable_prune();
      for (const auto& id : m.job_ids) q->add_job_ids(id);
      q->set_older_than_s(m.older_than_s);
      q->set_keep(m.keep);
      q->set_dry_run(m.dry_run);
      break;
    }
  }
  return p.SerializeAsString();
}

Status DecodeClientRequest(std::string_view bytes, ClientRequestMsg* m) {
  pw::ClientRequest p;
  if (!Parse(bytes, &p)) return Malformed("client request does not decode");
  *m = ClientRequestMsg{};
  m->request_id = p.request_id();
  if (Status s = VersionCheck(p.version()); !s.ok()) return s;
  using T = ClientRequestMsg::Type;
  switch (p.body_case()) {
    case pw::ClientRequest::kSubmit:
      m->type = T::kSubmit;
      FromProto(p.submit().spec(), &m->spec, &m->decode_violations);
      m->spec_bytes = EncodeJobSpec(m->spec);
      m->client_token = p.submit().client_token();
      break;
    case pw::ClientRequest::kStatus:
      m->type = T::kStatus;
      m->job_id = p.status().job_id();
      break;
    case pw::ClientRequest::kWatch:
      m->type = T::kWatch;
      m->job_id = p.watch().job_id();
      break;
    case pw::ClientRequest::kCancel:
      m->type = T::kCancel;
      m->job_id = p.cancel().job_id();
      break;
    case pw::ClientRequest::kList:
      m->type = T::kList;
      break;
    case pw::ClientRequest::kFetch:
      m->type = T::kFetch;
      m->job_id = p.fetch().job_id();
      m->count = ClampInt(std::max<uint32_t>(1, p.fetch().count()));
      m->log_only = p.fetch().log_only();
      m->log_from = p.fetch().log_from();
      break;
    case pw::ClientRequest::kWorkers:
      m->type = T::kWorkers;
      break;
    case pw::ClientRequest::kPing:
      m->type = T::kPing;
      break;
    case pw::ClientRequest::kEvaluate: {
      const auto& e = p.evaluate();
      m->type = T::kEvaluate;
      m->job_id = e.job_id();
      m->batch_seq = e.batch_seq();
      m->genomes.resize(e.genomes_size());
      for (int i = 0; i < e.genomes_size(); ++i)
        if (Status s = FromProto(e.genomes(i), &m->genomes[i]); !s.ok())
          return Malformed("evaluate.genomes[" + std::to_string(i) + "]: " + s.message());
      break;
    }
    case pw::ClientRequest::kClose:
      m->type = T::kClose;
      m->job_id = p.close().job_id();
      break;
    case pw::ClientRequest::kPrune: {
      const auto& q = p.prune();
      m->type = T::kPrune;
      if (q.job_ids_size() > 100000) return Malformed("prune.job_ids: more than 100000");
      m->job_ids.assign(q.job_ids().begin(), q.job_ids().end());
      if (!std::isfinite(q.older_than_s()) || q.older_than_s() < 0)
        return Malformed("prune.older_than_s = " + std::to_string(q.older_than_s()) +
                         ": must be finite and >= 0");
      if (q.keep() < 0)
        return Malformed("prune.keep = " + std::to_string(q.keep()) + ": must be >= 0");
      m->older_than_s = q.older_than_s();
      m->keep = q.keep();
      m->dry_run = q.dry_run();
      break;
    }
    default:
      return Malformed("client request has no body");
  }
  return Status::Ok();
}

std::string EncodeClientReply(const ClientReplyMsg& m) {
  pw::ClientReply p;
  p.set_version(kProtocolVersion);
  p.set_request_id(m.request_id);
  p.set_code(static_cast<pw::Code>(m.code));
  p.set_error(m.error);
  for (const auto& v : m.violations) {
    auto* pv = p.add_violations();
    pv->set_field(v.field);
    pv->set_description(v.description);
  }
  using T = ClientReplyMsg::Type;
  switch (m.type) {
    case T::kSubmit:
      p.mutable_submit()->set_job_id(m.job_id);
      p.mutable_submit()->set_existed(m.existed);
      break;
    case T::kStatus:
      InfoToProto(m.info, p.mutable_status());
      break;
    case T::kList:
      for (const auto& j : m.jobs) InfoToProto(j, p.mutable_list()->add_jobs());
      p.mutable_list()->set_workers(static_cast<uint32_t>(m.workers));
      p.mutable_list()->set_worker_threads(static_cast<uint32_t>(m.worker_threads));
      break;
    case T::kFetch: {
      auto* f = p.mutable_fetch();
      InfoToProto(m.info, f->mutable_info());
      for (const auto& b : m.best) ToProto(b, f->add_best());
      for (const auto& r : m.log) ToProto(r, f->add_log());
      if (m.spec) ToProto(*m.spec, f->mutable_spec());
      for (const auto& n : m.networks) io::ToProto(n, f->add_networks());
      if (m.committee) ToProto(*m.committee, f->mutable_committee());
      break;
    }
    case T::kEvent: {
      auto* e = p.mutable_event();
      e->set_job_id(m.event.job_id);
      e->set_state(static_cast<pw::JobState>(m.event.state));
      if (m.event.record) ToProto(*m.event.record, e->mutable_record());
      e->set_message(m.event.message);
      e->set_workers(static_cast<uint32_t>(std::max(0, m.event.workers)));
      e->set_worker_threads(static_cast<uint32_t>(std::max(0, m.event.worker_threads)));
      e->set_storage_error(m.event.storage_error);
      break;
    }
    case T::kEvaluate: {
      auto* e = p.mutable_evaluate();
      e->set_job_id(m.job_id);
      e->set_batch_seq(m.batch_seq);
      e->set_done(m.done);
      for (size_t i = 0; i < m.results.size(); ++i)
        ToProto(m.results[i], static_cast<int>(i), e->add_results());
      e->set_worker_threads(static_cast<uint32_t>(std::max(0, m.worker_threads)));
      break;
    }
    case T::kWorkers:
      ToProto(m.workers_snapshot, p.mutable_workers());
      break;
    case T::kPrune: {
      auto* q = p.mutable_prune();
      for (const auto& id : m.pruned) q->add_pruned(id);
      for (const auto& v : m.refused) {
        auto* r = q->add_refused();
        r->set_field(v.field);
        r->set_description(v.description);
      }
      break;
    }
    case T::kNone:
      break;
  }
  return p.SerializeAsString();
}

Status DecodeClientReply(std::string_view bytes, ClientReplyMsg* m) {
  pw::ClientReply p;
  if (!Parse(bytes, &p)) return Malformed("client reply does not decode");
  if (Status s = VersionCheck(p.version()); !s.ok()) return s;
  *m = ClientReplyMsg{};
  m->request_id = p.request_id();
  if (Status s = CodeFromProto(p.code(), &m->code); !s.ok()) return s;
  m->error = p.error();
  for (const auto& v : p.violations()) m->violations.push_back({v.field(), v.description()});
  using T = ClientReplyMsg::Type;
  switch (p.body_case()) {
    case pw::ClientReply::kSubmit:
      m->type = T::kSubmit;
      m->job_id = p.submit().job_id();
      m->existed = p.submit().existed();
      break;
    case pw::ClientReply::kStatus:
      m->type = T::kStatus;
      return InfoFromProto(p.status(), &m->info);
    case pw::ClientReply::kList:
      m->type = T::kList;
      m->workers = ClampInt(p.list().workers());
      m->worker_threads = ClampInt(p.list().worker_threads());
      for (const auto& j : p.list().jobs()) {
        m->jobs.emplace_back();
        if (Status s = InfoFromProto(j, &m->jobs.back()); !s.ok()) return s;
      }
      break;
    case pw::ClientReply::kFetch:
      m->type = T::kFetch;
      for (const auto& r : p.fetch().log()) m->log.push_back(FromProto(r));
      if (p.fetch().has_spec()) {
        m->spec.emplace();
        FromProto(p.fetch().spec(), &*m->spec, nullptr);
      }
      if (Status s = IndividualsFromProto(p.fetch().best(), &m->best); !s.ok()) return s;
      for (int i = 0; i < p.fetch().networks_size(); ++i) {
        io::SavedNetwork n;
        if (Status s = io::FromProto(p.fetch().networks(i), &n); !s.ok())
          return Malformed("fetch.networks[" + std::to_string(i) + "]: " + s.message());
        m->networks.push_back(std::move(n));
      }
      if (p.fetch().has_committee()) {
        m->committee.emplace();
        if (Status s = FromProto(p.fetch().committee(), &*m->committee); !s.ok())
          return Malformed("fetch." + s.message());
      }
      return InfoFromProto(p.fetch().info(), &m->info);
    case pw::ClientReply::kEvent:
      m->type = T::kEvent;
      if (!ValidState(p.event().state())) return Malformed("event state unknown");
      m->event.job_id = p.event().job_id();
      m->event.state = static_cast<JobState>(p.event().state());
      if (p.event().has_record()) m->event.record = FromProto(p.event().record());
      m->event.message = p.event().message();
      m->event.workers = ClampInt(p.event().workers());
      m->event.worker_threads = ClampInt(p.event().worker_threads());
      m->event.storage_error = p.event().storage_error();
      break;
    case pw::ClientReply::kEvaluate: {
      const auto& e = p.evaluate();
      m->type = T::kEvaluate;
      m->job_id = e.job_id();
      m->batch_seq = e.batch_seq();
      m->done = e.done();
      m->worker_threads = ClampInt(e.worker_threads());
      m->results.resize(e.results_size());
      for (int i = 0; i < e.results_size(); ++i) {
        if (e.results(i).index() != i)
          return Malformed("evaluate.results[" + std::to_string(i) + "].index");
        if (Status s = FromProto(e.results(i), &m->results[i]); !s.ok()) return s;
      }
      break;
    }
    case pw::ClientReply::kPrune:
      m->type = T::kPrune;
      m->pruned.assign(p.prune().pruned().begin(), p.prune().pruned().end());
      for (const auto& r : p.prune().refused()) m->refused.push_back({r.field(), r.description()});
      break;
    case pw::ClientReply::kWorkers:
      m->type = T::kWorkers;
      m->workers_snapshot = FromProto(p.workers());
      break;
    default:
      m->type = T::kNone;
      break;
  }
  return Status::Ok();
}

}  // namespace pz::service
