// CurveZMQ for the service: key files, the directories of allowed public keys, the ZAP handler
// (ZeroMQ's inproc://zeromq.zap.01 protocol, RFC 27) and a handshake monitor that turns a refused
// connection into a clear error on the refused side. See docs/service.md, "Security".
//
// Key files are czmq's "zcert" text format (ZPL), so czmq-made certificates work too:
//
//   #   ZeroMQ CURVE **Secret** Certificate        (NAME.key, mode 0600)
//   metadata
//   curve
//       public-key = "<40 Z85 characters>"
//       secret-key = "<40 Z85 characters>"
//
// NAME.pub is the same without the secret-key line. Lines starting with '#' and blank lines are
// ignored; a file holding a secret key is refused when group or others have any permission on it.
#pragma once

#include <atomic>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include "model/status.h"

namespace zmq {
class context_t;
class socket_t;
}  // namespace zmq

namespace pz::service {

/// A CURVE key pair as Z85 text (40 characters each); secret_z85 is empty for a public key.
struct CurveKeyPair {
  std::string public_z85, secret_z85;
};

/// A fresh key pair (libsodium through zmq_curve_keypair).
Status GenerateCurveKeyPair(CurveKeyPair* out);
/// Parses a key file's text; `source` names it in errors ("<source>:<line>: …").
Status ParseCurveKeyFile(std::string_view text, const std::string& source, CurveKeyPair* out);
/// Writes DIR/NAME.key (secret, mode 0600) and DIR/NAME.pub (mode 0644); refuses to overwrite.
Status WriteCurveKeyFiles(const std::filesystem::path& dir, const std::string& name,
                          const CurveKeyPair& pair);
/// Reads a secret key file (refused if group/world accessible or without a secret key); the
/// public key is derived from the secret one when the file lacks it, and checked when present.
Status LoadCurveSecretFile(const std::filesystem::path& path, CurveKeyPair* out);
/// Reads a public key (a .pub file, or the public-key line of a .key file).
Status LoadCurvePublicFile(const std::filesystem::path& path, std::string* public_z85);

/// Public keys allowed on one endpoint: every *.pub file of a directory, by the file's stem.
class AllowedKeys {
 public:
  /// Reads the directory (an error names the file); replaces the keys only on success.
  Status Load(const std::filesystem::path& dir);
  /// The key's name (file stem) if the 32-byte binary public key is allowed.
  std::optional<std::string> Find(std::string_view key_bytes) const;
  size_t size() const;
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  mutable std::mutex mu_;
  std::map<std::string, std::string> names_;  // binary key → name
};

/// The server side of CURVE for the master: its key pair and who may connect where.
struct CurveServerConfig {
  CurveKeyPair keys;
  std::filesystem::path allow_workers, allow_clients;
};

/// ZAP domains set on the master's two sockets.
inline constexpr const char* kZapDomainWorkers = "workers";
inline constexpr const char* kZapDomainClients = "clients";

/// The ZAP handler: a thread with a REP socket on inproc://zeromq.zap.01 in the sockets'
/// context. A CURVE peer is accepted when its public key is in the allowed directory of the
/// socket's domain; the User-Id of its messages is then "<domain>:<key name>". Directories are
/// re-read when a key is not found (keys can be added without a restart).
class ZapHandler {
 public:
  ZapHandler(zmq::context_t& ctx, const CurveServerConfig& config);
  ~ZapHandler();
  /// Loads both directories and binds; must precede the bind of the CURVE sockets.
  Status Start();
  void Stop();
  uint64_t accepted() const { return accepted_; }
  uint64_t refused() const { return refused_; }

 private:
  void Run();
  zmq::context_t& ctx_;
  CurveServerConfig config_;
  AllowedKeys workers_, clients_;
  std::unique_ptr<zmq::socket_t> sock_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> accepted_{0}, refused_{0};
};

/// Sets the client side of CURVE on a socket (before connect).
void SetCurveClient(zmq::socket_t& sock, const CurveKeyPair& own, const std::string& server_public);

/// Watches a connecting socket's handshakes (zmq_socket_monitor) and explains a failure:
/// "the master refused this worker's CURVE key (ZAP 400: …)", a mechanism mismatch, …
class HandshakeMonitor {
 public:
  /// `who`: "client" or "worker" (for the messages).
  HandshakeMonitor(zmq::context_t& ctx, zmq::socket_t& watched, std::string who);
  ~HandshakeMonitor();
  void* handle() const;  ///< for zmq::poll
  /// Reads the pending events; returns the explanation of the last definitive handshake failure
  /// (the master refused the key, another mechanism, a wrong master key), if any. Other failures
  /// (a connection cut during the handshake, …) may pass: ZeroMQ retries; see last_transient().
  std::optional<std::string> Poll();
  const std::string& last_transient() const { return transient_; }

 private:
  std::unique_ptr<zmq::socket_t> pair_;
  std::string who_, transient_;
};

/// True for endpoints only this host can reach: tcp on 127.0.0.0/8, ::1 or localhost, ipc://,
/// inproc://.
bool IsLoopbackEndpoint(std::string_view endpoint);

}  // namespace pz::service
