// `piezoid submit | status | watch | jobs | cancel | fetch`: the service commands, thin wrappers
// of client/service_client.h. Register with RegisterServiceCommands(app, exit_code).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "client/cmd_service.h"
#include "client/service_client.h"
#include "master/wire_codec.h"

namespace pz::client {
namespace {

struct Common {
  std::string master = "tcp://127.0.0.1:5556";
  int timeout_ms = 5000;
};

void AddCommon(CLI::App* c, Common& o) {
  c->add_option("--master", o.master, "the master's client endpoint")->capture_default_str();
  c->add_option("--timeout-ms", o.timeout_ms, "per-request timeout [ms]")->capture_default_str();
}

int Report(const Status& s) {
  if (s.ok()) return 0;
  std::fprintf(stderr, "piezoid: error: %s\n", s.ToString().c_str());
  return s.code() == StatusCode::kInvalidArgument ? 2 : 1;
}

void PrintInfo(const master::JobInfo& i) {
  std::printf("%s  %-9s  %-9s  gen %llu/%llu  best %.9g  evals %llu  %s%s\n", i.job_id.c_str(),
              master::JobStateName(i.state), i.kind.c_str(),
              static_cast<unsigned long long>(i.generation),
              static_cast<unsigned long long>(i.max_generations), i.best_cost,
              static_cast<unsigned long long>(i.evaluations), i.name.c_str(),
              i.quarantined.empty() ? "" : ("  quarantined " + std::to_string(i.quarantined.size())).c_str());
}

}  // namespace

void RegisterServiceCommands(CLI::App& app, int& exit_code) {
  auto common = std::make_shared<Common>();
  auto job_id = std::make_shared<std::string>();
  auto spec_path = std::make_shared<std::string>();
  auto count = std::make_shared<int>(1);

  auto* submit = app.add_subcommand("submit", "submit a job spec (protobuf JSON, see examples/)");
  AddCommon(submit, *common);
  submit->add_option("spec", *spec_path, "job spec file")->required()->check(CLI::ExistingFile);
  submit->callback([=, &exit_code] {
    std::ifstream in(*spec_path);
    std::stringstream ss;
    ss << in.rdbuf();
    ServiceClient c({common->master, common->timeout_ms, 3});
    SubmitResult r;
    std::vector<master::FieldViolation> v;
    Status s = c.SubmitJson(ss.str(), &r, &v);
    for (const auto& x : v) std::fprintf(stderr, "  %s\n", x.description.c_str());
    if (s.ok()) std::printf("%s%s\n", r.job_id.c_str(), r.existed ? " (already submitted)" : "");
    exit_code = Report(s);
  });

  auto* status = app.add_subcommand("status", "a job's state and progress");
  AddCommon(status, *common);
  status->add_option("job", *job_id)->required();
  status->callback([=, &exit_code] {
    ServiceClient c({common->master, common->timeout_ms, 3});
    master::JobInfo i;
    Status s = c.GetStatus(*job_id, &i);
    if (s.ok()) PrintInfo(i);
    exit_code = Report(s);
  });

  auto* jobs = app.add_subcommand("jobs", "list the master's jobs and workers");
  AddCommon(jobs, *common);
  jobs->callback([=, &exit_code] {
    ServiceClient c({common->master, common->timeout_ms, 3});
    std::vector<master::JobInfo> all;
    int workers = 0, threads = 0;
    Status s = c.List(&all, &workers, &threads);
    if (s.ok()) {
      std::printf("%d workers, %d threads\n", workers, threads);
      for (const auto& i : all) PrintInfo(i);
    }
    exit_code = Report(s);
  });

  auto* cancel = app.add_subcommand("cancel", "cancel a running job");
  AddCommon(cancel, *common);
  cancel->add_option("job", *job_id)->required();
  cancel->callback([=, &exit_code] {
    ServiceClient c({common->master, common->timeout_ms, 3});
    exit_code = Report(c.Cancel(*job_id));
  });

  auto* watch = app.add_subcommand("watch", "print a job's generations until it ends");
  AddCommon(watch, *common);
  watch->add_option("job", *job_id)->required();
  watch->callback([=, &exit_code] {
    ServiceClient c({common->master, common->timeout_ms, 3});
    Status s = c.Watch(
        *job_id,
        [](const master::JobEvent& e) {
          if (e.record)
            std::printf("gen %llu best %.9g mean %.6g evals %llu\n",
                        static_cast<unsigned long long>(e.record->generation), e.record->best_cost,
                        e.record->mean_cost, static_cast<unsigned long long>(e.record->evaluations));
          if (master::IsFinal(e.state))
            std::printf("%s %s\n", master::JobStateName(e.state), e.message.c_str());
          std::fflush(stdout);
          return true;
        },
        std::chrono::hours(24 * 365));
    exit_code = Report(s);
  });

  auto* fetch = app.add_subcommand("fetch", "the best individuals of a job");
  AddCommon(fetch, *common);
  fetch->add_option("job", *job_id)->required();
  fetch->add_option("-n,--count", *count, "how many")->capture_default_str();
  fetch->callback([=, &exit_code] {
    ServiceClient c({common->master, common->timeout_ms, 3});
    std::vector<master::ScoredGenome> best;
    master::JobInfo info;
    Status s = c.Fetch(*job_id, *count, &best, nullptr, &info);
    if (s.ok()) {
      PrintInfo(info);
      for (const auto& b : best)
        std::printf("%3d  %.17g  %s\n", b.index, b.fitness.cost, master::BitString(b.genome).c_str());
    }
    exit_code = Report(s);
  });
}

}  // namespace pz::client
