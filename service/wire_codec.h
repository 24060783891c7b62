// The edge between protobuf (proto/job.proto, proto/wire.proto) and the domain structs of
// service/service_types.h: the only file that sees generated protobuf types on the service side.
// Decoders never throw: they return kDataLoss for a frame that does not decode (or decodes to
// inconsistent content) and kFailedPrecondition for another protocol or format version.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "service/service_types.h"
#include "model/status.h"

namespace pz::service {

/// FNV-1a 64-bit hash of `bytes` as 16 hex digits (content addressing, not authentication).
std::string ContentHash(std::string_view bytes);

/// The job id of a spec (its serialised bytes) submitted with a client token: content-addressed,
/// so a retried submission is the same job.
std::string JobIdOf(const std::string& spec_bytes, const std::string& client_token);

/// Maps a decode status to the wire code answered to the sender.
WireCode DecodeFailureCode(const Status& s);

// Job specs. Encoding is deterministic (stable bytes for hashing); defaults are made explicit.
std::string EncodeJobSpec(const job::JobSpec& spec);
/// Decodes a serialised JobSpec; field-level problems (e.g. an unknown enum) go to *violations.
Status DecodeJobSpec(std::string_view bytes, job::JobSpec* spec,
                     std::vector<job::FieldViolation>* violations = nullptr);
/// Parses a protobuf-JSON job spec (the user-facing format, see examples/).
Status JobSpecFromJson(const std::string& json, job::JobSpec* spec,
                       std::vector<job::FieldViolation>* violations = nullptr);
std::string JobSpecToJson(const job::JobSpec& spec);

// Worker ↔ master.
std::string EncodeWorkerToMaster(const WorkerMsg& m);
Status DecodeWorkerToMaster(std::string_view bytes, WorkerMsg* m);
std::string EncodeMasterToWorker(const WorkerMsg& m);
Status DecodeMasterToWorker(std::string_view bytes, WorkerMsg* m);

/// A generation's tasks encoded once, when the generation is submitted: each one is the wire bytes
/// of a TaskBatch's `tasks` entry (tag, length, Task{index, packed genome}), so that a lease — and
/// a re-dispatched suspect or a speculative copy — is written by copying bytes, without the genomes
/// being copied or packed again. A message of PackedBatchHead + Write decodes
/// (DecodeMasterToWorker) exactly as EncodeMasterToWorker's batch of the same tasks.
class PackedTasks {
 public:
  PackedTasks() = default;
  /// `indices[i]` is the population index of `genomes[i]` (same length).
  PackedTasks(std::span<const opt::Genome> genomes, std::span<const int> indices);
  int size() const { return static_cast<int>(ends_.size()); }
  /// Bytes of the entries of `positions` (each in [0, size())).
  size_t Bytes(std::span<const int> positions) const;
  /// Writes the entries of `positions` at `out` (Bytes(positions) bytes); returns the end.
  char* Write(std::span<const int> positions, char* out) const;

 private:
  std::string_view Entry(int position) const;
  std::string bytes_;
  std::vector<size_t> ends_;  ///< entry i is bytes_[ends_[i-1], ends_[i])
};

/// The bytes of a batch message (MasterToWorker) up to its tasks: the envelope and `header`'s
/// fields (its indices and genomes are ignored), the batch's length counting `task_bytes` more,
/// which PackedTasks::Write appends.
std::string PackedBatchHead(const TaskBatchMsg& header, size_t task_bytes);

// Client ↔ master.
/// The dashboard's JSON documents (proto/dashboard.proto through protobuf's JSON printer).
std::string DashboardStateJson(const std::string& master, double polled_unix_s, uint64_t polls,
                               const std::string& error, const std::vector<JobInfo>& jobs,
                               const WorkersSnapshot& workers, const std::string& workers_error,
                               const std::vector<std::string>& reports);
std::string DashboardCurveJson(const std::string& job_id,
                               const std::vector<GenerationRecord>& records);

std::string EncodeClientRequest(const ClientRequestMsg& m);
Status DecodeClientRequest(std::string_view bytes, ClientRequestMsg* m);
std::string EncodeClientReply(const ClientReplyMsg& m);
Status DecodeClientReply(std::string_view bytes, ClientReplyMsg* m);

// Stored job state.
std::string EncodeCheckpoint(const JobCheckpoint& c);
Status DecodeCheckpoint(std::string_view bytes, JobCheckpoint* c);

/// A file of the state directory: `payload` (a serialised message of protobuf type `type`) framed
/// with its length and CRC-32 (proto StoredFile).
std::string EncodeStoredFile(std::string_view type, std::string_view payload);
/// The payload of a stored file of `type`; kDataLoss naming what is wrong (not a stored file,
/// another type, truncated, checksum mismatch). A file written before stored files existed (a
/// bare payload) is kNotFound, so that a caller may read it as the bare message.
Status DecodeStoredFile(std::string_view bytes, std::string_view type, std::string* payload);

/// "0101…" rendering of genome bits (logs, reports).
std::string BitString(const opt::Genome& g);

}  // namespace pz::service
