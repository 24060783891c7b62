// `piezoid submit | status | list | watch | cancel | fetch | export`: the service commands, thin
// wrappers of svcclient/service_client.h, svcclient/job_file.h, client/job_report.h and
// controller/export_c.h. Register with RegisterServiceCommands(app, exit_code).
#include "client/cmd_service.h"

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
#include "client/dashboard.h"
#include "client/fit_file.h"
#include "svcclient/job_file.h"
#include "client/job_report.h"
#include "svcclient/service_client.h"
#include "controller/export_c.h"
#include "hgann/hgann_job.h"
#include "job/job_kind.h"
#include "kinds/kinds.h"
#include "model/modal_simulator.h"
#include "service/wire_codec.h"

namespace pz::client {
namespace fs = std::filesystem;

int ExitCodeOf(const Status& s) {
  switch (s.code()) {
    case StatusCode::kOk:
      return kExitOk;
    case StatusCode::kInvalidArgument:
      return kExitBadInput;
    case StatusCode::kUnavailable:
      return kExitUnreachable;
    case StatusCode::kNotFound:
      return kExitUnknownJob;
    case StatusCode::kFailedPrecondition:
      return kExitJobNotOk;
    default:
      return kExitFailure;
  }
}

svcclient::ServiceClientOptions ClientOptionsOf(const std::string& master, int timeout_ms,
                                                int retries, const std::string& curve_secret,
                                                const std::string& master_public) {
  svcclient::ServiceClientOptions o;
  o.endpoint = master;
  o.timeout_ms = timeout_ms;
  o.retries = retries;
  if (curve_secret.empty() != master_public.empty())
    throw InputError(curve_secret.empty() ? "--master-public (or PIEZOID_MASTER_PUBLIC) needs "
                                            "--curve-secret (or PIEZOID_CURVE_SECRET)"
                                          : "--curve-secret (or PIEZOID_CURVE_SECRET) needs "
                                            "--master-public (or PIEZOID_MASTER_PUBLIC)");
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
  std::string curve_secret = Env("PIEZOID_CURVE_SECRET"),
              master_public = Env("PIEZOID_MASTER_PUBLIC");
  /// The client of these options; a bad key file throws InputError (exit code 2).
  svcclient::ServiceClient Client() const {
    return svcclient::ServiceClient(
        ClientOptionsOf(master, timeout_ms, retries, curve_secret, master_public));
  }
};

std::string DefaultMaster() { return Env("PIEZOID_MASTER", "tcp://127.0.0.1:5556"); }

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

int Report(const Status& s) {
  if (s.ok()) return kExitOk;
  std::fprintf(stderr, "piezoid: error: %s\n", s.message().c_str());
  return ExitCodeOf(s);
}

/// Prints every violation; returns the exit code for an invalid spec.
int ReportViolations(const std::string& what, const std::vector<job::FieldViolation>& v,
                     const Status& s) {
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

/// Writes text to path: kExitOk, or the exit code after saying that it cannot.
int WriteFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  f.close();
  return f ? kExitOk : Report({StatusCode::kInternal, path + ": cannot write"});
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
    if (int code = WriteFile(o.embedded_out, service::JobSpecToJson(spec) + "\n"); code != kExitOk)
      return code;
    std::fprintf(stderr, "piezoid: wrote %s (the spec with its data embedded; not submitted)\n",
                 o.embedded_out.c_str());
    return kExitOk;
  }
  svcclient::SubmitResult r;
  s = o.Client().Submit(spec, &r, &v, o.token);
  if (!s.ok())
    return s.code() == StatusCode::kInvalidArgument ? ReportViolations("job spec " + o.spec, v, s)
                                                    : Report(s);
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
  return Report(s);
}

int ShowStatus(const StatusOptions& o) {
  if (o.job_id.empty()) return ListJobs(o);
  service::JobInfo i;
  Status s = o.Client().GetStatus(o.job_id, &i);
  if (s.ok()) PrintInfo(i);
  return Report(s);
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
  return Report(s);
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
  if (!s.ok()) return Report(s);
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
  if (!s.ok()) return Report(s);
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
  if (!s.ok()) return Report(s);
  s = c.GetStatus(o.job_id, &info);
  if (!s.ok()) return Report(s);
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
  FetchedJob job;
  Status s =
      o.Client().Fetch(o.job_id, o.count, &job.best, &job.log, &job.info, &job.spec, &job.networks,
                       &job.committee);
  if (!s.ok()) return Report(s);
  if (!service::IsFinal(job.info.state))
    std::fprintf(stderr,
                 "piezoid: note: job %s is still %s (generation %llu): this is the best so far\n",
                 o.job_id.c_str(), service::JobStateName(job.info.state),
                 static_cast<unsigned long long>(job.info.generation));
  const fs::path dir = o.out.empty() ? fs::path(o.job_id) : fs::path(o.out);
  FetchOutput out;
  s = WriteFetchedJob(job, dir, !o.no_plots, std::cout, &out);
  std::cout.flush();
  if (s.ok() && !out.report.empty()) std::printf("report: %s\n", out.report.string().c_str());
  return Report(s);
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

// ---------------------------------------------------------------- export

struct ExportOptions {
  std::string network, out, name = "piezoid_predict", job;
  bool plant = false;
  controller::FinPlantExport fin;
};

/// The beam of the job spec `file` (its hgann.geometry overrides), and its cases' saturations as a
/// note for the header.
int JobBeam(const std::string& file, model::BeamGeometry* geometry, std::string* note) {
  job::JobSpec spec;
  std::vector<job::FieldViolation> v;
  Status s = svcclient::LoadJobSpecFile(file, &spec, &v);
  if (!s.ok()) return ReportViolations("job spec " + file, v, s);
  const auto* h = std::get_if<job::HgannProblem>(&spec.problem);
  if (!h) return Report(InvalidArgument(FieldError("--job", file, "is not an hgann job spec")));
  hgann::HgannFitnessConfig config;
  if (s = hgann::HgannConfigFromProblem(*h, &config); !s.ok()) return Report(s);
  *geometry = config.geometry;
  std::ostringstream n;
  n << "The beam of job spec " << fs::path(file).filename().string()
    << "; its cases' saturations [deg]";
  for (const auto& c : config.cases)
    n << (&c == &config.cases.front() ? ": " : ", ") << "case " << c.number << " ("
      << c.drive.amplitude_v << " V, " << c.drive.frequency_hz << " Hz) b1 " << CDecimal(c.b1)
      << " b2 " << CDecimal(c.b2);
  *note = n.str() + ".";
  return kExitOk;
}

/// The file `piezoid export` reads for PATH: PATH itself, or for a folder the first of fit.json
/// (piezoid fit), network.pb (identify; fetch of an hgann job) and networks/best-1.pb (fetch).
std::string ExportSource(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return path;
  for (const char* name : {"fit.json", "network.pb", "networks/best-1.pb"}) {
    const fs::path p = fs::path(path) / name;
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  throw InputError(
      path +
      ": a folder without fit.json, network.pb or networks/best-1.pb (what piezoid fit, identify "
      "and fetch write)");
}

int ExportNetwork(const ExportOptions& o) {
  const std::string source = ExportSource(o.network);
  // A fit.json (piezoid fit): the record model's header (client/cmd_compensate.cc).
  if (LooksLikeFitJson(source))
    return ExportFit(source, o.out, o.name == "piezoid_predict" ? "" : o.name);
  io::SavedNetwork net;
  Status s = io::LoadNetwork(source, &net);
  if (!s.ok()) return Report(InvalidArgument(s.message()));
  std::string header;
  if (o.plant) {
    model::BeamGeometry geometry;  // the spec's beam, as the HGANN fitness's default …
    controller::FinPlantExport fin = o.fin;
    if (!o.job.empty()) {  // … or the job's
      if (int code = JobBeam(o.job, &geometry, &fin.note); code != kExitOk) return code;
    }
    const model::BimorphPlant plant(geometry);
    const model::ModalSimulator sim(plant);
    s = controller::NetworkAndFinToCHeader(net, sim, fin, o.name, &header);
  } else {
    s = controller::NetworkToCHeader(net, o.name, &header);
  }
  if (!s.ok()) return Report(s);
  if (o.out.empty()) {
    std::fwrite(header.data(), 1, header.size(), stdout);
    return kExitOk;
  }
  if (int code = WriteFile(o.out, header); code != kExitOk) return code;
  if (o.plant)
    std::fprintf(stderr,
                 "piezoid: wrote %s: %s_params, %s_init, %s_step, %s_inverse_step at %g Hz\n",
                 o.out.c_str(), o.name.c_str(), o.name.c_str(), o.name.c_str(), o.name.c_str(),
                 o.fin.sample_rate_hz);
  else
    std::fprintf(stderr, "piezoid: wrote %s: %s(amplitude_v, frequency_hz, p[7])\n", o.out.c_str(),
                 o.name.c_str());
  return kExitOk;
}

void RegisterExport(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ExportOptions>();
  auto* c = app.add_subcommand("export",
                               "write a network file (.pb or .json) or a fit.json (piezoid fit) as "
                               "a standalone C header for a controller");
  c->add_option("network", o->network,
                "network file (from fetch or identify), fit.json of piezoid fit, or their folder "
                "(fit.json, network.pb or "
                "networks/best-1.pb in it)")
      ->required();
  c->add_option("--out,-o", o->out, "header file to write (default: stdout)");
  c->add_option("--name", o->name,
                "name of the C function (a C identifier; for a fit.json the prefix of its "
                "functions, default the header's file stem)")
      ->capture_default_str();
  auto* plant = c->add_flag("--plant", o->plant,
                            "add the bimorph-fin plant (spec beam) as a per-sample recursion: "
                            "NAME_init, NAME_step (drive -> angle), "
                            "NAME_inverse_step (angle -> drive)");
  c->add_option("--sample-rate", o->fin.sample_rate_hz,
                "the controller's sample rate [Hz] (with --plant)")
      ->needs(plant)
      ->capture_default_str();
  c->add_option("--drive-limit", o->fin.drive_limit_v,
                "|drive| limit [V] (with --plant; 0 = the largest training amplitude)")
      ->needs(plant)
      ->capture_default_str();
  c->add_option("--job", o->job,
                "the HGANN job spec (.json) the network was identified with: its beam "
                "(hgann.geometry) and, in a "
                "comment, its cases' saturations (with --plant; default: the spec's beam)")
      ->needs(plant);
  c->add_option("--inverse-horizon", o->fin.inverse_horizon,
                "samples over which NAME_inverse_step reaches the desired angle (with --plant; 1 = "
                "exact one-step "
                "inversion, unstable on this plant)")
      ->needs(plant)
      ->capture_default_str();
  OnRun(c, o, exit_code, ExportNetwork);
}

// ---------------------------------------------------------------- dashboard

struct DashboardFlags : Common {
  std::string listen = "127.0.0.1:8080", token_file, reports, cache, url_file;
  int poll_ms = 1000;
  bool no_plots = false;
};

/// The dashboard's options of its flags: InvalidArgument naming --listen or --token-file.
Status DashboardOptionsOf(const DashboardFlags& f, DashboardOptions* o) {
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
  DashboardOptions o;
  if (Status s = DashboardOptionsOf(f, &o); !s.ok()) return Report(s);
  // SIGINT / SIGTERM end the dashboard: blocked here (every thread inherits the mask), awaited
  // below.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  Dashboard d(o);
  if (Status s = d.Start(); !s.ok()) return Report(s);
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
  RegisterExport(app, exit_code);
  RegisterDashboard(app, exit_code);
  RegisterKeygen(app, exit_code);
  RegisterDoctor(app, exit_code);
}

// ---- the flags of searches on a master ----

CompleteServiceFlags::CompleteServiceFlags()
    : curve_secret(Env("PIEZOID_CURVE_SECRET")), master_public(Env("PIEZOID_MASTER_PUBLIC")) {}

svcclient::ServiceEvaluatorOptions CompleteServiceFlags::Options() const {
  svcclient::ServiceEvaluatorOptions o;
  o.client = ClientOptionsOf(master, timeout_ms, retries, curve_secret, master_public);
  return o;
}

void AddCompleteServiceFlags(CLI::App* cmd, CompleteServiceFlags& f) {
  cmd->add_option("--master", f.master,
                  "run every evaluation of the searches on the workers of this piezoid-master (its "
                  "client endpoint, "
                  "e.g. tcp://127.0.0.1:5556), one evaluation session per search or fit: the same "
                  "result, bit for "
                  "bit, as the local run")
      ->type_name("ENDPOINT");
  cmd->add_option("--timeout-ms", f.timeout_ms, "with --master: per-request timeout [ms]")
      ->check(CLI::Range(10, 3600000))
      ->capture_default_str();
  cmd->add_option("--retries", f.retries, "with --master: attempts per request")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option(
      "--curve-secret", f.curve_secret,
      "with --master, CURVE: this client's key pair, NAME.key from `piezoid keygen` (default: "
      "$PIEZOID_CURVE_SECRET)");
  cmd->add_option(
      "--master-public", f.master_public,
      "with --master, CURVE: the master's public key file (default: $PIEZOID_MASTER_PUBLIC)");
}

}  // namespace pz::client
