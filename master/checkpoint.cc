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
using service::EncodeCheckpoint;
using service::JobCheckpoint;
namespace fs = std::filesystem;
namespace {

Status Errno(const std::string& what, const fs::path& p) {
  return Internal(what + " " + p.string() + ": " + std::strerror(errno));
}

bool ValidJobId(const std::string& id) {
  if (id.empty() || id.size() > 64) return false;
  for (char c : id)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') return false;
  return true;
}

}  // namespace

Status WriteFileAtomic(const fs::path& path, std::string_view bytes, bool durable) {
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
  ::close(fd);
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
  return WriteFileAtomic(dir(job_id) / "spec.pb", spec_bytes);
}

Status JobDirectory::LoadSpec(const std::string& job_id, std::string* spec_bytes) const {
  if (!ValidJobId(job_id)) return InvalidArgument("bad job id '" + job_id + "'");
  return ReadWholeFile(dir(job_id) / "spec.pb", spec_bytes);
}

Status JobDirectory::SaveCheckpoint(const JobCheckpoint& c, bool durable) const {
  if (!ValidJobId(c.job_id)) return InvalidArgument("bad job id '" + c.job_id + "'");
  return WriteFileAtomic(dir(c.job_id) / "checkpoint.pb", EncodeCheckpoint(c), durable);
}

Status JobDirectory::LoadCheckpoint(const std::string& job_id, JobCheckpoint* c) const {
  if (!ValidJobId(job_id)) return InvalidArgument("bad job id '" + job_id + "'");
  std::string bytes;
  if (Status s = ReadWholeFile(dir(job_id) / "checkpoint.pb", &bytes); !s.ok()) return s;
  if (Status s = DecodeCheckpoint(bytes, c); !s.ok()) return s;
  if (c->job_id != job_id) return {StatusCode::kDataLoss, "checkpoint of another job"};
  return Status::Ok();
}

}  // namespace pz::master
