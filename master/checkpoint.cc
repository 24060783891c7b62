#include "master/checkpoint.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>

#include "service/wire_codec.h"

namespace pz::master {

using service::DecodeCheckpoint;
using service::DecodeStoredFile;
using service::EncodeCheckpoint;
using service::EncodeStoredFile;
using service::JobCheckpoint;
namespace fs = std::filesystem;
namespace {

Status Errno(const std::string& what, const fs::path& p) {
  return Internal(what + " " + p.string() + ": " + std::strerror(errno));
}

constexpr std::string_view kSpecType = "pz.wire.JobSpec";
constexpr std::string_view kCheckpointType = "pz.wire.JobCheckpoint";

bool ValidJobId(const std::string& id) {
  if (id.empty() || id.size() > 64) return false;
  for (char c : id)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') return false;
  return true;
}

}  // namespace

Status WriteFileAtomic(const fs::path& path, std::string_view bytes, bool durable,
                       const fs::path& previous) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec) return Internal("cannot create " + path.parent_path().string() + ": " + ec.message());
  const fs::path tmp = path.string() + ".tmp";
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Errno("cannot open", tmp);
  size_t off = 0;
  while (off < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + off, bytes.size() - off);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      Status s = Errno("cannot write", tmp);
      ::close(fd);
      return s;
    }
    off += static_cast<size_t>(n);
  }
  if (durable && ::fsync(fd) != 0) {
    Status s = Errno("cannot fsync", tmp);
    ::close(fd);
    return s;
  }
  if (::close(fd) != 0) return Errno("cannot write", tmp);  // NFS and friends report late
  if (!previous.empty()) {
    // The replaced file becomes `previous` through a hard link, so that `path` exists at every
    // instant (a master killed between two renames would otherwise leave only `previous`).
    const fs::path link_tmp = previous.string() + ".tmp";
    (void)::unlink(link_tmp.c_str());
    if (::link(path.c_str(), link_tmp.c_str()) == 0) {
      if (::rename(link_tmp.c_str(), previous.c_str()) != 0)
        return Errno("cannot rename onto", previous);
    } else if (errno != ENOENT) {
      return Errno("cannot link " + path.string() + " to", link_tmp);
    }
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) return Errno("cannot rename onto", path);
  if (!durable) return Status::Ok();
  int dfd = ::open(path.parent_path().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    (void)::fsync(dfd);
    ::close(dfd);
  }
  return Status::Ok();
}

Status ReadWholeFile(const fs::path& path, std::string* out, size_t max_bytes) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return NotFound(path.string() + " does not exist");
  const auto size = fs::file_size(path, ec);
  if (ec) return Internal("cannot stat " + path.string() + ": " + ec.message());
  if (size > max_bytes) return OutOfRange(path.string() + " is larger than allowed");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Internal("cannot open " + path.string());
  out->assign(size, '\0');
  in.read(out->data(), static_cast<std::streamsize>(size));
  if (!in) return Internal("cannot read " + path.string());
  return Status::Ok();
}

std::vector<std::string> JobDirectory::List() const {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(root_, ec)) {
    const std::string name = e.path().filename().string();
    if (e.is_directory() && ValidJobId(name)) out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

Status JobDirectory::SaveSpec(const std::string& job_id, std::string_view spec_bytes) const {
  if (!ValidJobId(job_id)) return InvalidArgument("bad job id '" + job_id + "'");
  return WriteFileAtomic(dir(job_id) / kSpecFile, EncodeStoredFile(kSpecType, spec_bytes));
}

Status JobDirectory::LoadSpec(const std::string& job_id, std::string* spec_bytes) const {
  if (!ValidJobId(job_id)) return InvalidArgument("bad job id '" + job_id + "'");
  const fs::path file = dir(job_id) / kSpecFile;
  std::string bytes;
  if (Status s = ReadWholeFile(file, &bytes); !s.ok()) return s;
  Status s = DecodeStoredFile(bytes, kSpecType, spec_bytes);
  if (s.code() == StatusCode::kNotFound) {  // written before stored files: the bare spec
    *spec_bytes = std::move(bytes);
    return Status::Ok();
  }
  if (!s.ok()) return {StatusCode::kDataLoss, file.string() + ": " + s.message()};
  return Status::Ok();
}

Status JobDirectory::SaveCheckpoint(const JobCheckpoint& c, bool durable) const {
  if (!ValidJobId(c.job_id)) return InvalidArgument("bad job id '" + c.job_id + "'");
  return WriteFileAtomic(dir(c.job_id) / kCheckpointFile,
                         EncodeStoredFile(kCheckpointType, EncodeCheckpoint(c)), durable,
                         dir(c.job_id) / kPreviousFile);
}

namespace {

/// One checkpoint file: OK, NotFound (no such file), or why it is unusable.
Status LoadOne(const fs::path& file, const std::string& job_id, JobCheckpoint* c) {
  std::string bytes, payload;
  if (Status s = ReadWholeFile(file, &bytes); !s.ok()) return s;
  Status s = DecodeStoredFile(bytes, kCheckpointType, &payload);
  if (s.code() == StatusCode::kNotFound) {
    payload = std::move(bytes);  // written before stored files: the bare checkpoint
  } else if (!s.ok()) {
    return {StatusCode::kDataLoss, s.message()};
  }
  if (Status d = DecodeCheckpoint(payload, c); !d.ok())
    return {StatusCode::kDataLoss,
            s.code() == StatusCode::kNotFound ? "not a checkpoint" : d.message()};
  if (c->job_id != job_id) return {StatusCode::kDataLoss, "the checkpoint of job " + c->job_id};
  return Status::Ok();
}

}  // namespace

Status JobDirectory::LoadCheckpoint(const std::string& job_id, JobCheckpoint* c,
                                    std::string* notice) const {
  if (!ValidJobId(job_id)) return InvalidArgument("bad job id '" + job_id + "'");
  notice->clear();
  const fs::path current = dir(job_id) / kCheckpointFile, previous = dir(job_id) / kPreviousFile;
  const Status a = LoadOne(current, job_id, c);
  if (a.ok()) return a;
  const Status b = LoadOne(previous, job_id, c);
  if (a.code() == StatusCode::kNotFound && b.code() == StatusCode::kNotFound)
    return a;  // a new job
  std::string why =
      current.string() + ": " + (a.code() == StatusCode::kNotFound ? "missing" : a.message());
  if (b.ok()) {
    *notice = why + "; resumed from " + previous.string() + " (after generation " +
              std::to_string(c->log.size()) + ")";
    return b;
  }
  *c = JobCheckpoint{};
  *notice = why + "; " + previous.string() + ": " +
            (b.code() == StatusCode::kNotFound ? "missing" : b.message()) +
            "; restarted from generation 0 from the job's spec";
  return {StatusCode::kNotFound, *notice};
}

Status JobDirectory::Remove(const std::string& job_id) const {
  if (!ValidJobId(job_id)) return InvalidArgument("bad job id '" + job_id + "'");
  std::error_code ec;
  fs::remove_all(dir(job_id), ec);
  if (ec) return Internal("cannot remove " + dir(job_id).string() + ": " + ec.message());
  return Status::Ok();
}

std::optional<PinnedProfile> PinnedArithmetic(const JobDirectory& dir) {
  for (const std::string& id : dir.List()) {
    service::JobCheckpoint c;
    std::string notice;
    if (!dir.LoadCheckpoint(id, &c, &notice).ok() || service::IsFinal(c.state) ||
        c.arithmetic.empty())
      continue;
    return PinnedProfile{c.arithmetic,
                         "fixed by job " + id + ", computed on it before this master started"};
  }
  return std::nullopt;
}

}  // namespace pz::master
