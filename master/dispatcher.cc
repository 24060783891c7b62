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
  j.strikes.assign(tasks, 0);
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

std::vector<Quarantined> Dispatcher::RemoveWorker(const std::string& id, bool strike) {
  std::vector<Quarantined> out;
  std::vector<Lease> taken;
  for (auto it = leases_.begin(); it != leases_.end();) {
    if (it->second.worker == id) {
      taken.push_back(std::move(it->second));
      it = leases_.erase(it);
    } else {
      ++it;
    }
  }
  for (const Lease& l : taken) {
    Release(l);
    auto q = Requeue(l, strike);
    out.insert(out.end(), q.begin(), q.end());
  }
  auto w = workers_.find(id);
  if (w != workers_.end()) {
    total_threads_ -= w->second.threads;
    workers_.erase(w);
  }
  return out;
}

bool Dispatcher::HasRoom(const WorkerSlot& w) const {
  return w.leases < options_.leases_per_worker || w.items < w.threads;
}

int Dispatcher::BatchSize(const WorkerSlot& w, const JobTasks& j) const {
  const int pending = static_cast<int>(j.pending.size());
  long rounds = 1;
  if (w.item_s > 0) rounds = std::max(1L, std::lround(std::floor(options_.target_batch_s / w.item_s)));
  long target = std::min<long>(options_.max_batch, rounds * w.threads);
  long guided = static_cast<long>(
      std::ceil(static_cast<double>(pending) * w.threads / (2.0 * std::max(1, total_threads_))));
  long size = std::min(target, std::max<long>(guided, w.threads));
  size = std::min<long>({size, pending, options_.max_batch});
  return static_cast<int>(std::max(1L, size));
}

std::optional<Lease> Dispatcher::NextLease(TimePoint now) {
  // The job: fewest tasks in flight among those with pending tasks; ties: served longest ago.
  JobTasks* job = nullptr;
  const std::string* job_id = nullptr;
  for (auto& [id, j] : jobs_) {
    if (j.pending.empty() && j.suspects.empty()) continue;
    if (!job || j.in_flight < job->in_flight ||
        (j.in_flight == job->in_flight && j.last_served < job->last_served)) {
      job = &j;
      job_id = &id;
    }
  }
  if (!job) return std::nullopt;
  // The worker: with room, least loaded per thread; ties: served longest ago.
  WorkerSlot* worker = nullptr;
  const std::string* worker_id = nullptr;
  for (auto& [id, w] : workers_) {
    if (!HasRoom(w)) continue;
    if (!worker || static_cast<double>(w.items) / w.threads <
                       static_cast<double>(worker->items) / worker->threads ||
        (w.items * worker->threads == worker->items * w.threads &&
         w.last_served < worker->last_served)) {
      worker = &w;
      worker_id = &id;
    }
  }
  if (!worker) return std::nullopt;

  Lease l;
  l.id = next_lease_id_++;
  l.worker = *worker_id;
  l.job_id = *job_id;
  l.generation = job->generation;
  if (!job->suspects.empty()) {
    l.positions.push_back(job->suspects.front());
    job->suspects.pop_front();
  } else {
    const int n = BatchSize(*worker, *job);
    l.positions.assign(job->pending.begin(), job->pending.begin() + n);
    job->pending.erase(job->pending.begin(), job->pending.begin() + n);
  }
  const int n = static_cast<int>(l.positions.size());
  worker->leases += 1;
  worker->items += n;
  worker->last_served = job->last_served = ++serve_counter_;
  job->in_flight += n;
  const double rounds = std::ceil(static_cast<double>(worker->items) / worker->threads);
  l.granted = now;
  l.deadline = now + std::chrono::duration_cast<Duration>(
                         std::chrono::duration<double>(rounds * job->task_timeout_s));
  leases_.emplace(l.id, l);
  return l;
}

void Dispatcher::Release(const Lease& lease) {
  const int n = static_cast<int>(lease.positions.size());
  if (auto w = workers_.find(lease.worker); w != workers_.end()) {
    w->second.leases -= 1;
    w->second.items -= n;
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
  }
  return l;
}

std::vector<Quarantined> Dispatcher::Requeue(const Lease& lease, bool strike) {
  std::vector<Quarantined> out;
  auto it = jobs_.find(lease.job_id);
  if (it == jobs_.end() || it->second.generation != lease.generation) return out;
  JobTasks& j = it->second;
  for (int p : lease.positions) {
    if (p < 0 || p >= j.tasks || j.done[p]) continue;
    if (strike) j.strikes[p] += 1;
    if (j.strikes[p] >= j.quarantine_after) {
      j.done[p] = 1;
      --j.remaining;
      out.push_back({lease.job_id, lease.generation, p, j.strikes[p]});
    } else if (j.strikes[p] > 0) {
      j.suspects.push_back(p);
    } else {
      j.pending.push_front(p);
    }
  }
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
    auto q = Requeue(l, true);
    out.insert(out.end(), q.begin(), q.end());
  }
  return out;
}

TimePoint Dispatcher::NextDeadline() const {
  TimePoint t = TimePoint::max();
  for (const auto& [id, l] : leases_) t = std::min(t, l.deadline);
  return t;
}

double Dispatcher::worker_item_seconds(const std::string& id) const {
  auto it = workers_.find(id);
  return it == workers_.end() ? -1 : it->second.item_s;
}

}  // namespace pz::master
