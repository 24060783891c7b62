#include "master/dispatcher.h"

#include <algorithm>
#include <cmath>

namespace pz::master {

using service::Duration;
using service::TimePoint;

Dispatcher::Dispatcher(DispatchOptions options, uint64_t first_lease_id)
    : options_(options), next_lease_id_(first_lease_id) {
  options_.max_batch = std::max(1, options_.max_batch);
  options_.leases_per_worker = std::max(1, options_.leases_per_worker);
}

void Dispatcher::StartGeneration(const std::string& job_id, uint64_t generation, int tasks,
                                 double task_timeout_s, int quarantine_after) {
  JobTasks& j = jobs_[job_id];
  const uint64_t served = j.last_served;
  const int in_flight = j.in_flight;  // stale leases of the previous generation still held
  j = JobTasks{};
  j.generation = generation;
  j.tasks = j.remaining = tasks;
  j.in_flight = in_flight;
  j.task_timeout_s = task_timeout_s;
  j.quarantine_after = std::max(1, quarantine_after);
  j.done.assign(tasks, 0);
  j.struck_by.assign(tasks, {});
  for (int i = 0; i < tasks; ++i) j.pending.push_back(i);
  j.last_served = served;
}

void Dispatcher::RemoveJob(const std::string& job_id) {
  for (auto it = leases_.begin(); it != leases_.end();) {
    if (it->second.job_id == job_id) {
      Release(it->second);
      it = leases_.erase(it);
    } else {
      ++it;
    }
  }
  jobs_.erase(job_id);
}

int Dispatcher::remaining(const std::string& job_id) const {
  auto it = jobs_.find(job_id);
  return it == jobs_.end() ? 0 : it->second.remaining;
}

bool Dispatcher::MarkDone(const std::string& job_id, uint64_t generation, int position) {
  auto it = jobs_.find(job_id);
  if (it == jobs_.end()) return false;
  JobTasks& j = it->second;
  if (j.generation != generation || position < 0 || position >= j.tasks || j.done[position])
    return false;
  j.done[position] = 1;
  --j.remaining;
  return true;
}

void Dispatcher::AddWorker(const std::string& id, int threads) {
  auto [it, inserted] = workers_.try_emplace(id);
  if (!inserted) total_threads_ -= it->second.threads;
  it->second.threads = std::max(1, threads);
  total_threads_ += it->second.threads;
}

void Dispatcher::RemoveWorker(const std::string& id, bool lost, TimePoint now) {
  std::vector<Lease> taken;
  for (auto it = leases_.begin(); it != leases_.end();) {
    if (it->second.worker == id) {
      taken.push_back(std::move(it->second));
      it = leases_.erase(it);
    } else {
      ++it;
    }
  }
  Departure d;
  d.worker = id;
  d.at = now;
  for (const Lease& l : taken) {
    d.held_jobs.emplace_back(l.job_id, l.generation);
    d.held.push_back(l.positions);
  }
  for (const Lease& l : taken) {
    Release(l);
    if (lost && l.solo && !l.positions.empty()) {  // it died running this task alone
      d.job_id = l.job_id;
      d.generation = l.generation;
      d.position = l.positions[0];
      candidates_.push_back(d);
    }
    (void)Requeue(l, lost ? RequeueCause::kWorkerLost : RequeueCause::kTransient, now);
  }
  departures_.push_back(d);
  while (!departures_.empty() && now - departures_.front().at > 2 * quiet_window())
    departures_.pop_front();
  auto w = workers_.find(id);
  if (w != workers_.end()) {
    total_threads_ -= w->second.threads;
    workers_.erase(w);
  }
}

bool Dispatcher::Departure::Held(const std::string& job, uint64_t gen, int pos) const {
  for (size_t i = 0; i < held.size(); ++i)
    if (held_jobs[i].first == job && held_jobs[i].second == gen &&
        std::find(held[i].begin(), held[i].end(), pos) != held[i].end())
      return true;
  return false;
}

Duration Dispatcher::quiet_window() const {
  return std::chrono::duration_cast<Duration>(
      std::chrono::duration<double>(std::max(0.0, options_.quiet_window_s)));
}

std::optional<Quarantined> Dispatcher::Strike(const std::string& job_id, uint64_t generation,
                                              int position, const std::string& worker) {
  auto it = jobs_.find(job_id);
  if (it == jobs_.end() || it->second.generation != generation) return std::nullopt;
  JobTasks& j = it->second;
  if (position < 0 || position >= j.tasks || j.done[position]) return std::nullopt;
  auto& by = j.struck_by[position];
  if (std::find(by.begin(), by.end(), worker) == by.end()) by.push_back(worker);
  const int strikes = static_cast<int>(by.size());
  if (strikes < j.quarantine_after) return std::nullopt;
  j.done[position] = 1;
  --j.remaining;
  std::erase(j.suspects, position);
  std::erase(j.pending, position);
  return Quarantined{job_id, generation, position, strikes};
}

std::vector<Quarantined> Dispatcher::ConfirmStrikes(TimePoint now) {
  std::vector<Quarantined> out;
  const Duration window = quiet_window();
  while (!candidates_.empty() && now - candidates_.front().at >= window) {
    const Departure c = std::move(candidates_.front());
    candidates_.pop_front();
    // Another worker, not running this same task, left around the death: the cluster was not
    // healthy then (churn, a partition), so the death says nothing about the task.
    bool isolated = true;
    for (const Departure& d : departures_) {
      if (d.worker == c.worker || d.at < c.at - window || d.at > c.at + window) continue;
      if (d.Held(c.job_id, c.generation, c.position)) continue;  // the task's own doing
      isolated = false;
      break;
    }
    if (!isolated) continue;
    if (auto q = Strike(c.job_id, c.generation, c.position, c.worker)) out.push_back(*q);
  }
  return out;
}

bool Dispatcher::HasRoom(const WorkerSlot& w) const {
  if (w.exclusive) return false;
  return w.leases < options_.leases_per_worker || w.items < w.threads;
}

int Dispatcher::BatchSize(const WorkerSlot& w, const JobTasks& j) const {
  const int pending = static_cast<int>(j.pending.size());
  long rounds = 1;
  if (w.item_s > 0)
    rounds = std::max(1L, std::lround(std::floor(options_.target_batch_s / w.item_s)));
  long target = std::min<long>(options_.max_batch, rounds * w.threads);
  long guided = static_cast<long>(
      std::ceil(static_cast<double>(pending) * w.threads / (2.0 * std::max(1, total_threads_))));
  long size = std::min(target, std::max<long>(guided, w.threads));
  size = std::min<long>({size, pending, options_.max_batch});
  return static_cast<int>(std::max(1L, size));
}

Lease Dispatcher::Grant(const std::string& job_id, JobTasks& job, const std::string& worker_id,
                        WorkerSlot& worker, std::vector<int> positions, bool solo, TimePoint now) {
  Lease l;
  l.id = next_lease_id_++;
  l.worker = worker_id;
  l.job_id = job_id;
  l.generation = job.generation;
  l.positions = std::move(positions);
  l.solo = solo;
  const int n = static_cast<int>(l.positions.size());
  l.rounds = (n + worker.threads - 1) / worker.threads;
  worker.leases += 1;
  worker.items += n;
  worker.exclusive = solo;
  worker.last_served = job.last_served = ++serve_counter_;
  job.in_flight += n;
  const double rounds = std::ceil(static_cast<double>(worker.items) / worker.threads);
  l.granted = now;
  l.deadline = now + std::chrono::duration_cast<Duration>(
                         std::chrono::duration<double>(rounds * job.task_timeout_s));
  leases_.emplace(l.id, l);
  return l;
}

std::optional<Lease> Dispatcher::NextLease(TimePoint now) {
  // Suspects first, each alone on an idle worker (served longest ago); with no idle worker, the
  // least loaded one gets no new lease until it is idle (it drains), so suspects never starve.
  const std::string* drain = nullptr;
  {
    JobTasks* job = nullptr;
    const std::string* job_id = nullptr;
    for (auto& [id, j] : jobs_) {
      if (j.suspects.empty()) continue;
      if (!job || j.last_served < job->last_served) {
        job = &j;
        job_id = &id;
      }
    }
    if (job) {
      WorkerSlot *idle = nullptr, *least = nullptr;
      const std::string *idle_id = nullptr, *least_id = nullptr;
      for (auto& [id, w] : workers_) {
        if (w.exclusive) continue;
        if (w.leases == 0) {
          if (!idle || w.last_served < idle->last_served) {
            idle = &w;
            idle_id = &id;
          }
        } else if (!least || static_cast<double>(w.items) / w.threads <
                                 static_cast<double>(least->items) / least->threads) {
          least = &w;
          least_id = &id;
        }
      }
      if (idle) {
        const int p = job->suspects.front();
        job->suspects.pop_front();
        return Grant(*job_id, *job, *idle_id, *idle, {p}, /*solo=*/true, now);
      }
      drain = least_id;
    }
  }
  // The job: fewest tasks in flight among those with pending tasks; ties: served longest ago.
  JobTasks* job = nullptr;
  const std::string* job_id = nullptr;
  for (auto& [id, j] : jobs_) {
    if (j.pending.empty()) continue;
    if (!job || j.in_flight < job->in_flight ||
        (j.in_flight == job->in_flight && j.last_served < job->last_served)) {
      job = &j;
      job_id = &id;
    }
  }
  if (!job) return Speculate(now);
  // The worker: with room, least loaded per thread; ties: served longest ago.
  WorkerSlot* worker = nullptr;
  const std::string* worker_id = nullptr;
  for (auto& [id, w] : workers_) {
    if (!HasRoom(w) || (drain && id == *drain)) continue;
    if (!worker ||
        static_cast<double>(w.items) / w.threads <
            static_cast<double>(worker->items) / worker->threads ||
        (w.items * worker->threads == worker->items * w.threads &&
         w.last_served < worker->last_served)) {
      worker = &w;
      worker_id = &id;
    }
  }
  if (!worker) return std::nullopt;
  const int n = BatchSize(*worker, *job);
  std::vector<int> positions(job->pending.begin(), job->pending.begin() + n);
  job->pending.erase(job->pending.begin(), job->pending.begin() + n);
  return Grant(*job_id, *job, *worker_id, *worker, std::move(positions), /*solo=*/false, now);
}

void Dispatcher::Release(const Lease& lease) {
  const int n = static_cast<int>(lease.positions.size());
  if (auto w = workers_.find(lease.worker); w != workers_.end()) {
    w->second.leases -= 1;
    w->second.items -= n;
    if (lease.solo) w->second.exclusive = false;
  }
  if (auto j = jobs_.find(lease.job_id); j != jobs_.end()) j->second.in_flight -= n;
}

std::optional<Lease> Dispatcher::Complete(const std::string& worker, uint64_t lease_id,
                                          double eval_seconds) {
  auto it = leases_.find(lease_id);
  if (it == leases_.end() || it->second.worker != worker) return std::nullopt;
  Lease l = std::move(it->second);
  leases_.erase(it);
  Release(l);
  auto w = workers_.find(worker);
  if (w != workers_.end() && !l.positions.empty() && eval_seconds >= 0 &&
      std::isfinite(eval_seconds)) {
    const double item = std::max(1e-7, eval_seconds / static_cast<double>(l.positions.size()));
    w->second.item_s = w->second.item_s < 0 ? item : 0.7 * w->second.item_s + 0.3 * item;
    // The generation's time per task, for its stragglers: per thread, as the holder ran it.
    if (auto j = jobs_.find(l.job_id);
        j != jobs_.end() && j->second.generation == l.generation && !l.speculative) {
      j->second.task_s.push_back(item);
      j->second.median_task_s = -1;
    }
  }
  return l;
}

TimePoint Dispatcher::StragglerAt(const Lease& l) const {
  if (options_.speculate_after <= 0 || l.speculative || l.copied || l.solo) return TimePoint::max();
  auto j = jobs_.find(l.job_id);
  if (j == jobs_.end() || j->second.generation != l.generation || j->second.task_s.empty())
    return TimePoint::max();
  const JobTasks& job = j->second;
  if (job.median_task_s < 0) {
    std::vector<double> t = job.task_s;
    std::nth_element(t.begin(), t.begin() + static_cast<long>(t.size() / 2), t.end());
    job.median_task_s = t[t.size() / 2];
  }
  const double expected = job.median_task_s * l.rounds;
  const double after = std::max(options_.speculate_min_s, options_.speculate_after * expected);
  return l.granted + std::chrono::duration_cast<Duration>(std::chrono::duration<double>(after));
}

std::optional<Lease> Dispatcher::Speculate(TimePoint now) {
  if (options_.speculate_after <= 0) return std::nullopt;
  // An idle worker, served longest ago (one that holds no lease holds no straggler either).
  WorkerSlot* idle = nullptr;
  const std::string* idle_id = nullptr;
  for (auto& [id, w] : workers_) {
    if (w.exclusive || w.leases > 0) continue;
    if (!idle || w.last_served < idle->last_served) {
      idle = &w;
      idle_id = &id;
    }
  }
  if (!idle) return std::nullopt;
  // The stragglers of the jobs that have nothing else to hand out, the one granted first.
  for (;;) {
    Lease* straggler = nullptr;
    for (auto& [id, l] : leases_) {
      auto j = jobs_.find(l.job_id);
      if (j == jobs_.end() || !j->second.pending.empty() || !j->second.suspects.empty()) continue;
      if (StragglerAt(l) > now) continue;
      if (!straggler || l.granted < straggler->granted) straggler = &l;
    }
    if (!straggler) return std::nullopt;
    straggler->copied = true;  // once, whether or not anything is left to copy
    JobTasks& job = jobs_.at(straggler->job_id);
    std::vector<int> left;
    for (int p : straggler->positions)
      if (!job.done[p]) left.push_back(p);
    if (left.empty()) continue;
    const std::string job_id = straggler->job_id;
    Lease copy = Grant(job_id, job, *idle_id, *idle, std::move(left), /*solo=*/false, now);
    copy.speculative = true;
    leases_.at(copy.id).speculative = true;
    ++speculative_leases_;
    return copy;
  }
}

std::vector<Quarantined> Dispatcher::Requeue(const Lease& lease, RequeueCause cause,
                                             TimePoint now) {
  std::vector<Quarantined> out;
  auto it = jobs_.find(lease.job_id);
  if (it == jobs_.end() || it->second.generation != lease.generation) return out;
  JobTasks& j = it->second;
  for (int p : lease.positions) {
    if (p < 0 || p >= j.tasks || j.done[p]) continue;
    if (cause == RequeueCause::kDeadline && lease.solo) {  // it hangs its worker, which lives on
      if (auto q = Strike(lease.job_id, lease.generation, p, lease.worker)) {
        out.push_back(*q);
        continue;
      }
    }
    if (cause == RequeueCause::kTransient && !lease.solo) {
      j.pending.push_front(p);
    } else {
      j.suspects.push_back(p);
    }
  }
  (void)now;
  return out;
}

std::vector<Quarantined> Dispatcher::ExpireLeases(TimePoint now) {
  std::vector<Lease> expired;
  for (auto it = leases_.begin(); it != leases_.end();) {
    if (it->second.deadline <= now) {
      expired.push_back(std::move(it->second));
      it = leases_.erase(it);
    } else {
      ++it;
    }
  }
  std::vector<Quarantined> out;
  for (const Lease& l : expired) {
    Release(l);
    auto q = Requeue(l, RequeueCause::kDeadline, now);
    out.insert(out.end(), q.begin(), q.end());
  }
  return out;
}

TimePoint Dispatcher::NextDeadline() const {
  TimePoint t = TimePoint::max();
  bool idle = false;  // straggler times matter only while a worker could take a copy
  for (const auto& [id, w] : workers_) idle = idle || (!w.exclusive && w.leases == 0);
  for (const auto& [id, l] : leases_) {
    t = std::min(t, l.deadline);
    if (!idle) continue;
    auto j = jobs_.find(l.job_id);
    if (j != jobs_.end() && j->second.pending.empty() && j->second.suspects.empty())
      t = std::min(t, StragglerAt(l));
  }
  if (!candidates_.empty()) t = std::min(t, candidates_.front().at + quiet_window());
  return t;
}

double Dispatcher::worker_item_seconds(const std::string& id) const {
  auto it = workers_.find(id);
  return it == workers_.end() ? -1 : it->second.item_s;
}

std::vector<Dispatcher::WorkerLoad> Dispatcher::Workers() const {
  std::vector<WorkerLoad> out;
  out.reserve(workers_.size());
  for (const auto& [id, w] : workers_)
    out.push_back({id, w.threads, w.item_s, w.leases, w.items, w.exclusive});
  return out;
}

}  // namespace pz::master
