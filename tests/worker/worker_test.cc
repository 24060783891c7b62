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
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <mutex>
#include <stdexcept>
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

/// Lease `id` of the job of `spec`: n tasks, task i the genome genome(i) at population index
/// first_index + i.
WorkerMsg LeaseOf(const std::string& spec, uint64_t id, int n,
                  const std::function<opt::Genome(int)>& genome, int first_index = 0) {
  WorkerMsg lease;
  lease.type = WorkerMsg::Type::kBatch;
  lease.batch.lease_id = id;
  lease.batch.job_id = "j1";
  lease.batch.generation = 1;
  lease.batch.context_hash = service::ContentHash(spec);
  lease.batch.deadline_s = 60;
  for (int i = 0; i < n; ++i) {
    lease.batch.indices.push_back(first_index + i);
    lease.batch.genomes.push_back(genome(i));
  }
  return lease;
}

/// Runs a worker in a thread; serves one lease of `tasks` genomes of the spec; returns the
/// worker's result message (or a default one on timeout) once every task is answered.
struct Session {
  ScriptedMaster master;
  std::atomic<bool> stop{false};
  WorkerStats stats;
  std::unique_ptr<Worker> worker;
  std::thread thread;
  explicit Session(int grace_ms, int threads = 1,
                   const job::JobKindRegistry& kinds = kinds::All()) {
    WorkerOptions o;
    o.master = master.endpoint();
    o.threads = threads;
    o.heartbeat_ms = 100;
    o.stop_grace_ms = grace_ms;
    worker = std::make_unique<Worker>(o, kinds);
    thread = std::thread([this] { stats = worker->Run(stop); });
  }
  ~Session() {
    stop = true;
    if (thread.joinable()) thread.join();
  }
  /// Ready → lease → context request → context; returns the context requests seen. The lease's
  /// genome i: `genome(i)`, or 16 bits of i's parity.
  int Lease(const std::string& spec, int tasks,
            const std::function<opt::Genome(int)>& genome = {}) {
    WorkerMsg m;
    EXPECT_TRUE(master.Next(&m));
    EXPECT_EQ(m.type, WorkerMsg::Type::kReady);
    const WorkerMsg lease = LeaseOf(spec, 7, tasks, [&](int i) {
      if (genome) return genome(i);
      opt::Genome g;
      g.bits.assign(16, static_cast<uint8_t>(i & 1));
      return g;
    });
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
    const int n = 1 + k % 13;
    const WorkerMsg lease = LeaseOf(
        spec, 100 + static_cast<uint64_t>(k), n,
        [k](int i) {
          opt::Genome g;
          g.bits.assign(16, 0);
          g.bits[static_cast<size_t>((k + i) % 16)] = 1;
          return g;
        },
        1000 * k);
    tasks_of[lease.batch.lease_id] = n;
    s.master.Send(lease);
  }
  std::set<uint64_t> answered;
  while (answered.size() < tasks_of.size() + 1) {
    WorkerMsg m;
    ASSERT_TRUE(s.master.Next(&m)) << answered.size() << " leases answered";
    if (m.type != WorkerMsg::Type::kResult) continue;
    ASSERT_EQ(m.result.code, service::WireCode::kOk);
    ASSERT_TRUE(answered.insert(m.result.lease_id).second)
        << "lease " << m.result.lease_id << " answered twice";
    if (m.result.lease_id == 7) continue;
    const int k = static_cast<int>(m.result.lease_id - 100);
    ASSERT_EQ(static_cast<int>(m.result.indices.size()), tasks_of.at(m.result.lease_id));
    for (size_t i = 0; i < m.result.indices.size(); ++i) {
      EXPECT_EQ(m.result.indices[i], 1000 * k + static_cast<int>(i));
      opt::Genome g;
      g.bits.assign(16, 0);
      g.bits[static_cast<size_t>((k + static_cast<int>(i)) % 16)] = 1;
      EXPECT_EQ(m.result.results[i].cost, f->Evaluate(g).cost)
          << "lease " << m.result.lease_id << " task " << i;
    }
  }
  s.stop = true;
  s.thread.join();
  int total = 3;
  for (const auto& [id, n] : tasks_of) total += n;
  EXPECT_EQ(s.stats.tasks, static_cast<uint64_t>(total));
}

/// What a LanesFitness was asked: each EvaluateMany group and each Evaluate, as (lease, task).
struct CallLog {
  std::mutex mu;
  std::vector<std::vector<std::pair<int, int>>> groups;
  std::vector<std::pair<int, int>> singles;
};

/// A fitness of `lanes` lanes whose genome is reals = {lease, task}: cost lease·100 + task + 0.25,
/// but task 1 costs NaN and task 4 throws — in Evaluate and in EvaluateMany alike (a group holding
/// task 4 throws as a whole, as a side-by-side simulation would). Both record their calls.
class LanesFitness final : public opt::FitnessFunction {
 public:
  LanesFitness(int lanes, CallLog* log) : lanes_(lanes), log_(log) {}
  static std::pair<int, int> Id(const opt::Genome& g) {
    return {static_cast<int>(g.reals.at(0)), static_cast<int>(g.reals.at(1))};
  }
  static opt::FitnessResult Cost(const opt::Genome& g) {
    const auto [lease, task] = Id(g);
    if (task == 4) throw std::runtime_error("task 4 fails");
    if (task == 1) return {std::numeric_limits<double>::quiet_NaN(), opt::FitnessStatus::kOk, {}};
    return {lease * 100.0 + task + 0.25, opt::FitnessStatus::kOk, {}};
  }
  opt::FitnessResult Evaluate(const opt::Genome& g) const override {
    if (log_) {
      std::lock_guard lock(log_->mu);
      log_->singles.push_back(Id(g));
    }
    return Cost(g);
  }
  int lanes() const override { return lanes_; }
  void EvaluateMany(std::span<const opt::Genome* const> gs,
                    std::span<opt::FitnessResult> out) const override {
    if (log_) {
      std::lock_guard lock(log_->mu);
      auto& group = log_->groups.emplace_back();
      for (const opt::Genome* g : gs) group.push_back(Id(*g));
    }
    for (size_t l = 0; l < gs.size(); ++l) out[l] = Cost(*gs[l]);
  }

 private:
  int lanes_;
  CallLog* log_;
};

/// The synthetic kind, its fitness a LanesFitness.
job::JobKind LanesKind(int lanes, CallLog* log) {
  job::JobKind k = kinds::SyntheticJobKind();
  k.make_fitness = [lanes, log](const job::JobSpec&, std::unique_ptr<opt::FitnessFunction>* f) {
    *f = std::make_unique<LanesFitness>(lanes, log);
    return Status::Ok();
  };
  return k;
}

bool SameResult(const opt::FitnessResult& a, const opt::FitnessResult& b) {
  return std::memcmp(&a.cost, &b.cost, sizeof a.cost) == 0 && a.status == b.status &&
         a.reason == b.reason;
}

// A fitness with lanes: a compute thread takes up to lanes() consecutive tasks of one lease at a
// time (a group never straddles two leases, and starts at a multiple of lanes() in its lease), and
// evaluates them side by side; a genome that throws in a group sends that group one at a time, so
// it gets the single path's penalty and its neighbours their own costs; a NaN gets the penalty
// alone. Every result is EvaluateGuarded's, bit for bit. With lanes() = 1 nothing is grouped.
TEST(Worker, AFitnessWithLanesGetsGroupsOfOneLeaseAndEachGenomeTheSinglePathsResult) {
  for (const int lanes : {3, 1}) {
    for (const int threads : {1, 3}) {
      SCOPED_TRACE(std::to_string(lanes) + " lanes, " + std::to_string(threads) + " threads");
      CallLog log;
      job::JobKindRegistry kinds;
      kinds.Register(LanesKind(lanes, &log));
      Session s(10000, threads, kinds);
      const std::string spec = SleepySpec(0);
      job::JobSpec decoded;
      ASSERT_TRUE(service::DecodeJobSpec(spec, &decoded).ok());
      const double penalty = decoded.limits.penalty_cost;
      auto genome = [](int lease, int task) {
        opt::Genome g;
        g.reals = {static_cast<double>(lease), static_cast<double>(task)};
        return g;
      };
      s.Lease(spec, 5, [&](int i) { return genome(7, i); });  // lease 7, which fetches the context
      std::map<int, int> tasks_of = {{7, 5}};                 // lease id → tasks
      for (int k = 0; k < 60; ++k) {
        const int n = 1 + k % 10;
        const WorkerMsg lease = LeaseOf(spec, 100 + static_cast<uint64_t>(k), n,
                                        [&](int i) { return genome(100 + k, i); });
        tasks_of[100 + k] = n;
        s.master.Send(lease);
      }
      std::set<int> answered;
      while (answered.size() < tasks_of.size()) {
        WorkerMsg m;
        ASSERT_TRUE(s.master.Next(&m)) << answered.size() << " leases answered";
        if (m.type != WorkerMsg::Type::kResult) continue;
        ASSERT_EQ(m.result.code, service::WireCode::kOk);
        const int id = static_cast<int>(m.result.lease_id);
        ASSERT_TRUE(answered.insert(id).second) << "lease " << id << " answered twice";
        ASSERT_EQ(static_cast<int>(m.result.results.size()), tasks_of.at(id));
        for (int i = 0; i < tasks_of.at(id); ++i) {
          const opt::FitnessResult& r = m.result.results[static_cast<size_t>(i)];
          // The single path's result (opt::EvaluateGuarded): the failing genomes the penalty with
          // the reason, their neighbours their own costs.
          opt::FitnessResult want{id * 100.0 + i + 0.25, opt::FitnessStatus::kOk, {}};
          if (i == 4) want = {penalty, opt::FitnessStatus::kError, "exception: task 4 fails"};
          if (i == 1) want = {penalty, opt::FitnessStatus::kError, "non-finite cost nan"};
          EXPECT_TRUE(SameResult(r, want))
              << "lease " << id << " task " << i << ": " << r.cost << " " << r.reason;
        }
      }
      s.stop = true;
      s.thread.join();
      int total = 0;
      for (const auto& [id, n] : tasks_of) total += n;
      EXPECT_EQ(s.stats.tasks, static_cast<uint64_t>(total));
      // The groups: of one lease, consecutive, aligned, each once; the singles: the tasks of the
      // groups of one and of the groups that threw (task 4), each once.
      std::multiset<std::pair<int, int>> want_singles,
          singles(log.singles.begin(), log.singles.end());
      std::multiset<std::pair<int, int>> want_groups, groups;
      for (const auto& [id, n] : tasks_of) {
        for (int first = 0; first < n; first += lanes) {
          const int m = std::min(lanes, n - first);
          if (m > 1) want_groups.insert({id, first});
          if (m == 1 || (first <= 4 && 4 < first + m))
            for (int i = first; i < first + m; ++i) want_singles.insert({id, i});
        }
      }
      for (const auto& g : log.groups) {
        ASSERT_FALSE(g.empty());
        const auto [id, first] = g.front();
        EXPECT_EQ(first % lanes, 0) << "a group of lease " << id << " starts at task " << first;
        EXPECT_EQ(static_cast<int>(g.size()), std::min(lanes, tasks_of.at(id) - first))
            << "lease " << id;
        for (size_t j = 0; j < g.size(); ++j)
          EXPECT_EQ(g[j], std::make_pair(id, first + static_cast<int>(j)))
              << "a group straddles leases or skips";
        groups.insert({id, first});
      }
      EXPECT_EQ(groups, want_groups);
      EXPECT_EQ(singles, want_singles);
      if (lanes == 1) {
        EXPECT_TRUE(log.groups.empty());
      }
    }
  }
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
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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
  EXPECT_EQ(WEXITSTATUS(status), kReturned) << "0: the library ended the process; 1: not reported "
                                               "stuck; 2: waited past the grace; 3: no DISCONNECT";
}

}  // namespace
}  // namespace pz::worker
