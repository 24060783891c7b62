// The worker engine against a scripted master (a ROUTER socket speaking the wire codec): it
// announces itself, fetches a job context once by hash, evaluates a lease; and when asked to stop
// while an evaluation will not end within stop_grace_ms, Run returns with the thread reported
// stuck instead of ending the process (the library never does; piezoid-worker exits itself).
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <zmq.hpp>

#include "kinds/kinds.h"
#include "service/wire_codec.h"
#include "worker/worker.h"

namespace pz::worker {
namespace {

using namespace std::chrono_literals;
using service::WorkerMsg;

/// A master of one worker on a loopback port the system picks.
class ScriptedMaster {
 public:
  ScriptedMaster() : router_(ctx_, zmq::socket_type::router) {
    router_.set(zmq::sockopt::linger, 0);
    router_.bind("tcp://127.0.0.1:*");
    endpoint_ = router_.get(zmq::sockopt::last_endpoint);
  }
  const std::string& endpoint() const { return endpoint_; }

  /// The next message of a type other than heartbeat (bounded wait); false on timeout.
  bool Next(WorkerMsg* m, std::chrono::milliseconds timeout = 5000ms) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < until) {
      zmq::pollitem_t items[] = {{router_.handle(), 0, ZMQ_POLLIN, 0}};
      zmq::poll(items, 1, 50ms);
      if (!(items[0].revents & ZMQ_POLLIN)) continue;
      zmq::message_t id, body;
      if (!router_.recv(id) || !router_.recv(body)) return false;
      peer_ = id.to_string();
      if (!service::DecodeWorkerToMaster(body.to_string_view(), m).ok()) return false;
      if (m->type != WorkerMsg::Type::kHeartbeat) return true;
    }
    return false;
  }
  void Send(const WorkerMsg& m) {
    router_.send(zmq::buffer(peer_), zmq::send_flags::sndmore);
    router_.send(zmq::buffer(service::EncodeMasterToWorker(m)));
  }

 private:
  zmq::context_t ctx_;
  zmq::socket_t router_;
  std::string endpoint_, peer_;
};

/// A synthetic job whose every evaluation sleeps `sleep_ms`.
std::string SleepySpec(double sleep_ms) {
  job::JobSpec s;
  job::SyntheticProblem p;
  p.cost = job::SyntheticProblem::Cost::kFunction;
  p.genome_bits = 16;
  p.sleep_ms = sleep_ms;
  s.problem = p;
  s.ga = job::GaSettings{};
  return service::EncodeJobSpec(s);
}

/// Runs a worker in a thread; serves one lease of `tasks` genomes of the spec; returns the
/// worker's result message (or a default one on timeout) once every task is answered.
struct Session {
  ScriptedMaster master;
  std::atomic<bool> stop{false};
  WorkerStats stats;
  std::unique_ptr<Worker> worker;
  std::thread thread;
  explicit Session(int grace_ms, int threads = 1) {
    WorkerOptions o;
    o.master = master.endpoint();
    o.threads = threads;
    o.heartbeat_ms = 100;
    o.stop_grace_ms = grace_ms;
    worker = std::make_unique<Worker>(o, kinds::All());
    thread = std::thread([this] { stats = worker->Run(stop); });
  }
  ~Session() {
    stop = true;
    if (thread.joinable()) thread.join();
  }
  /// Ready → lease → context request → context; returns the context requests seen.
  int Lease(const std::string& spec, int tasks) {
    WorkerMsg m;
    EXPECT_TRUE(master.Next(&m));
    EXPECT_EQ(m.type, WorkerMsg::Type::kReady);
    WorkerMsg lease;
    lease.type = WorkerMsg::Type::kBatch;
    lease.batch.lease_id = 7;
    lease.batch.job_id = "j1";
    lease.batch.generation = 1;
    lease.batch.context_hash = service::ContentHash(spec);
    lease.batch.deadline_s = 60;
    for (int i = 0; i < tasks; ++i) {
      opt::Genome g;
      g.bits.assign(16, static_cast<uint8_t>(i & 1));
      lease.batch.indices.push_back(i);
      lease.batch.genomes.push_back(g);
    }
    master.Send(lease);
    EXPECT_TRUE(master.Next(&m));
    EXPECT_EQ(m.type, WorkerMsg::Type::kContextRequest);
    EXPECT_EQ(m.context_hash, lease.batch.context_hash);
    WorkerMsg context;
    context.type = WorkerMsg::Type::kContext;
    context.context_hash = lease.batch.context_hash;
    context.context_spec = spec;
    master.Send(context);
    return 1;
  }
};

TEST(Worker, EvaluatesALeaseAfterFetchingItsContextOnce) {
  Session s(10000);
  s.Lease(SleepySpec(0), 5);
  WorkerMsg m;
  ASSERT_TRUE(s.master.Next(&m));
  ASSERT_EQ(m.type, WorkerMsg::Type::kResult);
  EXPECT_EQ(m.result.lease_id, 7u);
  EXPECT_EQ(m.result.code, service::WireCode::kOk);
  ASSERT_EQ(m.result.indices, (std::vector<int>{0, 1, 2, 3, 4}));
  // The same costs as the kind's own fitness.
  job::JobSpec spec;
  ASSERT_TRUE(service::DecodeJobSpec(SleepySpec(0), &spec).ok());
  std::unique_ptr<opt::FitnessFunction> f;
  ASSERT_TRUE(kinds::All().MakeFitness(spec, &f).ok());
  for (int i = 0; i < 5; ++i) {
    opt::Genome g;
    g.bits.assign(16, static_cast<uint8_t>(i & 1));
    EXPECT_EQ(m.result.results[i].cost, f->Evaluate(g).cost) << i;
  }
  s.stop = true;
  s.thread.join();
  EXPECT_EQ(s.stats.tasks, 5u);
  EXPECT_EQ(s.stats.contexts_fetched, 1u);
  EXPECT_EQ(s.stats.stuck_threads, 0);
}

// The threads handed a lease take its tasks one at a time: many leases, of fewer and more tasks
// than the worker has threads, sent back to back, are each answered once with every result.
TEST(Worker, ManySmallLeasesOnManyThreadsAreEachAnsweredOnceAndWhole) {
  Session s(10000, /*threads=*/8);
  const std::string spec = SleepySpec(0);
  s.Lease(spec, 3);  // lease 7, which fetches the context
  job::JobSpec decoded;
  ASSERT_TRUE(service::DecodeJobSpec(spec, &decoded).ok());
  std::unique_ptr<opt::FitnessFunction> f;
  ASSERT_TRUE(kinds::All().MakeFitness(decoded, &f).ok());
  constexpr int kLeases = 400;
  std::map<uint64_t, int> tasks_of;  // lease id → tasks
  for (int k = 0; k < kLeases; ++k) {
    WorkerMsg lease;
    lease.type = WorkerMsg::Type::kBatch;
    lease.batch.lease_id = 100 + static_cast<uint64_t>(k);
    lease.batch.job_id = "j1";
    lease.batch.generation = 1;
    lease.batch.context_hash = service::ContentHash(spec);
    lease.batch.deadline_s = 60;
    const int n = 1 + k % 13;
    for (int i = 0; i < n; ++i) {
      opt::Genome g;
      g.bits.assign(16, 0);
      g.bits[static_cast<size_t>((k + i) % 16)] = 1;
      lease.batch.indices.push_back(1000 * k + i);
      lease.batch.genomes.push_back(g);
    }
    tasks_of[lease.batch.lease_id] = n;
    s.master.Send(lease);
  }
  std::set<uint64_t> answered;
  while (answered.size() < tasks_of.size() + 1) {
    WorkerMsg m;
    ASSERT_TRUE(s.master.Next(&m)) << answered.size() << " leases answered";
    if (m.type != WorkerMsg::Type::kResult) continue;
    ASSERT_EQ(m.result.code, service::WireCode::kOk);
    ASSERT_TRUE(answered.insert(m.result.lease_id).second) << "lease " << m.result.lease_id << " answered twice";
    if (m.result.lease_id == 7) continue;
    const int k = static_cast<int>(m.result.lease_id - 100);
    ASSERT_EQ(static_cast<int>(m.result.indices.size()), tasks_of.at(m.result.lease_id));
    for (size_t i = 0; i < m.result.indices.size(); ++i) {
      EXPECT_EQ(m.result.indices[i], 1000 * k + static_cast<int>(i));
      opt::Genome g;
      g.bits.assign(16, 0);
      g.bits[static_cast<size_t>((k + static_cast<int>(i)) % 16)] = 1;
      EXPECT_EQ(m.result.results[i].cost, f->Evaluate(g).cost) << "lease " << m.result.lease_id << " task " << i;
    }
  }
  s.stop = true;
  s.thread.join();
  int total = 3;
  for (const auto& [id, n] : tasks_of) total += n;
  EXPECT_EQ(s.stats.tasks, static_cast<uint64_t>(total));
}

/// The stop scenario, in a child process: its exit status says what happened (kReturned: Run
/// came back with the thread reported stuck, in time, after saying goodbye). Run in a child so
/// that a library that ends the process (as it once did, with std::_Exit(0)) fails the test
/// instead of ending the test binary with status 0.
constexpr int kReturned = 42;
int StuckStopScenario() {
  Session s(200);
  s.Lease(SleepySpec(2500), 1);        // one evaluation of 2.5 s
  std::this_thread::sleep_for(300ms);  // it is running now
  const auto t0 = std::chrono::steady_clock::now();
  s.stop = true;
  s.thread.join();
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  WorkerMsg m;
  const bool goodbye = s.master.Next(&m, 2000ms) && m.type == WorkerMsg::Type::kDisconnect;
  if (s.stats.stuck_threads != 1) return 1;
  if (waited >= 2.0) return 2;  // it waited for the evaluation instead of the grace period
  if (!goodbye) return 3;
  s.worker.reset();  // leaves the engine to the stuck thread, which ends 2.5 s after it began
  std::this_thread::sleep_for(2500ms);
  return kReturned;
}

TEST(Worker, AnEvaluationThatOutlastsTheGraceIsReportedNotKilled) {
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) ::_exit(StuckStopScenario());
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "the scenario died of a signal";
  EXPECT_EQ(WEXITSTATUS(status), kReturned)
      << "0: the library ended the process; 1: not reported stuck; 2: waited past the grace; 3: no DISCONNECT";
}

}  // namespace
}  // namespace pz::worker
