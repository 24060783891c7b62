// Job state on disk: state_dir/jobs/<job id>/{spec.pb, checkpoint.pb, checkpoint.prev.pb}, each a
// StoredFile (proto/job.proto: the payload with its length and CRC-32), each replaced atomically
// (write a temporary file, rename it over the old one), so a master killed at any instant leaves
// either the previous or the new checkpoint, never a torn one. A durable write also fsyncs the file
// before the rename and the directory after it, so the checkpoint survives a power loss too.
//
// Integrity: every write of checkpoint.pb first moves the one it replaces to checkpoint.prev.pb.
// Loading verifies the checksum; a checkpoint that is missing, truncated, altered (one flipped bit
// is enough), of another job or undecodable is replaced by the previous one (a generation earlier:
// resuming from it gives the same result, bit for bit, since the GA's state includes its
// generator), and when that is bad too the job restarts from generation 0 from its spec (the same
// result again). What was done is returned as a notice naming the files, for the log and status.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "service/service_types.h"
#include "model/status.h"

namespace pz::master {

/// Writes `bytes` to path.tmp and renames it over `path`; when `previous` is given, the file it
/// replaces first becomes `previous` (hard link + rename: `path` exists at every instant).
Status WriteFileAtomic(const std::filesystem::path& path, std::string_view bytes,
                       bool durable = true, const std::filesystem::path& previous = {});
/// Reads a whole file (at most max_bytes); NotFound if it does not exist.
Status ReadWholeFile(const std::filesystem::path& path, std::string* out,
                     size_t max_bytes = size_t{1} << 31);

class JobDirectory {
 public:
  explicit JobDirectory(std::filesystem::path state_dir) : root_(std::move(state_dir) / "jobs") {}
  std::filesystem::path dir(const std::string& job_id) const { return root_ / job_id; }
  static constexpr const char* kSpecFile = "spec.pb";
  static constexpr const char* kCheckpointFile = "checkpoint.pb";
  static constexpr const char* kPreviousFile = "checkpoint.prev.pb";

  /// The ids of all stored jobs, sorted.
  std::vector<std::string> List() const;
  Status SaveSpec(const std::string& job_id, std::string_view spec_bytes) const;
  /// NotFound when there is no spec.pb; kDataLoss naming the file when it is corrupt.
  Status LoadSpec(const std::string& job_id, std::string* spec_bytes) const;
  /// durable: fsync file and directory (see the file comment). The replaced checkpoint becomes
  /// checkpoint.prev.pb.
  Status SaveCheckpoint(const service::JobCheckpoint& c, bool durable = true) const;
  /// The job's checkpoint, or the previous one when it is unusable (*notice says which file was
  /// bad and why, and what was used). NotFound when there is no usable checkpoint: a new job, or
  /// (with *notice set) one whose checkpoints are both unusable, to be restarted from its spec.
  Status LoadCheckpoint(const std::string& job_id, service::JobCheckpoint* c,
                        std::string* notice) const;
  /// Removes the job's folder (a submission whose spec could not be written, a pruned job).
  Status Remove(const std::string& job_id) const;

 private:
  std::filesystem::path root_;
};

/// The arithmetic profile a master must serve on this state directory: the one recorded in the
/// checkpoint of a job that has not ended (the first such job by id), with a sentence naming that
/// job for the refusal of other workers; nullopt when no running job recorded one. A job computed
/// on one profile continues on it after a restart, whichever worker reaches the new master first.
struct PinnedProfile {
  std::string profile, why;
};
std::optional<PinnedProfile> PinnedArithmetic(const JobDirectory& dir);

}  // namespace pz::master
