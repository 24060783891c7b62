// `piezoid submit | status | list | watch | cancel | prune | fetch | dashboard`: the service
// commands, thin wrappers of svcclient/service_client.h, svcclient/job_file.h, reports/job_report.h
// and dashboard/dashboard.h. Register with RegisterServiceCommands(app, exit_code).
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "client/commands.h"
#include "client/service_flags.h"
#include "dashboard/dashboard.h"
#include "hgann/hgann_job.h"
#include "job/job_kind.h"
#include "kinds/kinds.h"
#include "reports/job_report.h"
#include "service/wire_codec.h"
#include "svcclient/job_file.h"
#include "svcclient/service_client.h"

namespace pz::client {
namespace fs = std::filesystem;

namespace {

struct Common {
  std::string master;
  int timeout_ms = 4000;
  int retries = 2;
  std::string curve_secret = EnvOr("PIEZOID_CURVE_SECRET"),
              master_public = EnvOr("PIEZOID_MASTER_PUBLIC");
  /// The client of these options; a bad key file throws InputError (exit code 2).
  svcclient::ServiceClient Client() const {
    return svcclient::ServiceClient(
        ClientOptionsOf(master, timeout_ms, retries, curve_secret, master_public));
  }
};

std::string DefaultMaster() { return EnvOr("PIEZOID_MASTER", "tcp://127.0.0.1:5556"); }

void AddCommon(CLI::App* c, Common& o) {
  c->add_option("--master", o.master,
                "the master's client endpoint (default: $PIEZOID_MASTER or tcp://127.0.0.1:5556)")
      ->capture_default_str();
  c->add_option("--timeout-ms", o.timeout_ms, "per-request timeout [ms]")
      ->check(CLI::Range(10, 3600000))
      ->capture_default_str();
  c->add_option("--retries", o.retries, "attempts per request before giving up")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  c->add_option("--curve-secret", o.curve_secret,
                "CURVE: this client's key pair, NAME.key from `piezoid keygen` (default: "
                "$PIEZOID_CURVE_SECRET)");
  c->add_option("--master-public", o.master_public,
                "CURVE: the master's public key file (default: $PIEZOID_MASTER_PUBLIC)");
}

std::string Num(double x, int prec = 6) {
  std::ostringstream os;
  os.precision(prec);
  os << x;
  return os.str();
}

/// "12/1000": the last completed generation (generation 0 is the initial population) of at most
/// max; "-" before the first.
std::string Generation(const service::JobInfo& i) {
  if (i.algorithm == "external") return std::to_string(i.generation) + "b";  // a session: batches
  return (i.generation == 0 ? std::string("-") : std::to_string(i.generation - 1)) + "/" +
         std::to_string(i.max_generations);
}

void PrintInfo(const service::JobInfo& i) {
  std::printf(
      "%-17s %-9s %-9s gen %-9s best %-12s evals %-8llu %6.1f s  %s%s%s\n", i.job_id.c_str(),
      (std::string(service::JobStateName(i.state)) + (i.archived ? "*" : "")).c_str(),
      i.kind.c_str(), Generation(i).c_str(), i.generation == 0 ? "-" : Num(i.best_cost, 8).c_str(),
      static_cast<unsigned long long>(i.evaluations), i.elapsed_s, i.name.c_str(),
      i.quarantined.empty() ? ""
                            : ("  quarantined " + std::to_string(i.quarantined.size())).c_str(),
      i.message.empty() ? "" : ("  (" + i.message + ")").c_str());
  if (!i.storage_error.empty())
    std::printf("%-17s   ! checkpoints not written: %s\n", "", i.storage_error.c_str());
  if (!i.notice.empty()) std::printf("%-17s   ! on loading: %s\n", "", i.notice.c_str());
}

void PrintList(const std::vector<service::JobInfo>& all, int workers, int threads) {
  std::printf("%d worker%s (%d thread%s), %zu job%s\n", workers, workers == 1 ? "" : "s", threads,
              threads == 1 ? "" : "s", all.size(), all.size() == 1 ? "" : "s");
  bool archived = false;
  for (const auto& i : all) {
    PrintInfo(i);
    archived = archived || i.archived;
  }
  if (archived) std::printf("* archived: on the master's disk only (fetch reads it there)\n");
}

/// The watch progress display: a bar redrawn in place on a terminal, a line every few seconds
/// otherwise (logs, pipes).
class Progress {
 public:
  Progress(uint64_t max_generations, bool hgann)
      : max_(max_generations), hgann_(hgann), tty_(::isatty(STDOUT_FILENO) != 0) {}

  void Update(const service::JobEvent& e) {
    if (e.storage_error != storage_error_) {  // said once when it starts and once when it ends
      storage_error_ = e.storage_error;
      std::printf("%s%s\n", tty_ && printed_ ? "\n" : "",
                  storage_error_.empty()
                      ? "checkpoints are written again"
                      : ("! checkpoints not written (a master restart would lose progress): " +
                         storage_error_)
                            .c_str());
    }
    if (!e.record) return;
    const auto& r = *e.record;
    window_.push_back(r);
    while (window_.size() > 10) window_.pop_front();
    double evals = 0, secs = 0;
    for (const auto& w : window_) {
      evals += w.evaluations;
      secs += w.wall_time_s;
    }
    const double rate = secs > 0 ? evals / secs : 0;
    const auto now = std::chrono::steady_clock::now();
    const double since = std::chrono::duration<double>(now - last_print_).count();
    const bool last = max_ > 0 && r.generation >= max_;
    if (!(since >= (tty_ ? 0.1 : 5.0) || last || printed_ == 0)) return;
    last_print_ = now;
    ++printed_;
    constexpr int kWidth = 28;
    const double frac = max_ > 0 ? std::min(1.0, static_cast<double>(r.generation) / max_) : 0;
    std::string bar(kWidth, '.');
    for (int i = 0; i < static_cast<int>(std::lround(frac * kWidth)); ++i) bar[i] = '#';
    char line[384];
    const std::string best = Num(r.best_cost, 6) + (hgann_ ? " deg²" : "");
    std::snprintf(line, sizeof line,
                  "gen %4llu/%-4llu [%s] best %-*s %7.0f evals/s  %d worker%s (%d threads)",
                  static_cast<unsigned long long>(r.generation),
                  static_cast<unsigned long long>(max_), bar.c_str(), hgann_ ? 17 : 14,
                  best.c_str(), rate, e.workers, e.workers == 1 ? "" : "s", e.worker_threads);
    const std::string islands = reports::IslandsBrief(r);
    std::strncat(line, islands.c_str(), sizeof line - std::strlen(line) - 1);
    if (tty_) {
      std::printf("\r%s\033[K", line);
    } else {
      std::printf("%s\n", line);
    }
    std::fflush(stdout);
  }
  void End() {
    if (tty_ && printed_ > 0) std::printf("\n");
    std::fflush(stdout);
  }

 private:
  uint64_t max_;
  bool hgann_, tty_;
  std::deque<service::GenerationRecord> window_;
  std::chrono::steady_clock::time_point last_print_{};
  int printed_ = 0;
  std::string storage_error_;
};

/// Adds the subcommand `name` with the options of every client of the master (AddCommon) in o.
CLI::App* AddMasterCommand(CLI::App& app, const char* name, const char* description, Common& o) {
  auto* c = app.add_subcommand(name, description);
  o.master = DefaultMaster();
  AddCommon(c, o);
  return c;
}

/// Registers the subcommand `c` whose run is `run(options)`, its result the exit code.
template <typename Options, typename Run>
void OnRun(CLI::App* c, const std::shared_ptr<Options>& o, int& exit_code, Run run) {
  c->callback([o, &exit_code, run] { exit_code = run(*o); });
}

// ---------------------------------------------------------------- submit

struct SubmitOptions : Common {
  std::string spec, token, embedded_out;
};

int SubmitJob(const SubmitOptions& o) {
  job::JobSpec spec;
  std::vector<job::FieldViolation> v;
  Status s = svcclient::LoadJobSpecFile(o.spec, &spec, &v);
  if (!s.ok()) return ReportViolations("job spec " + o.spec, v, s);
  // Checked here first (same rules as the master), so a bad spec needs no master to be told.
  v = kinds::All().Validate(spec);
  if (!v.empty()) return ReportViolations("job spec " + o.spec, v, InvalidArgument("invalid"));
  if (!o.embedded_out.empty()) {
    if (int code = WriteTextFile(o.embedded_out, service::JobSpecToJson(spec) + "\n");
        code != kExitOk)
      return code;
    std::fprintf(stderr, "piezoid: wrote %s (the spec with its data embedded; not submitted)\n",
                 o.embedded_out.c_str());
    return kExitOk;
  }
  svcclient::SubmitResult r;
  s = o.Client().Submit(spec, &r, &v, o.token);
  if (!s.ok())
    return s.code() == StatusCode::kInvalidArgument ? ReportViolations("job spec " + o.spec, v, s)
                                                    : ReportStatus(s);
  std::printf("%s\n", r.job_id.c_str());
  if (r.existed)
    std::fprintf(stderr, "piezoid: job %s had already been submitted\n", r.job_id.c_str());
  return kExitOk;
}

void RegisterSubmit(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<SubmitOptions>();
  auto* c = AddMasterCommand(
      app, "submit",
      "submit a job spec (protobuf JSON, see examples/): prints the job id on stdout", *o);
  c->add_option("spec", o->spec,
                "job spec file (an hgann spec's case_set_dir is read here, relative to it)")
      ->required();
  c->add_option(
      "--client-token", o->token,
      "idempotence token: submitting the same spec with the same token again returns the same job "
      "(default: a random one)");
  c->add_option(
      "--write-embedded", o->embedded_out,
      "write the checked spec with its case data embedded (protobuf JSON, what the Python client "
      "submits) to this file instead of submitting it");
  OnRun(c, o, exit_code, SubmitJob);
}

// ---------------------------------------------------------------- status / list

struct StatusOptions : Common {
  std::string job_id;  ///< empty: every job
};

int ListJobs(const Common& o) {
  std::vector<service::JobInfo> all;
  int workers = 0, threads = 0;
  Status s = o.Client().List(&all, &workers, &threads);
  if (s.ok()) PrintList(all, workers, threads);
  return ReportStatus(s);
}

int ShowStatus(const StatusOptions& o) {
  if (o.job_id.empty()) return ListJobs(o);
  service::JobInfo i;
  Status s = o.Client().GetStatus(o.job_id, &i);
  if (s.ok()) PrintInfo(i);
  return ReportStatus(s);
}

void RegisterStatus(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<StatusOptions>();
  auto* c =
      AddMasterCommand(app, "status", "a job's state and progress (every job without an id)", *o);
  c->add_option("job", o->job_id, "job id (optional)");
  OnRun(c, o, exit_code, ShowStatus);
}

void RegisterList(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<Common>();
  auto* c = AddMasterCommand(app, "list", "the master's jobs and workers", *o);
  c->alias("jobs");
  OnRun(c, o, exit_code, ListJobs);
}

// ---------------------------------------------------------------- cancel

struct JobOptions : Common {
  std::string job_id;
};

int CancelJob(const JobOptions& o) {
  Status s = o.Client().Cancel(o.job_id);
  if (s.ok()) std::printf("%s cancelled\n", o.job_id.c_str());
  return ReportStatus(s);
}

void RegisterCancel(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<JobOptions>();
  auto* c =
      AddMasterCommand(app, "cancel", "cancel a running job (its checkpoint stays fetchable)", *o);
  c->add_option("job", o->job_id, "job id")->required();
  OnRun(c, o, exit_code, CancelJob);
}

// ---------------------------------------------------------------- prune

struct PruneOptions : Common {
  std::vector<std::string> job_ids;
  double older_days = 0;
  int keep = 0;
  bool dry_run = false;
};

int PruneJobs(const PruneOptions& o) {
  if (o.job_ids.empty() && o.older_days <= 0 && o.keep <= 0) {
    std::fprintf(stderr, "piezoid prune: name the jobs, or give --older-than DAYS or --keep N\n");
    return kExitBadInput;
  }
  std::vector<std::string> pruned;
  std::vector<job::FieldViolation> refused;
  Status s =
      o.Client().Prune(o.job_ids, o.older_days * 86400.0, o.keep, o.dry_run, &pruned, &refused);
  if (!s.ok()) return ReportStatus(s);
  for (const auto& id : pruned)
    std::printf("%s %s\n", o.dry_run ? "would prune" : "pruned", id.c_str());
  for (const auto& v : refused)
    std::fprintf(stderr, "piezoid prune: %s: %s\n", v.field.c_str(), v.description.c_str());
  if (pruned.empty() && refused.empty()) std::printf("nothing to prune\n");
  return refused.empty() ? kExitOk : kExitJobNotOk;
}

void RegisterPrune(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<PruneOptions>();
  auto* c = AddMasterCommand(app, "prune",
                             "delete ended jobs from the master (memory and state directory): "
                             "those named, or by age / count",
                             *o);
  c->add_option("jobs", o->job_ids, "ended jobs to delete (running ones are refused)");
  c->add_option("--older-than", o->older_days,
                "delete the ended jobs that ended more than DAYS ago")
      ->check(CLI::PositiveNumber);
  c->add_option("--keep", o->keep, "delete all but the N most recently ended jobs")
      ->check(CLI::Range(1, 100000000));
  c->add_flag("--dry-run", o->dry_run, "list what would be deleted, delete nothing");
  OnRun(c, o, exit_code, PruneJobs);
}

// ---------------------------------------------------------------- watch

int WatchJob(const JobOptions& o) {
  svcclient::ServiceClient c = o.Client();
  service::JobInfo info;
  Status s = c.GetStatus(o.job_id, &info);
  if (!s.ok()) return ReportStatus(s);
  std::printf("job %s (%s%s%s), %llu generations at most\n", o.job_id.c_str(), info.kind.c_str(),
              info.name.empty() ? "" : ": ", info.name.c_str(),
              static_cast<unsigned long long>(info.max_generations));
  if (!info.notice.empty()) std::printf("! on loading: %s\n", info.notice.c_str());
  Progress progress(info.max_generations, info.kind == "hgann");
  s = c.Watch(
      o.job_id,
      [&progress](const service::JobEvent& e) {
        progress.Update(e);
        return true;
      },
      std::chrono::hours(24 * 365));
  progress.End();
  if (!s.ok()) return ReportStatus(s);
  s = c.GetStatus(o.job_id, &info);
  if (!s.ok()) return ReportStatus(s);
  std::printf("job %s %s (%s) after %llu generations: best cost %s%s, %llu evaluations in %.1f s\n",
              o.job_id.c_str(), service::JobStateName(info.state), info.message.c_str(),
              static_cast<unsigned long long>(info.generation > 0 ? info.generation - 1 : 0),
              Num(info.best_cost, 9).c_str(), info.kind == "hgann" ? " deg²" : "",
              static_cast<unsigned long long>(info.evaluations), info.elapsed_s);
  if (info.state == service::JobState::kSucceeded || info.generation > 0)
    std::printf("fetch the result: piezoid fetch %s --out <folder>\n", o.job_id.c_str());
  return info.state == service::JobState::kSucceeded ? kExitOk : kExitJobNotOk;
}

void RegisterWatch(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<JobOptions>();
  auto* c = AddMasterCommand(
      app, "watch",
      "follow a job until it ends: generation, best cost, evaluations/s, workers; then the result",
      *o);
  c->add_option("job", o->job_id, "job id")->required();
  OnRun(c, o, exit_code, WatchJob);
}

// ---------------------------------------------------------------- fetch

struct FetchOptions : JobOptions {
  int count = 5;
  std::string out;
  bool no_plots = false;
};

int FetchJob(const FetchOptions& o) {
  reports::FetchedJob job;
  Status s =
      o.Client().Fetch(o.job_id, o.count, &job.best, &job.log, &job.info, &job.spec, &job.networks);
  if (!s.ok()) return ReportStatus(s);
  if (!service::IsFinal(job.info.state))
    std::fprintf(stderr,
                 "piezoid: note: job %s is still %s (generation %llu): this is the best so far\n",
                 o.job_id.c_str(), service::JobStateName(job.info.state),
                 static_cast<unsigned long long>(job.info.generation));
  const fs::path dir = o.out.empty() ? fs::path(o.job_id) : fs::path(o.out);
  reports::FetchOutput out;
  s = reports::WriteFetchedJob(job, dir, !o.no_plots, std::cout, &out);
  std::cout.flush();
  if (s.ok() && !out.report.empty()) std::printf("report: %s\n", out.report.string().c_str());
  return ReportStatus(s);
}

void RegisterFetch(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<FetchOptions>();
  auto* c = AddMasterCommand(app, "fetch",
                             "write a job's best networks (.pb, .json) and, for hgann jobs, the "
                             "report of `piezoid identify`",
                             *o);
  c->add_option("job", o->job_id, "job id")->required();
  c->add_option("--best,-n", o->count, "how many of the best individuals (1 … 32)")
      ->check(CLI::Range(1, 32))
      ->capture_default_str();
  c->add_option("--out,-o", o->out, "result folder (default: ./<job id>)");
  c->add_flag("--no-plots", o->no_plots,
              "do not render figures (gnuplot scripts are still written)");
  OnRun(c, o, exit_code, FetchJob);
}

// ---------------------------------------------------------------- dashboard

struct DashboardFlags : Common {
  std::string listen = "127.0.0.1:8080", token_file, reports, cache, url_file;
  int poll_ms = 1000;
  bool no_plots = false;
};

/// The dashboard's options of its flags: InvalidArgument naming --listen or --token-file.
Status DashboardOptionsOf(const DashboardFlags& f, dashboard::DashboardOptions* o) {
  o->client = ClientOptionsOf(f.master, f.timeout_ms, f.retries, f.curve_secret, f.master_public);
  const size_t colon = f.listen.rfind(':');
  if (colon == std::string::npos || colon + 1 == f.listen.size())
    return InvalidArgument("--listen '" + f.listen + "': must be HOST:PORT, e.g. 127.0.0.1:8080");
  o->host = f.listen.substr(0, colon);
  if (o->host.size() > 2 && o->host.front() == '[' && o->host.back() == ']')
    o->host = o->host.substr(1, o->host.size() - 2);
  try {
    size_t used = 0;
    o->port = std::stoi(f.listen.substr(colon + 1), &used);
    if (used != f.listen.size() - colon - 1) throw std::invalid_argument("trailing characters");
  } catch (const std::exception&) {
    return InvalidArgument("--listen '" + f.listen + "': the port must be a number in [0, 65535]");
  }
  if (!f.token_file.empty()) {
    std::ifstream in(f.token_file);
    if (!in || !std::getline(in, o->token))
      return InvalidArgument("--token-file " + f.token_file + ": cannot read its first line");
    while (!o->token.empty() && std::isspace(static_cast<unsigned char>(o->token.back())))
      o->token.pop_back();
  }
  o->poll_ms = f.poll_ms;
  o->reports_dir = f.reports;
  o->cache_dir = f.cache;
  o->plots = !f.no_plots;
  return Status::Ok();
}

int ServeDashboard(const DashboardFlags& f) {
  dashboard::DashboardOptions o;
  if (Status s = DashboardOptionsOf(f, &o); !s.ok()) return ReportStatus(s);
  // SIGINT / SIGTERM end the dashboard: blocked here (every thread inherits the mask), awaited
  // below.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  dashboard::Dashboard d(o);
  if (Status s = d.Start(); !s.ok()) return ReportStatus(s);
  if (!f.url_file.empty()) {
    const std::string tmp = f.url_file + ".tmp";
    std::ofstream(tmp) << d.url() << "\n";
    std::error_code ec;
    fs::rename(tmp, f.url_file, ec);
  }
  std::printf("piezoid dashboard of %s on %s%s (Ctrl-C to stop)\n", o.client.endpoint.c_str(),
              d.url().c_str(), o.token.empty() ? "" : "?token=…");
  std::fflush(stdout);
  int sig = 0;
  sigwait(&signals, &sig);
  d.Stop();
  return kExitOk;
}

void RegisterDashboard(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<DashboardFlags>();
  auto* c = AddMasterCommand(
      app, "dashboard",
      "serve a live web page of the master's jobs, fitness curves, workers and reports (read-only)",
      *o);
  c->add_option("--listen", o->listen,
                "HOST:PORT to serve on (PORT 0: any free port; beyond loopback needs --token-file)")
      ->capture_default_str();
  c->add_option(
      "--token-file", o->token_file,
      "file whose first line is the access token every request must carry (?token= or a Bearer "
      "header); required beyond loopback or with CURVE");
  c->add_option("--poll-ms", o->poll_ms, "how often the master is polled [ms]")
      ->capture_default_str();
  c->add_option("--reports", o->reports,
                "also serve the report folders (each with a report.md) under this folder");
  c->add_option("--cache", o->cache,
                "where ended jobs' reports are built (default: a temporary folder)");
  c->add_option("--url-file", o->url_file,
                "write the dashboard's URL to this file once it listens");
  c->add_flag("--no-plots", o->no_plots, "build job reports without figures (no gnuplot)");
  OnRun(c, o, exit_code, ServeDashboard);
}

}  // namespace

void RegisterServiceCommands(CLI::App& app, int& exit_code) {
  RegisterSubmit(app, exit_code);
  RegisterStatus(app, exit_code);
  RegisterList(app, exit_code);
  RegisterCancel(app, exit_code);
  RegisterPrune(app, exit_code);
  RegisterWatch(app, exit_code);
  RegisterFetch(app, exit_code);
  RegisterDashboard(app, exit_code);
  RegisterKeygen(app, exit_code);
  RegisterDoctor(app, exit_code);
}

}  // namespace pz::client
