// Security of the service (issue 5): CURVE key files and `piezoid keygen`; a master requiring
// CURVE on both endpoints refuses unknown worker and client keys (with a clear error on the
// refused side), serves known ones (a job runs to the end, bit-identical to the in-process run),
// and its traffic is encrypted (a plaintext marker of the job spec crosses a recording TCP proxy
// without CURVE, not with it); the submission limits (data size per job, jobs per client, message
// size); the state directory lock; the warning of a plain master on a non-loopback address.
#include <poll.h>
#include <sys/stat.h>

#include <atomic>
#include <mutex>

#include "service/security.h"
#include "service_harness.h"

namespace pz::testing {
namespace {

using service::CurveKeyPair;

/// Waits (bounded) until `pred` holds.
template <typename F>
bool WaitFor(F pred, std::chrono::milliseconds limit = std::chrono::seconds(20)) {
  const auto until = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < until) {
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return pred();
}

int PortOf(const std::string& endpoint) {
  return std::stoi(endpoint.substr(endpoint.rfind(':') + 1));
}

/// A TCP forwarder on 127.0.0.1 that records every byte it forwards (both directions).
class RecordingProxy {
 public:
  explicit RecordingProxy(int target_port) : target_(target_port) {
    listen_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    int one = 1;
    ::setsockopt(listen_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(listen_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    ::listen(listen_, 16);
    socklen_t len = sizeof a;
    ::getsockname(listen_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] { Run(); });
  }
  ~RecordingProxy() {
    stop_ = true;
    thread_.join();
    for (auto [a, b] : pairs_) {
      ::close(a);
      ::close(b);
    }
    ::close(listen_);
  }
  std::string endpoint() const { return "tcp://127.0.0.1:" + std::to_string(port_); }
  std::string captured() {
    std::lock_guard lock(mu_);
    return bytes_;
  }

 private:
  void Run() {
    char buf[65536];
    while (!stop_) {
      std::vector<pollfd> fds{{listen_, POLLIN, 0}};
      for (auto [a, b] : pairs_) {
        fds.push_back({a, POLLIN, 0});
        fds.push_back({b, POLLIN, 0});
      }
      if (::poll(fds.data(), fds.size(), 50) <= 0) continue;
      if (fds[0].revents & POLLIN) {
        const int in = ::accept4(listen_, nullptr, nullptr, SOCK_CLOEXEC);
        const int out = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        a.sin_port = htons(static_cast<uint16_t>(target_));
        if (in >= 0 && ::connect(out, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) {
          pairs_.push_back({in, out});
        } else {
          if (in >= 0) ::close(in);
          ::close(out);
        }
      }
      std::vector<size_t> dead;
      for (size_t i = 1; i < fds.size(); ++i) {
        if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
        const size_t p = (i - 1) / 2;
        const int from = fds[i].fd;
        const int to = from == pairs_[p].first ? pairs_[p].second : pairs_[p].first;
        const ssize_t n = ::read(from, buf, sizeof buf);
        bool ok = n > 0;
        if (ok) {
          {
            std::lock_guard lock(mu_);
            bytes_.append(buf, static_cast<size_t>(n));
          }
          for (ssize_t done = 0; ok && done < n;) {
            const ssize_t w = ::write(to, buf + done, static_cast<size_t>(n - done));
            ok = w > 0;
            done += w > 0 ? w : 0;
          }
        }
        if (!ok && (dead.empty() || dead.back() != p)) dead.push_back(p);
      }
      for (auto it = dead.rbegin(); it != dead.rend(); ++it) {
        ::close(pairs_[*it].first);
        ::close(pairs_[*it].second);
        pairs_.erase(pairs_.begin() + static_cast<long>(*it));
      }
    }
  }

  int target_, port_ = 0, listen_ = -1;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::vector<std::pair<int, int>> pairs_;
  std::mutex mu_;
  std::string bytes_;
};

/// Key pairs in a temporary folder: keys/NAME.key|pub, allowed public keys in
/// allow/{workers,clients}.
class Keys {
 public:
  explicit Keys(const fs::path& dir) : dir_(dir) {
    fs::create_directories(dir_ / "allow" / "workers");
    fs::create_directories(dir_ / "allow" / "clients");
  }
  /// Makes NAME's pair; allowed on "workers", "clients" or nowhere ("").
  CurveKeyPair Make(const std::string& name, const std::string& allowed_on) {
    CurveKeyPair p;
    EXPECT_TRUE(service::GenerateCurveKeyPair(&p).ok());
    Status s = service::WriteCurveKeyFiles(dir_ / "keys", name, p);
    EXPECT_TRUE(s.ok()) << s.message();
    if (!allowed_on.empty())
      fs::copy_file(pub(name), dir_ / "allow" / allowed_on / (name + ".pub"));
    return p;
  }
  fs::path key(const std::string& name) const { return dir_ / "keys" / (name + ".key"); }
  fs::path pub(const std::string& name) const { return dir_ / "keys" / (name + ".pub"); }
  std::vector<std::string> MasterArgs() const {
    return {"--curve-secret",  key("master").string(),
            "--allow-workers", (dir_ / "allow" / "workers").string(),
            "--allow-clients", (dir_ / "allow" / "clients").string()};
  }

 private:
  fs::path dir_;
};

fs::path TempDir(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() /
      ("pz-sec-" + name + "-" + std::to_string(::getpid()) + "-" + std::to_string(FreePort()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::unique_ptr<Process> CurveWorker(const std::string& endpoint, const Keys& keys,
                                     const std::string& name, const fs::path& log) {
  return std::make_unique<Process>(
      BuildDir() / "worker" / "piezoid-worker",
      std::vector<std::string>{"--master", endpoint, "--threads", "2", "--heartbeat-ms", "100",
                               "--liveness", "5", "--backoff-max-ms", "500", "--log-level", "info",
                               "--curve-secret", keys.key(name).string(), "--master-public",
                               keys.pub("master").string()},
      log);
}

svcclient::ServiceClient CurveClient(const std::string& endpoint, const CurveKeyPair& own,
                                     const CurveKeyPair& master_keys, int timeout_ms = 2000,
                                     int retries = 3) {
  svcclient::ServiceClientOptions o = ClientOptions(endpoint, timeout_ms, retries);
  o.curve = own;
  o.master_public = master_keys.public_z85;
  return svcclient::ServiceClient(o);
}

// ------------------------------------------------------------------ key files

TEST(SecurityKeys, KeygenWritesAPrivateSecretAndAReadablePublicKey) {
  const fs::path d = TempDir("keygen");
  std::string out, err;
  ASSERT_EQ(RunCli({"keygen", "--out", (d / "k").string(), "--name", "alice"}, &out, &err), 0)
      << err;
  struct stat st {};
  ASSERT_EQ(::stat((d / "k" / "alice.key").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  ASSERT_EQ(::stat((d / "k" / "alice.pub").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0644u);
  CurveKeyPair pair;
  Status s = service::LoadCurveSecretFile(d / "k" / "alice.key", &pair);
  ASSERT_TRUE(s.ok()) << s.message();
  std::string pub;
  ASSERT_TRUE(service::LoadCurvePublicFile(d / "k" / "alice.pub", &pub).ok());
  EXPECT_EQ(pub, pair.public_z85);
  EXPECT_NE(out.find(pub), std::string::npos) << out;
  EXPECT_EQ(Slurp(d / "k" / "alice.pub").find("secret-key"), std::string::npos);
  // Never overwritten.
  EXPECT_EQ(RunCli({"keygen", "--out", (d / "k").string(), "--name", "alice"}, &out, &err), 2);
  EXPECT_NE(err.find("exists"), std::string::npos) << err;
  fs::remove_all(d);
}

TEST(SecurityKeys, SecretKeyReadableByOthersIsRefusedNamingTheMode) {
  const fs::path d = TempDir("mode");
  Keys keys(d);
  keys.Make("w", "");
  ::chmod(keys.key("w").c_str(), 0644);
  CurveKeyPair p;
  Status s = service::LoadCurveSecretFile(keys.key("w"), &p);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("mode 0644"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("chmod 600"), std::string::npos) << s.message();
  ::chmod(keys.key("w").c_str(), 0640);
  EXPECT_FALSE(service::LoadCurveSecretFile(keys.key("w"), &p).ok());
  ::chmod(keys.key("w").c_str(), 0400);
  EXPECT_TRUE(service::LoadCurveSecretFile(keys.key("w"), &p).ok());
  // The .pub file is not a secret key.
  ::chmod(keys.pub("w").c_str(), 0600);
  s = service::LoadCurveSecretFile(keys.pub("w"), &p);
  EXPECT_NE(s.message().find("no secret-key"), std::string::npos) << s.message();
  // The CLI says the same, exit code 2.
  ::chmod(keys.key("w").c_str(), 0644);
  std::string err;
  EXPECT_EQ(RunCli({"list", "--curve-secret", keys.key("w").string(), "--master-public",
                    keys.pub("w").string()},
                   nullptr, &err),
            2);
  EXPECT_NE(err.find("mode 0644"), std::string::npos) << err;
  fs::remove_all(d);
}

TEST(SecurityKeys, BadKeyTextNamesTheLine) {
  CurveKeyPair p;
  Status s =
      service::ParseCurveKeyFile("metadata\ncurve\n    public-key = \"short\"\n", "x.pub", &p);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("x.pub:3: public-key"), std::string::npos) << s.message();
  s = service::ParseCurveKeyFile("hello\n", "y.pub", &p);
  EXPECT_NE(s.message().find("not a CURVE key file"), std::string::npos) << s.message();
  CurveKeyPair a, b;
  ASSERT_TRUE(service::GenerateCurveKeyPair(&a).ok());
  ASSERT_TRUE(service::GenerateCurveKeyPair(&b).ok());
  s = service::ParseCurveKeyFile(
      "public-key = \"" + a.public_z85 + "\"\nsecret-key = \"" + b.secret_z85 + "\"\n", "z.key",
      &p);
  EXPECT_NE(s.message().find("does not belong"), std::string::npos) << s.message();
  ASSERT_TRUE(
      service::ParseCurveKeyFile("secret-key = \"" + a.secret_z85 + "\"\n", "s.key", &p).ok());
  EXPECT_EQ(p.public_z85, a.public_z85);  // derived
}

TEST(SecurityKeys, LoopbackEndpoints) {
  EXPECT_TRUE(service::IsLoopbackEndpoint("tcp://127.0.0.1:5555"));
  EXPECT_TRUE(service::IsLoopbackEndpoint("tcp://127.0.1.1:*"));
  EXPECT_TRUE(service::IsLoopbackEndpoint("tcp://localhost:5555"));
  EXPECT_TRUE(service::IsLoopbackEndpoint("tcp://[::1]:5555"));
  EXPECT_TRUE(service::IsLoopbackEndpoint("ipc:///tmp/x"));
  EXPECT_FALSE(service::IsLoopbackEndpoint("tcp://*:5555"));
  EXPECT_FALSE(service::IsLoopbackEndpoint("tcp://0.0.0.0:5555"));
  EXPECT_FALSE(service::IsLoopbackEndpoint("tcp://10.1.2.3:5555"));
  EXPECT_FALSE(service::IsLoopbackEndpoint("tcp://eth0:5555"));
  EXPECT_FALSE(service::IsLoopbackEndpoint("tcp://[::]:5555"));
}

// ------------------------------------------------------------------ CURVE on the service

/// The same job through recording proxies on both endpoints, with or without CURVE: it runs to
/// the end bit-identical to the in-process reference, and the spec's marker crosses the wire in
/// clear only without CURVE.
void RunThroughProxies(bool curve) {
  const fs::path d = TempDir(curve ? "curve-run" : "plain-run");
  Keys keys(d);
  CurveKeyPair master_keys, client_keys;
  if (curve) {
    master_keys = keys.Make("master", "");
    keys.Make("worker1", "workers");
    client_keys = keys.Make("alice", "clients");
  }
  Cluster cluster(curve ? "curve" : "plain",
                  curve ? keys.MasterArgs() : std::vector<std::string>{});
  RecordingProxy to_workers(PortOf(cluster.worker_endpoint())),
      to_clients(PortOf(cluster.client_endpoint()));
  std::unique_ptr<Process> worker;
  if (curve) {
    worker = CurveWorker(to_workers.endpoint(), keys, "worker1", d / "worker.log");
  } else {
    worker = std::make_unique<Process>(
        BuildDir() / "worker" / "piezoid-worker",
        std::vector<std::string>{"--master", to_workers.endpoint(), "--threads", "2",
                                 "--heartbeat-ms", "100", "--liveness", "5", "--log-level", "warn"},
        d / "worker.log");
  }
  job::JobSpec spec = SyntheticSpec(41, 16, 6);
  const std::string marker = "PZ-MARKER-plaintext-7f3a9c";
  spec.name = marker;
  auto c = curve ? CurveClient(to_clients.endpoint(), client_keys, master_keys)
                 : svcclient::ServiceClient(ClientOptions(to_clients.endpoint(), 2000, 3));
  svcclient::SubmitResult r;
  Status s = c.Submit(spec, &r);
  ASSERT_TRUE(s.ok()) << s.message();
  service::JobInfo info;
  s = c.WaitFinal(r.job_id, std::chrono::seconds(60), &info);
  if (!s.ok()) {
    std::vector<service::JobInfo> jobs;
    int workers = -1;
    (void)c.List(&jobs, &workers);
    FAIL() << s.message() << "\nworkers " << workers << ", worker proxy bytes "
           << to_workers.captured().size() << ", worker running " << worker->running() << "\n"
           << Slurp(cluster.dir() / "master.log") << Slurp(d / "worker.log");
  }
  EXPECT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  std::vector<service::ScoredGenome> best;
  std::vector<service::GenerationRecord> log;
  ASSERT_TRUE(c.Fetch(r.job_id, 3, &best, &log).ok());
  ExpectSameRun(Reference(spec), best, log);
  const std::string clients = to_clients.captured(), workers = to_workers.captured();
  EXPECT_GT(clients.size(), 200u);
  EXPECT_GT(workers.size(), 200u);
  if (curve) {
    EXPECT_EQ(clients.find(marker), std::string::npos)
        << "the spec crossed the client endpoint in clear";
    EXPECT_EQ(workers.find(marker), std::string::npos)
        << "the spec crossed the worker endpoint in clear";
    EXPECT_NE(clients.find("CURVE"), std::string::npos);  // the ZMTP greeting names the mechanism
  } else {
    EXPECT_NE(clients.find(marker), std::string::npos) << "the proxy did not see the submission";
    EXPECT_NE(workers.find(marker), std::string::npos) << "the proxy did not see the job context";
  }
  worker.reset();
  fs::remove_all(d);
}

TEST(SecurityCurve, PlainTrafficCarriesTheSpecInClear) { RunThroughProxies(false); }

TEST(SecurityCurve, KnownKeysAreServedAndTrafficIsEncrypted) { RunThroughProxies(true); }

TEST(SecurityCurve, UnknownKeysAreRefusedOnBothEndpoints) {
  const fs::path d = TempDir("refuse");
  Keys keys(d);
  const CurveKeyPair master_keys = keys.Make("master", "");
  const CurveKeyPair alice = keys.Make("alice", "clients");
  const CurveKeyPair mallory = keys.Make("mallory", "");
  keys.Make("stranger", "");
  keys.Make("w-client-key", "clients");  // a client key is not a worker key
  Cluster cluster("refuse", keys.MasterArgs());
  // Client endpoint: an unknown key gets a clear error at once (no retries), exit code 3.
  {
    auto c = CurveClient(cluster.client_endpoint(), mallory, master_keys, 3000, 3);
    std::vector<service::JobInfo> jobs;
    const auto t0 = std::chrono::steady_clock::now();
    Status s = c.List(&jobs);
    EXPECT_EQ(s.code(), StatusCode::kUnavailable);
    EXPECT_NE(s.message().find("refused this client's CURVE key"), std::string::npos)
        << s.message();
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(2900));
    std::string err;
    EXPECT_EQ(RunCli({"list", "--master", cluster.client_endpoint(), "--curve-secret",
                      keys.key("mallory").string(), "--master-public", keys.pub("master").string()},
                     nullptr, &err),
              3);
    EXPECT_NE(err.find("refused this client's CURVE key"), std::string::npos) << err;
  }
  // A client without keys: told that the master may require CURVE keys.
  {
    std::string err;
    EXPECT_EQ(RunCli({"list", "--master", cluster.client_endpoint(), "--timeout-ms", "500",
                      "--retries", "1"},
                     nullptr, &err),
              3);
    EXPECT_NE(err.find("CURVE"), std::string::npos) << err;
  }
  // The allowed client is served (the same key pair files through the environment).
  {
    ::setenv("PIEZOID_CURVE_SECRET", keys.key("alice").c_str(), 1);
    ::setenv("PIEZOID_MASTER_PUBLIC", keys.pub("master").c_str(), 1);
    std::string out, err;
    EXPECT_EQ(RunCli({"list", "--master", cluster.client_endpoint()}, &out, &err), 0) << err;
    ::unsetenv("PIEZOID_CURVE_SECRET");
    ::unsetenv("PIEZOID_MASTER_PUBLIC");
    EXPECT_NE(out.find("0 workers"), std::string::npos) << out;
  }
  // Worker endpoint: unknown keys (and a key allowed only as a client) never join; the worker
  // says why.
  auto stranger = CurveWorker(cluster.worker_endpoint(), keys, "stranger", d / "stranger.log");
  auto misplaced =
      CurveWorker(cluster.worker_endpoint(), keys, "w-client-key", d / "misplaced.log");
  EXPECT_TRUE(WaitFor([&] {
    const std::string a = Slurp(d / "stranger.log"), b = Slurp(d / "misplaced.log");
    return a.find("refused this worker's CURVE key") != std::string::npos &&
           b.find("refused this worker's CURVE key") != std::string::npos;
  })) << Slurp(d / "stranger.log")
      << Slurp(d / "misplaced.log");
  auto c = CurveClient(cluster.client_endpoint(), alice, master_keys);
  std::vector<service::JobInfo> jobs;
  int workers = -1;
  ASSERT_TRUE(c.List(&jobs, &workers).ok());
  EXPECT_EQ(workers, 0);
  EXPECT_NE(Slurp(cluster.dir() / "master.log").find("refused workers"), std::string::npos);
  // A key added to the allowed directory is accepted without a restart.
  fs::copy_file(keys.pub("stranger"), d / "allow" / "workers" / "stranger.pub");
  EXPECT_TRUE(WaitFor([&] { return c.List(&jobs, &workers).ok() && workers == 1; }));
  stranger.reset();
  misplaced.reset();
  fs::remove_all(d);
}

TEST(SecurityCurve, MasterRefusesToStartWithBadKeyOptions) {
  const fs::path d = TempDir("badopts");
  Keys keys(d);
  keys.Make("master", "");
  ::chmod(keys.key("master").c_str(), 0604);
  const auto run = [&](std::vector<std::string> args) {
    args.insert(args.end(), {"--workers", "tcp://127.0.0.1:*", "--clients", "tcp://127.0.0.1:*",
                             "--state-dir", (d / "state").string()});
    std::string cmd = "'" + (BuildDir() / "master" / "piezoid-master").string() + "'";
    for (const auto& a : args) cmd += " '" + a + "'";
    cmd += " >'" + (d / "out.log").string() + "' 2>&1";
    const int st = std::system(cmd.c_str());
    return std::pair(WIFEXITED(st) ? WEXITSTATUS(st) : -1, Slurp(d / "out.log"));
  };
  auto [code, log] = run(keys.MasterArgs());
  EXPECT_EQ(code, 2);
  EXPECT_NE(log.find("mode 0604"), std::string::npos) << log;
  ::chmod(keys.key("master").c_str(), 0600);
  std::tie(code, log) = run({"--curve-secret", keys.key("master").string()});
  EXPECT_EQ(code, 2);
  EXPECT_NE(log.find("--allow-workers"), std::string::npos) << log;
  std::tie(code, log) =
      run({"--curve-secret", keys.key("master").string(), "--allow-workers",
           (d / "nowhere").string(), "--allow-clients", (d / "allow" / "clients").string()});
  EXPECT_NE(code, 0);
  EXPECT_NE(log.find("--allow-workers"), std::string::npos) << log;
  EXPECT_NE(log.find("nowhere"), std::string::npos) << log;
  fs::remove_all(d);
}

// ------------------------------------------------------------------ limits

TEST(SecurityLimits, SpecAboveTheDataSizePerJobIsRefusedNamingTheLimit) {
  Cluster cluster("specsize", {"--max-spec-bytes", "4096"});
  auto c = cluster.Client();
  job::JobSpec spec = SyntheticSpec(1, 8, 2);
  spec.name = std::string(5000, 'n');
  svcclient::SubmitResult r;
  std::vector<job::FieldViolation> v;
  Status s = c.Submit(spec, &r, &v);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << s.message();
  EXPECT_NE(s.message().find("--max-spec-bytes = 4096"), std::string::npos) << s.message();
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].field, "spec");
  spec.name = "small";
  EXPECT_TRUE(c.Submit(spec, &r).ok());
}

TEST(SecurityLimits, RunningJobsPerClientAreLimited) {
  Cluster cluster("perclient", {"--max-jobs-per-client", "1"});  // no workers: jobs stay running
  auto c = cluster.Client();
  svcclient::SubmitResult a, b;
  ASSERT_TRUE(c.Submit(SyntheticSpec(1, 8, 2), &a, nullptr, "tok-a").ok());
  Status s = c.Submit(SyntheticSpec(2, 8, 2), &b);
  EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.message();
  EXPECT_NE(s.message().find("--max-jobs-per-client"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("already has 1 running"), std::string::npos) << s.message();
  // A retry of the accepted submission is still answered.
  svcclient::SubmitResult again;
  ASSERT_TRUE(c.Submit(SyntheticSpec(1, 8, 2), &again, nullptr, "tok-a").ok());
  EXPECT_EQ(again.job_id, a.job_id);
  EXPECT_TRUE(again.existed);
  // Once the first has ended, another is accepted.
  ASSERT_TRUE(c.Cancel(a.job_id).ok());
  ASSERT_TRUE(c.WaitFinal(a.job_id, std::chrono::seconds(10)).ok());
  EXPECT_TRUE(c.Submit(SyntheticSpec(2, 8, 2), &b).ok());
}

TEST(SecurityLimits, WithCurveTheLimitIsPerClientKey) {
  const fs::path d = TempDir("perkey");
  Keys keys(d);
  const CurveKeyPair m = keys.Make("master", ""), alice = keys.Make("alice", "clients"),
                     bob = keys.Make("bob", "clients");
  auto args = keys.MasterArgs();
  args.insert(args.end(), {"--max-jobs-per-client", "1"});
  Cluster cluster("perkey", args);
  auto ca = CurveClient(cluster.client_endpoint(), alice, m);
  auto cb = CurveClient(cluster.client_endpoint(), bob, m);
  svcclient::SubmitResult r;
  ASSERT_TRUE(ca.Submit(SyntheticSpec(1, 8, 2), &r).ok());
  Status s = ca.Submit(SyntheticSpec(2, 8, 2), &r);
  EXPECT_NE(s.message().find("client clients:alice already has 1 running"), std::string::npos)
      << s.message();
  s = cb.Submit(SyntheticSpec(2, 8, 2), &r);
  EXPECT_TRUE(s.ok()) << s.message();
  fs::remove_all(d);
}

TEST(SecurityLimits, MessageSizeIsRefusedNamingTheLimit) {
  // Above the client's own limit: refused before sending.
  svcclient::ServiceClientOptions o =
      ClientOptions("tcp://127.0.0.1:" + std::to_string(FreePort()), 200, 1);
  o.max_message_bytes = 2048;
  svcclient::ServiceClient c(o);
  job::JobSpec spec = SyntheticSpec(1, 8, 2);
  spec.name = std::string(4096, 'n');
  svcclient::SubmitResult r;
  Status s = c.Submit(spec, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("max_message_bytes = 2048"), std::string::npos) << s.message();
  // Above the master's: the master drops the connection (ZMQ_MAXMSGSIZE) and keeps serving; the
  // client names the limit it may have hit.
  Cluster cluster("msgsize", {"--max-message-bytes", "1048576", "--max-spec-bytes", "4194304"});
  spec.name = std::string(1100000, 'n');
  auto big = cluster.Client(500, 1);
  s = big.Submit(spec, &r);
  EXPECT_EQ(s.code(), StatusCode::kUnavailable);
  EXPECT_NE(s.message().find("--max-message-bytes"), std::string::npos) << s.message();
  std::vector<service::JobInfo> jobs;
  EXPECT_TRUE(cluster.Client().List(&jobs).ok());
}

// ------------------------------------------------------------------ master start-up

TEST(SecurityMaster, SecondMasterOnTheSameStateDirectoryRefusesToStart) {
  Cluster cluster("lock");
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(cluster.Client().List(&jobs).ok());  // the first master is up
  Process second(BuildDir() / "master" / "piezoid-master",
                 {"--workers", "tcp://127.0.0.1:*", "--clients", "tcp://127.0.0.1:*", "--state-dir",
                  (cluster.dir() / "state").string()},
                 cluster.dir() / "second.log");
  EXPECT_TRUE(WaitFor([&] { return !second.running(); }, std::chrono::seconds(10)));
  const std::string log = Slurp(cluster.dir() / "second.log");
  EXPECT_NE(log.find("in use by another piezoid-master"), std::string::npos) << log;
  EXPECT_TRUE(cluster.Client().List(&jobs).ok());  // the first one still serves
}

TEST(SecurityMaster, PlainMasterOnANonLoopbackAddressWarns) {
  const fs::path d = TempDir("warn");
  Process m(
      BuildDir() / "master" / "piezoid-master",
      {"--workers", "tcp://0.0.0.0:" + std::to_string(FreePort()), "--clients",
       "tcp://127.0.0.1:" + std::to_string(FreePort()), "--state-dir", (d / "state").string()},
      d / "master.log");
  EXPECT_TRUE(
      WaitFor([&] { return Slurp(d / "master.log").find("workers on") != std::string::npos; }));
  const std::string log = Slurp(d / "master.log");
  EXPECT_NE(log.find("reachable from other hosts and CURVE is off"), std::string::npos) << log;
  const size_t first = log.find("reachable from other hosts");
  EXPECT_EQ(log.find("reachable from other hosts", first + 1), std::string::npos)
      << log;  // not the loopback one
  m.Kill(SIGTERM);
  fs::remove_all(d);
}

TEST(SecurityCli, SubmitWithAClientTokenIsIdempotent) {
  Cluster cluster("token");
  const fs::path spec = cluster.dir() / "job.json";
  std::ofstream(spec) << service::JobSpecToJson(SyntheticSpec(5, 8, 2));
  std::string a, b, err;
  ASSERT_EQ(RunCli({"submit", spec.string(), "--master", cluster.client_endpoint(),
                    "--client-token", "t1"},
                   &a, &err),
            0)
      << err;
  ASSERT_EQ(RunCli({"submit", spec.string(), "--master", cluster.client_endpoint(),
                    "--client-token", "t1"},
                   &b, &err),
            0)
      << err;
  EXPECT_EQ(a, b);
  EXPECT_NE(err.find("already been submitted"), std::string::npos) << err;
  ASSERT_EQ(RunCli({"submit", spec.string(), "--master", cluster.client_endpoint(),
                    "--client-token", "t2"},
                   &b, &err),
            0);
  EXPECT_NE(a, b);
}

}  // namespace
}  // namespace pz::testing
