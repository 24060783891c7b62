// `piezoid submit | status | list | watch | cancel | fetch | export`: the service commands, thin
// wrappers of client/service_client.h, client/job_file.h, client/job_report.h and
// client/export_c.h. Register with RegisterServiceCommands(app, exit_code).
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

#include "client/cmd_service.h"
#include "client/dashboard.h"
#include "client/export_c.h"
#include "client/job_file.h"
#include "client/job_report.h"
#include "client/service_client.h"
#include "job/job_kind.h"
#include "service/wire_codec.h"
#include "kinds/kinds.h"

namespace pz::client {
namespace fs = std::filesystem;

int ExitCodeOf(const Status& s) {
  switch (s.code()) {
    case StatusCode::kOk: return kExitOk;
    case StatusCode::kInvalidArgument: return kExitBadInput;
    case StatusCode::kUnavailable: return kExitUnreachable;
    case StatusCode::kNotFound: return kExitUnknownJob;
    case StatusCode::kFailedPrecondition: return kExitJobNotOk;
    default: return kExitFailure;
  }
}

ServiceClientOptions ClientOptionsOf(const std::string& master, int timeout_ms, int retries,
                                     const std::string& curve_secret, const std::string& master_public) {
  ServiceClientOptions o;
  o.endpoint = master;
  o.timeout_ms = timeout_ms;
  o.retries = retries;
  if (curve_secret.empty() != master_public.empty())
    throw InputError(curve_secret.empty()
                         ? "--master-public (or PIEZOID_MASTER_PUBLIC) needs --curve-secret (or PIEZOID_CURVE_SECRET)"
                         : "--curve-secret (or PIEZOID_CURVE_SECRET) needs --master-public (or PIEZOID_MASTER_PUBLIC)");
  if (!curve_secret.empty()) {
    service::CurveKeyPair keys;
    if (Status s = service::LoadCurveSecretFile(curve_secret, &keys); !s.ok())
      throw InputError("--curve-secret: " + s.message());
    if (Status s = service::LoadCurvePublicFile(master_public, &o.master_public); !s.ok())
      throw InputError("--master-public: " + s.message());
    o.curve = keys;
  }
  return o;
}

namespace {

std::string Env(const char* name, const char* fallback = "") {
  const char* env = std::getenv(name);
  return env && *env ? env : fallback;
}

struct Common {
  std::string master;
  int timeout_ms = 4000;
  int retries = 2;
  std::string curve_secret = Env("PIEZOID_CURVE_SECRET"), master_public = Env("PIEZOID_MASTER_PUBLIC");
  /// The client of these options; a bad key file throws InputError (exit code 2).
  ServiceClient Client() const {
    return ServiceClient(ClientOptionsOf(master, timeout_ms, retries, curve_secret, master_public));
  }
};

std::string DefaultMaster() { return Env("PIEZOID_MASTER", "tcp://127.0.0.1:5556"); }

void AddCommon(CLI::App* c, Common& o) {
  c->add_option("--master", o.master, "the master's client endpoint (default: $PIEZOID_MASTER or tcp://127.0.0.1:5556)")
      ->capture_default_str();
  c->add_option("--timeout-ms", o.timeout_ms, "per-request timeout [ms]")
      ->check(CLI::Range(10, 3600000))
      ->capture_default_str();
  c->add_option("--retries", o.retries, "attempts per request before giving up")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  c->add_option("--curve-secret", o.curve_secret,
                "CURVE: this client's key pair, NAME.key from `piezoid keygen` (default: $PIEZOID_CURVE_SECRET)");
  c->add_option("--master-public", o.master_public,
                "CURVE: the master's public key file (default: $PIEZOID_MASTER_PUBLIC)");
}

int Report(const Status& s) {
  if (s.ok()) return kExitOk;
  std::fprintf(stderr, "piezoid: error: %s\n", s.message().c_str());
  return ExitCodeOf(s);
}

/// Prints every violation; returns the exit code for an invalid spec.
int ReportViolations(const std::string& what, const std::vector<job::FieldViolation>& v, const Status& s) {
  if (v.empty()) return Report(s);
  std::fprintf(stderr, "piezoid: error: %s is invalid (%zu violation%s):\n", what.c_str(), v.size(),
               v.size() == 1 ? "" : "s");
  for (const auto& x : v) std::fprintf(stderr, "  %s\n", x.description.c_str());
  return kExitBadInput;
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
  std::printf("%-17s %-9s %-9s gen %-9s best %-12s evals %-8llu %6.1f s  %s%s%s\n", i.job_id.c_str(),
              (std::string(service::JobStateName(i.state)) + (i.archived ? "*" : "")).c_str(), i.kind.c_str(),
              Generation(i).c_str(),
              i.generation == 0 ? "-" : Num(i.best_cost, 8).c_str(),
              static_cast<unsigned long long>(i.evaluations), i.elapsed_s, i.name.c_str(),
              i.quarantined.empty() ? "" : ("  quarantined " + std::to_string(i.quarantined.size())).c_str(),
              i.message.empty() ? "" : ("  (" + i.message + ")").c_str());
  if (!i.storage_error.empty())
    std::printf("%-17s   ! checkpoints not written: %s\n", "", i.storage_error.c_str());
  if (!i.notice.empty()) std::printf("%-17s   ! on loading: %s\n", "", i.notice.c_str());
}

void PrintList(const std::vector<service::JobInfo>& all, int workers, int threads) {
  std::printf("%d worker%s (%d thread%s), %zu job%s\n", workers, workers == 1 ? "" : "s", threads, threads == 1 ? "" : "s", all.size(),
              all.size() == 1 ? "" : "s");
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
                  storage_error_.empty() ? "checkpoints are written again"
                                         : ("! checkpoints not written (a master restart would lose progress): " +
                                            storage_error_).c_str());
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
    std::snprintf(line, sizeof line, "gen %4llu/%-4llu [%s] best %-*s %7.0f evals/s  %d worker%s (%d threads)",
                  static_cast<unsigned long long>(r.generation), static_cast<unsigned long long>(max_), bar.c_str(),
                  hgann_ ? 17 : 14, best.c_str(), rate, e.workers, e.workers == 1 ? "" : "s", e.worker_threads);
    const std::string islands = IslandsBrief(r);
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

}  // namespace

void RegisterServiceCommands(CLI::App& app, int& exit_code) {
  auto common = std::make_shared<Common>();
  common->master = DefaultMaster();
  auto job_id = std::make_shared<std::string>();
  auto path = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto name = std::make_shared<std::string>("piezoid_predict");
  auto count = std::make_shared<int>(5);
  auto no_plots = std::make_shared<bool>(false);
  auto token = std::make_shared<std::string>();

  // ---------------------------------------------------------------- submit
  auto* submit = app.add_subcommand(
      "submit", "submit a job spec (protobuf JSON, see examples/): prints the job id on stdout");
  AddCommon(submit, *common);
  submit->add_option("spec", *path, "job spec file (an hgann spec's case_set_dir is read here, relative to it)")
      ->required();
  submit->add_option("--client-token", *token,
                     "idempotence token: submitting the same spec with the same token again returns the same job "
                     "(default: a random one)");
  auto embedded_out = std::make_shared<std::string>();
  submit->add_option("--write-embedded", *embedded_out,
                     "write the checked spec with its case data embedded (protobuf JSON, what the Python client "
                     "submits) to this file instead of submitting it");
  submit->callback([=, &exit_code] {
    job::JobSpec spec;
    std::vector<job::FieldViolation> v;
    Status s = LoadJobSpecFile(*path, &spec, &v);
    if (!s.ok()) {
      exit_code = ReportViolations("job spec " + *path, v, s);
      return;
    }
    // Checked here first (same rules as the master), so a bad spec needs no master to be told.
    v = kinds::All().Validate(spec);
    if (!v.empty()) {
      exit_code = ReportViolations("job spec " + *path, v, InvalidArgument("invalid"));
      return;
    }
    if (!embedded_out->empty()) {
      std::ofstream f(*embedded_out, std::ios::binary);
      f << service::JobSpecToJson(spec) << "\n";
      f.close();
      if (!f) {
        exit_code = Report({StatusCode::kInternal, *embedded_out + ": cannot write"});
        return;
      }
      std::fprintf(stderr, "piezoid: wrote %s (the spec with its data embedded; not submitted)\n", embedded_out->c_str());
      exit_code = kExitOk;
      return;
    }
    SubmitResult r;
    s = common->Client().Submit(spec, &r, &v, *token);
    if (!s.ok()) {
      exit_code = s.code() == StatusCode::kInvalidArgument ? ReportViolations("job spec " + *path, v, s) : Report(s);
      return;
    }
    std::printf("%s\n", r.job_id.c_str());
    if (r.existed) std::fprintf(stderr, "piezoid: job %s had already been submitted\n", r.job_id.c_str());
    exit_code = kExitOk;
  });

  // ---------------------------------------------------------------- status / list
  auto* status = app.add_subcommand("status", "a job's state and progress (every job without an id)");
  AddCommon(status, *common);
  status->add_option("job", *job_id, "job id (optional)");
  status->callback([=, &exit_code] {
    ServiceClient c = common->Client();
    if (job_id->empty()) {
      std::vector<service::JobInfo> all;
      int workers = 0, threads = 0;
      Status s = c.List(&all, &workers, &threads);
      if (s.ok()) PrintList(all, workers, threads);
      exit_code = Report(s);
      return;
    }
    service::JobInfo i;
    Status s = c.GetStatus(*job_id, &i);
    if (s.ok()) PrintInfo(i);
    exit_code = Report(s);
  });

  auto* list = app.add_subcommand("list", "the master's jobs and workers");
  list->alias("jobs");
  AddCommon(list, *common);
  list->callback([=, &exit_code] {
    std::vector<service::JobInfo> all;
    int workers = 0, threads = 0;
    Status s = common->Client().List(&all, &workers, &threads);
    if (s.ok()) PrintList(all, workers, threads);
    exit_code = Report(s);
  });

  // ---------------------------------------------------------------- cancel
  auto* cancel = app.add_subcommand("cancel", "cancel a running job (its checkpoint stays fetchable)");
  AddCommon(cancel, *common);
  cancel->add_option("job", *job_id, "job id")->required();
  cancel->callback([=, &exit_code] {
    Status s = common->Client().Cancel(*job_id);
    if (s.ok()) std::printf("%s cancelled\n", job_id->c_str());
    exit_code = Report(s);
  });

  // ---------------------------------------------------------------- prune
  auto* prune = app.add_subcommand(
      "prune", "delete ended jobs from the master (memory and state directory): those named, or by age / count");
  AddCommon(prune, *common);
  auto prune_ids = std::make_shared<std::vector<std::string>>();
  auto older_days = std::make_shared<double>(0);
  auto keep = std::make_shared<int>(0);
  auto dry_run = std::make_shared<bool>(false);
  prune->add_option("jobs", *prune_ids, "ended jobs to delete (running ones are refused)");
  prune->add_option("--older-than", *older_days, "delete the ended jobs that ended more than DAYS ago")
      ->check(CLI::PositiveNumber);
  prune->add_option("--keep", *keep, "delete all but the N most recently ended jobs")->check(CLI::Range(1, 100000000));
  prune->add_flag("--dry-run", *dry_run, "list what would be deleted, delete nothing");
  prune->callback([=, &exit_code] {
    if (prune_ids->empty() && *older_days <= 0 && *keep <= 0) {
      std::fprintf(stderr, "piezoid prune: name the jobs, or give --older-than DAYS or --keep N\n");
      exit_code = kExitBadInput;
      return;
    }
    std::vector<std::string> pruned;
    std::vector<job::FieldViolation> refused;
    Status s = common->Client().Prune(*prune_ids, *older_days * 86400.0, *keep, *dry_run, &pruned, &refused);
    if (!s.ok()) {
      exit_code = Report(s);
      return;
    }
    for (const auto& id : pruned) std::printf("%s %s\n", *dry_run ? "would prune" : "pruned", id.c_str());
    for (const auto& v : refused) std::fprintf(stderr, "piezoid prune: %s: %s\n", v.field.c_str(), v.description.c_str());
    if (pruned.empty() && refused.empty()) std::printf("nothing to prune\n");
    exit_code = refused.empty() ? kExitOk : kExitJobNotOk;
  });

  // ---------------------------------------------------------------- watch
  auto* watch = app.add_subcommand(
      "watch", "follow a job until it ends: generation, best cost, evaluations/s, workers; then the result");
  AddCommon(watch, *common);
  watch->add_option("job", *job_id, "job id")->required();
  watch->callback([=, &exit_code] {
    ServiceClient c = common->Client();
    service::JobInfo info;
    Status s = c.GetStatus(*job_id, &info);
    if (!s.ok()) {
      exit_code = Report(s);
      return;
    }
    std::printf("job %s (%s%s%s), %llu generations at most\n", job_id->c_str(), info.kind.c_str(),
                info.name.empty() ? "" : ": ", info.name.c_str(),
                static_cast<unsigned long long>(info.max_generations));
    if (!info.notice.empty()) std::printf("! on loading: %s\n", info.notice.c_str());
    Progress progress(info.max_generations, info.kind == "hgann");
    s = c.Watch(
        *job_id,
        [&progress](const service::JobEvent& e) {
          progress.Update(e);
          return true;
        },
        std::chrono::hours(24 * 365));
    progress.End();
    if (!s.ok()) {
      exit_code = Report(s);
      return;
    }
    s = c.GetStatus(*job_id, &info);
    if (!s.ok()) {
      exit_code = Report(s);
      return;
    }
    std::printf("job %s %s (%s) after %llu generations: best cost %s%s, %llu evaluations in %.1f s\n",
                job_id->c_str(), service::JobStateName(info.state), info.message.c_str(),
                static_cast<unsigned long long>(info.generation > 0 ? info.generation - 1 : 0),
                Num(info.best_cost, 9).c_str(), info.kind == "hgann" ? " deg²" : "",
                static_cast<unsigned long long>(info.evaluations), info.elapsed_s);
    if (info.state == service::JobState::kSucceeded || info.generation > 0)
      std::printf("fetch the result: piezoid fetch %s --out <folder>\n", job_id->c_str());
    exit_code = info.state == service::JobState::kSucceeded ? kExitOk : kExitJobNotOk;
  });

  // ---------------------------------------------------------------- fetch
  auto* fetch = app.add_subcommand(
      "fetch", "write a job's best networks (.pb, .json) and, for hgann jobs, the report of `piezoid identify`");
  AddCommon(fetch, *common);
  fetch->add_option("job", *job_id, "job id")->required();
  fetch->add_option("--best,-n", *count, "how many of the best individuals (1 … 32)")
      ->check(CLI::Range(1, 32))
      ->capture_default_str();
  fetch->add_option("--out,-o", *out, "result folder (default: ./<job id>)");
  fetch->add_flag("--no-plots", *no_plots, "do not render figures (gnuplot scripts are still written)");
  fetch->callback([=, &exit_code] {
    FetchedJob job;
    Status s = common->Client().Fetch(*job_id, *count, &job.best, &job.log, &job.info, &job.spec, &job.networks);
    if (!s.ok()) {
      exit_code = Report(s);
      return;
    }
    if (!service::IsFinal(job.info.state))
      std::fprintf(stderr, "piezoid: note: job %s is still %s (generation %llu): this is the best so far\n",
                   job_id->c_str(), service::JobStateName(job.info.state),
                   static_cast<unsigned long long>(job.info.generation));
    const fs::path dir = out->empty() ? fs::path(*job_id) : fs::path(*out);
    FetchOutput o;
    s = WriteFetchedJob(job, dir, !*no_plots, std::cout, &o);
    std::cout.flush();
    if (s.ok() && !o.report.empty()) std::printf("report: %s\n", o.report.string().c_str());
    exit_code = Report(s);
  });

  // ---------------------------------------------------------------- export
  auto* exp = app.add_subcommand(
      "export", "write a network file (.pb or .json) as a standalone C header for a controller");
  exp->add_option("network", *path, "network file (from fetch or identify)")->required();
  exp->add_option("--out,-o", *out, "header file to write (default: stdout)");
  exp->add_option("--name", *name, "name of the C function (a C identifier)")->capture_default_str();
  exp->callback([=, &exit_code] {
    io::SavedNetwork net;
    Status s = io::LoadNetwork(*path, &net);
    if (!s.ok()) {
      exit_code = Report(InvalidArgument(s.message()));
      return;
    }
    std::string header;
    s = NetworkToCHeader(net, *name, &header);
    if (!s.ok()) {
      exit_code = Report(s);
      return;
    }
    if (out->empty()) {
      std::fwrite(header.data(), 1, header.size(), stdout);
    } else {
      std::ofstream f(*out, std::ios::binary);
      f << header;
      f.close();
      if (!f) {
        exit_code = Report({StatusCode::kInternal, *out + ": cannot write"});
        return;
      }
      std::fprintf(stderr, "piezoid: wrote %s: %s(amplitude_v, frequency_hz, p[7])\n", out->c_str(), name->c_str());
    }
    exit_code = kExitOk;
  });

  // ---------------------------------------------------------------- dashboard
  auto* dash = app.add_subcommand(
      "dashboard", "serve a live web page of the master's jobs, fitness curves, workers and reports (read-only)");
  AddCommon(dash, *common);
  auto listen = std::make_shared<std::string>("127.0.0.1:8080");
  auto token_file = std::make_shared<std::string>();
  auto poll_ms = std::make_shared<int>(1000);
  auto reports = std::make_shared<std::string>();
  auto cache = std::make_shared<std::string>();
  auto endpoints_file = std::make_shared<std::string>();
  dash->add_option("--listen", *listen,
                   "HOST:PORT to serve on (PORT 0: any free port; beyond loopback needs --token-file)")
      ->capture_default_str();
  dash->add_option("--token-file", *token_file,
                   "file whose first line is the access token every request must carry (?token= or a Bearer "
                   "header); required beyond loopback or with CURVE");
  dash->add_option("--poll-ms", *poll_ms, "how often the master is polled [ms]")->capture_default_str();
  dash->add_option("--reports", *reports, "also serve the report folders (each with a report.md) under this folder");
  dash->add_option("--cache", *cache, "where ended jobs' reports are built (default: a temporary folder)");
  dash->add_option("--url-file", *endpoints_file, "write the dashboard's URL to this file once it listens");
  auto dash_no_plots = std::make_shared<bool>(false);
  dash->add_flag("--no-plots", *dash_no_plots, "build job reports without figures (no gnuplot)");
  dash->callback([=, &exit_code] {
    DashboardOptions o;
    o.client = ClientOptionsOf(common->master, common->timeout_ms, common->retries, common->curve_secret,
                               common->master_public);
    const size_t colon = listen->rfind(':');
    if (colon == std::string::npos || colon + 1 == listen->size()) {
      exit_code = Report(InvalidArgument("--listen '" + *listen + "': must be HOST:PORT, e.g. 127.0.0.1:8080"));
      return;
    }
    o.host = listen->substr(0, colon);
    if (o.host.size() > 2 && o.host.front() == '[' && o.host.back() == ']') o.host = o.host.substr(1, o.host.size() - 2);
    try {
      size_t used = 0;
      o.port = std::stoi(listen->substr(colon + 1), &used);
      if (used != listen->size() - colon - 1) throw std::invalid_argument("trailing characters");
    } catch (const std::exception&) {
      exit_code = Report(InvalidArgument("--listen '" + *listen + "': the port must be a number in [0, 65535]"));
      return;
    }
    if (!token_file->empty()) {
      std::ifstream f(*token_file);
      if (!f || !std::getline(f, o.token)) {
        exit_code = Report(InvalidArgument("--token-file " + *token_file + ": cannot read its first line"));
        return;
      }
      while (!o.token.empty() && std::isspace(static_cast<unsigned char>(o.token.back()))) o.token.pop_back();
    }
    o.poll_ms = *poll_ms;
    o.reports_dir = *reports;
    o.cache_dir = *cache;
    o.plots = !*dash_no_plots;
    // SIGINT / SIGTERM end the dashboard: blocked here (every thread inherits the mask), awaited below.
    sigset_t signals;
    sigemptyset(&signals);
    sigaddset(&signals, SIGINT);
    sigaddset(&signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &signals, nullptr);
    Dashboard d(o);
    if (Status s = d.Start(); !s.ok()) {
      exit_code = Report(s);
      return;
    }
    if (!endpoints_file->empty()) {
      const std::string tmp = *endpoints_file + ".tmp";
      std::ofstream(tmp) << d.url() << "\n";
      std::error_code ec;
      fs::rename(tmp, *endpoints_file, ec);
    }
    std::printf("piezoid dashboard of %s on %s%s (Ctrl-C to stop)\n", o.client.endpoint.c_str(), d.url().c_str(),
                o.token.empty() ? "" : "?token=…");
    std::fflush(stdout);
    int sig = 0;
    sigwait(&signals, &sig);
    d.Stop();
    exit_code = kExitOk;
  });

  RegisterKeygen(app, exit_code);
}

}  // namespace pz::client
