#include "service/security.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <zmq.hpp>

namespace pz::service {
namespace fs = std::filesystem;
namespace {

constexpr size_t kZ85KeyLength = 40;

bool IsZ85Key(std::string_view s) {
  if (s.size() != kZ85KeyLength) return false;
  uint8_t bin[32];
  std::string z(s);
  return zmq_z85_decode(bin, z.c_str()) != nullptr;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

Status ReadSmallFile(const fs::path& path, std::string* text) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return NotFound(path.string() + ": cannot open (" + std::strerror(errno) + ")");
  std::ostringstream ss;
  ss << f.rdbuf();
  *text = ss.str();
  if (text->size() > 64 * 1024)
    return InvalidArgument(path.string() + ": too large for a key file");
  return Status::Ok();
}

Status WriteFileMode(const fs::path& path, const std::string& text, mode_t mode) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0)
    return {errno == EEXIST ? StatusCode::kFailedPrecondition : StatusCode::kInternal,
            path.string() + ": cannot create (" + std::strerror(errno) + ")"};
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size()) &&
                  ::fchmod(fd, mode) == 0 && ::fsync(fd) == 0;
  ::close(fd);
  if (!ok) return Internal(path.string() + ": cannot write");
  return Status::Ok();
}

std::string KeyFileText(const CurveKeyPair& p, bool secret) {
  std::string t;
  t += secret ? "#   ZeroMQ CURVE **Secret** Certificate\n"
                "#   DO NOT PROVIDE THIS FILE TO OTHER USERS nor change its permissions.\n"
              : "#   ZeroMQ CURVE Public Certificate\n"
                "#   Exchange securely, or use a secure mechanism to verify the contents\n"
                "#   of this file after exchange.\n";
  t += "#   Written by piezoid keygen (czmq zcert format).\n\nmetadata\ncurve\n";
  t += "    public-key = \"" + p.public_z85 + "\"\n";
  if (secret) t += "    secret-key = \"" + p.secret_z85 + "\"\n";
  return t;
}

}  // namespace

Status GenerateCurveKeyPair(CurveKeyPair* out) {
  char pub[41], sec[41];
  if (zmq_curve_keypair(pub, sec) != 0)
    return Internal(std::string("zmq_curve_keypair: ") + zmq_strerror(zmq_errno()) +
                    " (libzmq without CURVE support?)");
  out->public_z85 = pub;
  out->secret_z85 = sec;
  return Status::Ok();
}

Status ParseCurveKeyFile(std::string_view text, const std::string& source, CurveKeyPair* out) {
  *out = CurveKeyPair{};
  int line_no = 0;
  bool any_key = false;
  while (!text.empty()) {
    const size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line_no;
    line = Trim(line);
    if (line.empty() || line.front() == '#') continue;
    const size_t eq = line.find('=');
    if (eq == std::string_view::npos) continue;  // section names: metadata, curve
    const std::string_view name = Trim(line.substr(0, eq));
    std::string_view value = Trim(line.substr(eq + 1));
    if (name != "public-key" && name != "secret-key") continue;  // other metadata
    const std::string where = source + ":" + std::to_string(line_no) + ": ";
    if (value.size() < 2 || value.front() != '"' || value.back() != '"')
      return InvalidArgument(where + std::string(name) + ": the key must be in double quotes");
    value = value.substr(1, value.size() - 2);
    if (!IsZ85Key(value))
      return InvalidArgument(where + std::string(name) + " = \"" +
                             std::string(value.substr(0, 48)) +
                             "\": not a 40-character Z85 CURVE key");
    (name == "public-key" ? out->public_z85 : out->secret_z85) = std::string(value);
    any_key = true;
  }
  if (!any_key)
    return InvalidArgument(source + ": no public-key or secret-key line (not a CURVE key file)");
  if (!out->secret_z85.empty()) {
    char derived[41];
    if (zmq_curve_public(derived, out->secret_z85.c_str()) != 0)
      return InvalidArgument(source + ": secret-key: cannot derive its public key");
    if (out->public_z85.empty()) {
      out->public_z85 = derived;
    } else if (out->public_z85 != derived) {
      return InvalidArgument(source + ": public-key does not belong to secret-key");
    }
  }
  return Status::Ok();
}

Status WriteCurveKeyFiles(const fs::path& dir, const std::string& name, const CurveKeyPair& pair) {
  if (name.empty() || name.find('/') != std::string::npos || name.front() == '.')
    return InvalidArgument("--name = '" + name +
                           "': must be a plain file name (no '/', not starting with '.')");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Internal(dir.string() + ": cannot create (" + ec.message() + ")");
  const fs::path key = dir / (name + ".key"), pub = dir / (name + ".pub");
  for (const auto& p : {key, pub})
    if (fs::exists(p, ec))
      return {StatusCode::kFailedPrecondition, p.string() + ": exists; not overwritten"};
  if (Status s = WriteFileMode(key, KeyFileText(pair, true), 0600); !s.ok()) return s;
  return WriteFileMode(pub, KeyFileText(pair, false), 0644);
}

Status LoadCurveSecretFile(const fs::path& path, CurveKeyPair* out) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    return NotFound(path.string() + ": secret key file: cannot stat (" + std::strerror(errno) +
                    ")");
  if (st.st_mode & 0077) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    return InvalidArgument(path.string() + ": secret key file has mode " + mode +
                           ": group or others may access it; refused (chmod 600 " + path.string() +
                           ")");
  }
  std::string text;
  if (Status s = ReadSmallFile(path, &text); !s.ok()) return s;
  if (Status s = ParseCurveKeyFile(text, path.string(), out); !s.ok()) return s;
  if (out->secret_z85.empty())
    return InvalidArgument(path.string() +
                           ": no secret-key line (is this the .pub file? give NAME.key)");
  return Status::Ok();
}

Status LoadCurvePublicFile(const fs::path& path, std::string* public_z85) {
  std::string text;
  if (Status s = ReadSmallFile(path, &text); !s.ok()) return s;
  CurveKeyPair p;
  // A public file must not carry a secret: parse only what is needed and ignore a secret line's
  // absence; a .key file given here is accepted for its public key.
  if (Status s = ParseCurveKeyFile(text, path.string(), &p); !s.ok()) return s;
  if (p.public_z85.empty()) return InvalidArgument(path.string() + ": no public-key line");
  *public_z85 = p.public_z85;
  return Status::Ok();
}

// ------------------------------------------------------------------ AllowedKeys

Status AllowedKeys::Load(const fs::path& dir) {
  std::map<std::string, std::string> names;
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return NotFound(dir.string() + ": not a directory of allowed public keys (*.pub)");
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.path().extension() != ".pub") continue;
    std::string z85;
    if (Status s = LoadCurvePublicFile(e.path(), &z85); !s.ok()) return s;
    uint8_t bin[32];
    zmq_z85_decode(bin, z85.c_str());
    names[std::string(reinterpret_cast<const char*>(bin), 32)] = e.path().stem().string();
  }
  if (ec) return Internal(dir.string() + ": cannot list (" + ec.message() + ")");
  std::lock_guard lock(mu_);
  dir_ = dir;
  names_ = std::move(names);
  return Status::Ok();
}

std::optional<std::string> AllowedKeys::Find(std::string_view key_bytes) const {
  std::lock_guard lock(mu_);
  auto it = names_.find(std::string(key_bytes));
  if (it == names_.end()) return std::nullopt;
  return it->second;
}

size_t AllowedKeys::size() const {
  std::lock_guard lock(mu_);
  return names_.size();
}

// ------------------------------------------------------------------ ZapHandler

ZapHandler::ZapHandler(zmq::context_t& ctx, const CurveServerConfig& config)
    : ctx_(ctx), config_(config) {}

ZapHandler::~ZapHandler() { Stop(); }

Status ZapHandler::Start() {
  if (Status s = workers_.Load(config_.allow_workers); !s.ok())
    return {s.code(), "--allow-workers: " + s.message()};
  if (Status s = clients_.Load(config_.allow_clients); !s.ok())
    return {s.code(), "--allow-clients: " + s.message()};
  try {
    sock_ = std::make_unique<zmq::socket_t>(ctx_, zmq::socket_type::rep);
    sock_->set(zmq::sockopt::linger, 0);
    sock_->bind("inproc://zeromq.zap.01");
  } catch (const zmq::error_t& e) {
    return Internal(std::string("ZAP handler: cannot bind inproc://zeromq.zap.01: ") + e.what());
  }
  spdlog::info("CURVE on: {} worker key(s) from {}, {} client key(s) from {}", workers_.size(),
               config_.allow_workers.string(), clients_.size(), config_.allow_clients.string());
  thread_ = std::thread([this] { Run(); });
  return Status::Ok();
}

void ZapHandler::Stop() {
  if (!thread_.joinable()) return;
  stop_ = true;
  thread_.join();
  sock_.reset();
}

void ZapHandler::Run() {
  while (!stop_.load()) {
    zmq::pollitem_t items[] = {{sock_->handle(), 0, ZMQ_POLLIN, 0}};
    try {
      zmq::poll(items, 1, std::chrono::milliseconds(100));
    } catch (const zmq::error_t& e) {
      if (e.num() == EINTR) continue;
      if (e.num() == ETERM) return;
      throw;
    }
    if (!(items[0].revents & ZMQ_POLLIN)) continue;
    std::vector<zmq::message_t> frames;
    for (int i = 0; i < 16; ++i) {
      zmq::message_t m;
      if (!sock_->recv(m, zmq::recv_flags::dontwait)) break;
      const bool more = m.more();
      frames.push_back(std::move(m));
      if (!more) break;
    }
    // version, request id, domain, address, routing id, mechanism, credentials…
    std::string request_id = frames.size() > 1 ? frames[1].to_string() : std::string();
    std::string code = "400", text, user;
    if (frames.size() < 6 || frames[0].to_string() != "1.0") {
      code = "500";
      text = "malformed ZAP request";
    } else {
      const std::string domain = frames[2].to_string(), address = frames[3].to_string(),
                        mechanism = frames[5].to_string();
      AllowedKeys* keys = domain == kZapDomainWorkers   ? &workers_
                          : domain == kZapDomainClients ? &clients_
                                                        : nullptr;
      if (!keys) {
        text = "unknown ZAP domain '" + domain + "'";
      } else if (mechanism != "CURVE" || frames.size() < 7 || frames[6].size() != 32) {
        text = "CURVE required";
      } else {
        const std::string key = frames[6].to_string();
        auto name = keys->Find(key);
        if (!name) {  // perhaps added since: re-read the directory once
          if (Status s = keys->Load(keys->dir()); !s.ok())
            spdlog::error("ZAP: re-reading {}: {}", keys->dir().string(), s.message());
          name = keys->Find(key);
        }
        char z85[41];
        zmq_z85_encode(z85, reinterpret_cast<const uint8_t*>(key.data()), 32);
        if (name) {
          code = "200";
          text = "OK";
          user = domain + ":" + *name;
          ++accepted_;
          spdlog::debug("ZAP: {} {} accepted as {}", domain, address, user);
        } else {
          text = "unknown " + std::string(domain == kZapDomainWorkers ? "worker" : "client") +
                 " key " + z85 + " (not in " + keys->dir().string() + ")";
          ++refused_;
          spdlog::warn("ZAP: refused {} from {}: {}", domain, address, text);
        }
      }
    }
    try {
      sock_->send(zmq::str_buffer("1.0"), zmq::send_flags::sndmore);
      sock_->send(zmq::buffer(request_id), zmq::send_flags::sndmore);
      sock_->send(zmq::buffer(code), zmq::send_flags::sndmore);
      sock_->send(zmq::buffer(text), zmq::send_flags::sndmore);
      sock_->send(zmq::buffer(user), zmq::send_flags::sndmore);
      sock_->send(zmq::str_buffer(""), zmq::send_flags::none);
    } catch (const zmq::error_t& e) {
      spdlog::error("ZAP: cannot reply: {}", e.what());
    }
  }
}

// ------------------------------------------------------------------ client side

void SetCurveClient(zmq::socket_t& sock, const CurveKeyPair& own,
                    const std::string& server_public) {
  sock.set(zmq::sockopt::curve_serverkey, server_public);
  sock.set(zmq::sockopt::curve_publickey, own.public_z85);
  sock.set(zmq::sockopt::curve_secretkey, own.secret_z85);
}

HandshakeMonitor::HandshakeMonitor(zmq::context_t& ctx, zmq::socket_t& watched, std::string who)
    : who_(std::move(who)) {
  static std::atomic<uint64_t> counter{0};
  const std::string ep = "inproc://pz-handshake-monitor-" + std::to_string(::getpid()) + "-" +
                         std::to_string(counter++);
  if (zmq_socket_monitor(watched.handle(), ep.c_str(),
                         ZMQ_EVENT_HANDSHAKE_FAILED_AUTH | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                             ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL) != 0)
    return;
  pair_ = std::make_unique<zmq::socket_t>(ctx, zmq::socket_type::pair);
  pair_->set(zmq::sockopt::linger, 0);
  pair_->connect(ep);
}

HandshakeMonitor::~HandshakeMonitor() = default;

void* HandshakeMonitor::handle() const { return pair_ ? pair_->handle() : nullptr; }

std::optional<std::string> HandshakeMonitor::Poll() {
  std::optional<std::string> out;
  if (!pair_) return out;
  for (int guard = 0; guard < 1000; ++guard) {
    zmq::message_t head, addr;
    if (!pair_->recv(head, zmq::recv_flags::dontwait)) break;
    if (head.more()) (void)pair_->recv(addr, zmq::recv_flags::dontwait);
    if (head.size() < 6) continue;
    uint16_t event;
    uint32_t value;
    std::memcpy(&event, head.data(), 2);
    std::memcpy(&value, static_cast<const char*>(head.data()) + 2, 4);
    const std::string where = addr.to_string();
    switch (event) {
      case ZMQ_EVENT_HANDSHAKE_FAILED_AUTH:
        out = "the master at " + where + " refused this " + who_ + "'s CURVE key (ZAP status " +
              std::to_string(value) + "): ask its operator to add this " + who_ +
              "'s .pub file to the master's --allow-" + who_ + "s directory";
        break;
      case ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL:
        if (value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH)
          out = "the master at " + where + " uses another security mechanism than this " + who_ +
                ": it may require CURVE keys (--curve-secret and --master-public), or not expect "
                "them";
        else if (value == ZMQ_PROTOCOL_ERROR_ZMTP_CRYPTOGRAPHIC)
          out = "CURVE handshake with the master at " + where +
                " failed (cryptographic error): is --master-public the master's public key?";
        else  // e.g. a connection cut during the handshake: ZeroMQ retries, so may we
          transient_ = "handshake with the master at " + where + " failed (ZMTP protocol error 0x" +
                       fmt::format("{:x}", value) + ")";
        break;
      default:
        transient_ = "handshake with the master at " + where + " failed";
        break;
    }
  }
  return out;
}

// ------------------------------------------------------------------ endpoints

bool IsLoopbackEndpoint(std::string_view ep) {
  if (ep.starts_with("ipc://") || ep.starts_with("inproc://")) return true;
  if (!ep.starts_with("tcp://")) return false;
  std::string_view host = ep.substr(6);
  // An optional "source;" part of a connect endpoint is irrelevant for binds.
  if (host.starts_with("[")) {
    const size_t close = host.find(']');
    host = close == std::string_view::npos ? host : host.substr(1, close - 1);
    return host == "::1";
  }
  host = host.substr(0, host.rfind(':'));
  return host == "localhost" || host == "127.0.0.1" || host.starts_with("127.") || host == "lo";
}

}  // namespace pz::service
