// Job state on disk: state_dir/jobs/<job id>/{spec.pb, checkpoint.pb}, each replaced atomically
// (write a temporary file, rename it over the old one), so a master killed at any instant leaves
// either the previous or the new checkpoint, never a torn one. A durable write also fsyncs the file
// before the rename and the directory after it, so the checkpoint survives a power loss too.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "service/service_types.h"
#include "model/status.h"

namespace pz::master {

Status WriteFileAtomic(const std::filesystem::path& path, std::string_view bytes, bool durable = true);
/// Reads a whole file (at most max_bytes); NotFound if it does not exist.
Status ReadWholeFile(const std::filesystem::path& path, std::string* out,
                     size_t max_bytes = size_t{1} << 31);

class JobDirectory {
 public:
  explicit JobDirectory(std::filesystem::path state_dir) : root_(std::move(state_dir) / "jobs") {}
  std::filesystem::path dir(const std::string& job_id) const { return root_ / job_id; }

  /// The ids of all stored jobs, sorted.
  std::vector<std::string> List() const;
  Status SaveSpec(const std::string& job_id, std::string_view spec_bytes) const;
  Status LoadSpec(const std::string& job_id, std::string* spec_bytes) const;
  /// durable: fsync file and directory (see the file comment).
  Status SaveCheckpoint(const service::JobCheckpoint& c, bool durable = true) const;
  /// NotFound when the job has no checkpoint yet.
  Status LoadCheckpoint(const std::string& job_id, service::JobCheckpoint* c) const;

 private:
  std::filesystem::path root_;
};

}  // namespace pz::master
