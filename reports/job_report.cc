#include "reports/job_report.h"

#include <chrono>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

#include "hgann/hgann_job.h"
#include "job/job_kind.h"
#include "model/chromosome.h"
#include "service/wire_codec.h"

namespace pz::reports {
namespace fs = std::filesystem;

opt::GaSummary GaSummaryOfJob(const FetchedJob& job) {
  opt::GaSummary s;
  const job::GaSettings ga = job.spec.ga.value_or(job::GaSettings{});
  s.islands = ga.islands;
  if (!job.best.empty()) {
    s.best = job.best.front().genome;
    s.best_fitness = job.best.front().fitness;
  }
  for (const auto& r : job.log) {
    if (r.improved) {
      s.best_generation = r.generation;
      s.best_island = r.best_island;
    }
    s.failures += r.failures;
  }
  if (!job.log.empty()) {
    s.generations = job.log.back().generation;
    s.evaluations = job.log.back().evaluations_total;
  }
  s.wall_time_s = job.info.elapsed_s;
  // A job that ended by the GA's rule carries the rule (JobInfo::termination); the GA's own text
  // is rebuilt from the stored state by the same function the GA uses.
  const std::string& m = job.info.message;
  const auto rule = job.info.termination;
  const int stall = job.log.empty() ? 0 : static_cast<int>(job.log.back().stall);
  const double target =
      job.spec.limits.target_cost.value_or(-std::numeric_limits<double>::infinity());
  std::ostringstream os;
  if (job.info.state == service::JobState::kRunning) {
    s.termination = opt::GaTermination::kCancelled;
    os << "job " << job.info.job_id << " is still running at the master: the best after generation "
       << s.generations << " so far";
  } else if (job.info.state == service::JobState::kCancelled) {
    s.termination = opt::GaTermination::kCancelled;
    os << "cancelled after generation " << s.generations;
  } else if (job.info.state == service::JobState::kFailed) {
    s.termination = opt::GaTermination::kCancelled;
    os << "job failed after generation " << s.generations << ": " << m;
  } else {
    s.termination = rule.value_or(opt::GaTermination::kMaxGenerations);
    os << opt::DescribeTermination(s.termination, s.best_fitness.cost, stall, s.best_generation,
                                   s.generations, ga.generations, target);
  }
  s.message = os.str();
  return s;
}

io::SavedNetwork SavedNetworkOfJob(const FetchedJob& job, const hgann::HgannFitness& fitness,
                                   size_t k) {
  PZ_CHECK(k < job.best.size());
  io::SavedNetwork n;
  n.network = fitness.Decode(job.best[k].genome);
  n.chromosome = job.best[k].genome.bits;
  auto& p = n.provenance;
  p.job_id = job.info.job_id;
  p.seed = job.spec.seed;
  // The best was found in the last improving generation; the others are members of the last
  // population, which is all the master keeps of them.
  const opt::GaSummary s = GaSummaryOfJob(job);
  p.generation = k == 0 ? s.best_generation : s.generations;
  p.fitness = job.best[k].fitness.cost;
  p.created_unix_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  p.piezoid_version = PIEZOID_VERSION;
  for (const auto& c : fitness.config().cases)
    if (c.training) p.training_cases.push_back("case" + std::to_string(c.number));
  return n;
}

hgann::IdentifyResult IdentifyResultOfJob(const FetchedJob& job,
                                          const hgann::HgannFitness& fitness) {
  hgann::IdentifyResult r;
  r.summary = GaSummaryOfJob(job);
  r.log = job.log;  // the records are the GA's own summaries
  r.best = SavedNetworkOfJob(job, fitness, 0);
  r.cases = fitness.EvaluateCases(r.best.network);
  r.committee = job.committee;  // the master's, computed as identify computes it
  return r;
}

IdentifyOptions IdentifyOptionsOfJob(const FetchedJob& job, const fs::path& out_dir, bool plots) {
  IdentifyOptions o;
  o.out_dir = out_dir;
  const auto* h = std::get_if<job::HgannProblem>(&job.spec.problem);
  o.cases_dir = h ? h->source : "";
  o.ga = job::ToGaOptions(job.spec, job::GenomeLayout{model::kChromosomeBits, 0});
  o.threads = 1;
  if (h) {
    o.ranges = h->ranges_preset.empty() ? "default" : h->ranges_preset;
    if (!h->ranges.empty()) {
      o.ranges += " with overrides of";
      for (const auto& r : h->ranges) o.ranges += " " + r.name;
    }
    o.spread_penalty = h->spread_penalty;
    o.trend_seeds = h->trend_seeds;
    o.preset = h->preset.empty() ? job::kDefaultHgannPreset : h->preset;
  }
  o.plots = plots;
  o.job_id = job.info.job_id;
  return o;
}

namespace {

void WriteProgressCsv(const fs::path& file, const std::vector<service::GenerationRecord>& log) {
  std::ofstream f(file);
  f << "generation,best_cost,median_cost,mean_cost,worst_cost,stall,evaluations,evaluations_total,"
       "failures,penalized,"
       "quarantined,wall_time_s,best_description"
    << IslandCsvHeader(log) << "\n";
  f << std::setprecision(17);
  for (const auto& g : log)
    f << g.generation << "," << g.best_cost << "," << g.median_cost << "," << g.mean_cost << ","
      << g.worst_cost << "," << g.stall << "," << g.evaluations << "," << g.evaluations_total << ","
      << g.failures << "," << g.penalized << "," << g.quarantined << "," << g.wall_time_s << ",\""
      << g.best_description << "\"" << IslandCsvCells(g) << "\n";
}

}  // namespace

Status WriteFetchedJob(const FetchedJob& job, const fs::path& out, bool plots, std::ostream& term,
                       FetchOutput* result) {
  FetchOutput local;
  FetchOutput& o = result ? *result : local;
  if (job.best.empty())
    return {StatusCode::kFailedPrecondition,
            "job " + job.info.job_id + " has no evaluated individual yet (generation " +
                std::to_string(job.info.generation) + "): fetch it again later"};
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) return InvalidArgument(out.string() + ": cannot create the folder: " + ec.message());

  const auto* h = std::get_if<job::HgannProblem>(&job.spec.problem);
  if (!h) {
    {
      std::ofstream f(out / "best.csv");
      f << "rank,index,cost,status,reason,bits\n" << std::setprecision(17);
      for (size_t k = 0; k < job.best.size(); ++k) {
        const auto& b = job.best[k];
        f << k + 1 << "," << b.index << "," << b.fitness.cost << ","
          << static_cast<int>(b.fitness.status) << ",\"" << b.fitness.reason << "\","
          << service::BitString(b.genome) << "\n";
      }
    }
    o.written.push_back(out / "best.csv");
    WriteProgressCsv(out / "progress.csv", job.log);
    o.written.push_back(out / "progress.csv");
    term << "job " << job.info.job_id << " (" << job.info.kind << "): best cost "
         << job.best.front().fitness.cost << "; " << job.best.size() << " individuals in "
         << (out / "best.csv").string() << ", log in " << (out / "progress.csv").string() << "\n";
    return Status::Ok();
  }

  hgann::HgannFitnessConfig config;
  if (Status s = hgann::HgannConfigFromProblem(*h, &config); !s.ok())
    return {s.code(), "the job's spec does not build its fitness here: " + s.message()};
  try {
    const hgann::HgannFitness fitness(std::move(config));
    fs::create_directories(out / "networks");
    for (size_t k = 0; k < job.best.size(); ++k) {
      // The master's networks; a master from before fetch returned them: decoded here.
      const io::SavedNetwork n =
          k < job.networks.size() ? job.networks[k] : SavedNetworkOfJob(job, fitness, k);
      for (const char* ext : {".pb", ".json"}) {
        const fs::path p = out / "networks" / ("best-" + std::to_string(k + 1) + ext);
        if (Status s = io::SaveNetwork(n, p.string()); !s.ok()) return s;
        o.written.push_back(p);
      }
    }
    io::CaseSet set = hgann::HgannCaseSet(*h);
    if (set.dir.empty()) set.dir = "job " + job.info.job_id;
    const hgann::IdentifyResult r = IdentifyResultOfJob(job, fitness);
    const auto files =
        WriteIdentifyReport(IdentifyOptionsOfJob(job, out, plots), set, fitness, r, term);
    o.written.insert(o.written.end(), files.begin(), files.end());
    o.report = out / "report.md";
    term << job.best.size() << " best networks in " << (out / "networks").string()
         << " (best-1 … best-" << job.best.size() << ", .pb and .json)\n";
  } catch (const InputError& e) {
    return InvalidArgument(e.what());
  }
  return Status::Ok();
}

}  // namespace pz::reports
