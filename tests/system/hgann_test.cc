// The real HGANN identification on the service, over real processes on 127.0.0.1: the bundled quick
// job (examples/hgann_quick.json: the nominal bench set, population 60 × 40 generations) over a
// master and 2 workers gives the same best networks and generation log, bit for bit, as the job run
// in this process; `piezoid submit / watch / status / list / fetch` work on it and fetch writes the
// networks and the report of `piezoid identify`; bad hgann specs are refused naming the field, by
// the client and by the master; an unreachable master and an unknown job give their message and
// exit code.
#include <gtest/gtest.h>

#include <fstream>
#include <optional>
#include <sstream>

#include "hgann/hgann_job.h"
#include "hgann/identify.h"
#include "hgann/loop_repair.h"
#include "hgann/output_move.h"
#include "io/network_io.h"
#include "job/job_kind.h"
#include "model/chromosome.h"
#include "reports/job_report.h"
#include "svcclient/job_file.h"
#include "tests/system/service_harness.h"
#include "tests/testing/pinned.h"

namespace pz::testing {
namespace {

using namespace std::chrono_literals;

const fs::path kExamples = fs::path(PIEZOID_DATA_DIR) / ".." / "examples";

job::JobSpec QuickSpec() {
  job::JobSpec spec;
  std::vector<job::FieldViolation> v;
  const Status s = svcclient::LoadJobSpecFile(kExamples / "hgann_quick.json", &spec, &v);
  PZ_CHECK_MSG(s.ok(), s.message());
  return spec;
}

bool HasField(const std::vector<job::FieldViolation>& v, const std::string& field) {
  for (const auto& x : v)
    if (x.field == field) return true;
  return false;
}

/// The in-process reference of the quick job, computed once for the tests of this file.
const service::JobCheckpoint& QuickReference() {
  static const service::JobCheckpoint ref = Reference(QuickSpec());
  return ref;
}

/// The job on a master with two 1-thread workers, run to its end (succeeded) and fetched.
void RunOnMasterAndTwoWorkers(const std::string& name, const job::JobSpec& spec,
                              service::JobInfo* info, std::vector<service::ScoredGenome>* best,
                              std::vector<service::GenerationRecord>* log,
                              std::optional<job::LawCommittee>* committee = nullptr) {
  Cluster c(name);
  c.AddWorker(1);
  c.AddWorker(1);
  auto client = c.Client();
  svcclient::SubmitResult r;
  ASSERT_TRUE(client.Submit(spec, &r).ok());
  ASSERT_TRUE(client.WaitFinal(r.job_id, 120s, info).ok());
  ASSERT_EQ(info->state, service::JobState::kSucceeded) << info->message;
  ASSERT_TRUE(
      client.Fetch(r.job_id, master::kBestKept, best, log, info, nullptr, nullptr, committee).ok());
}

TEST(ServiceHgann, QuickJobOverMasterAndTwoWorkersIsBitIdenticalToInProcess) {
  const job::JobSpec spec = QuickSpec();
  ASSERT_EQ(spec.kind(), "hgann");
  ASSERT_EQ(std::get<job::HgannProblem>(spec.problem).cases.size(), 9u);
  const service::JobCheckpoint& ref = QuickReference();
  ASSERT_EQ(ref.log.size(), 41u);
  EXPECT_FALSE(ref.log.back().best_description.empty());

  Cluster c("hgann");
  c.AddWorker(1);
  c.AddWorker(1);
  auto client = c.Client();
  svcclient::SubmitResult r;
  std::vector<job::FieldViolation> v;
  ASSERT_TRUE(client.Submit(spec, &r, &v).ok()) << (v.empty() ? "" : v.front().description);

  // `piezoid watch` follows it to the end and exits 0.
  std::string out, err;
  EXPECT_EQ(RunCli({"watch", r.job_id, "--master", c.client_endpoint()}, &out, &err), 0)
      << out << err;
  EXPECT_NE(out.find("succeeded"), std::string::npos) << out;

  service::JobInfo info;
  ASSERT_TRUE(client.WaitFinal(r.job_id, 50s, &info).ok());
  ASSERT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  std::vector<service::ScoredGenome> best;
  std::vector<service::GenerationRecord> log;
  job::JobSpec stored;
  std::vector<io::SavedNetwork> networks;
  ASSERT_TRUE(
      client.Fetch(r.job_id, master::kBestKept, &best, &log, &info, &stored, &networks).ok());
  ExpectSameRun(ref, best, log);
  EXPECT_EQ(service::EncodeJobSpec(stored),
            service::EncodeJobSpec(spec));  // the spec comes back intact

  // Fetch brings the networks themselves, as a client in any language deploys them: the same,
  // bit for bit, as this client's own decoding of the genomes and as the in-process run's.
  ASSERT_EQ(networks.size(), best.size());
  reports::FetchedJob job{info, stored, best, log, {}};
  hgann::HgannFitnessConfig config;
  ASSERT_TRUE(
      hgann::HgannConfigFromProblem(std::get<job::HgannProblem>(stored.problem), &config).ok());
  const hgann::HgannFitness fitness(config);
  for (size_t k = 0; k < networks.size(); ++k) {
    io::SavedNetwork mine = reports::SavedNetworkOfJob(job, fitness, k);
    mine.provenance.created_unix_ms = networks[k].provenance.created_unix_ms;
    EXPECT_EQ(networks[k], mine) << "network " << k;
    EXPECT_EQ(networks[k].network, fitness.Decode(ref.best[k].genome)) << "network " << k;
    EXPECT_TRUE(io::ValidateSavedNetwork(networks[k]).ok());
  }
  EXPECT_EQ(networks[0].provenance.fitness, ref.best[0].fitness.cost);
  EXPECT_EQ(networks[0].provenance.seed, spec.seed);
  EXPECT_EQ(networks[0].provenance.generation, ref.optimizer.best_generation);
  // The cap is said, not silently applied.
  std::vector<service::ScoredGenome> too_many;
  const Status capped = client.Fetch(r.job_id, master::kBestKept + 1, &too_many, &log);
  EXPECT_EQ(capped.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(capped.message().find("must be in [1, 32]"), std::string::npos) << capped.message();
}

TEST(ServiceHgann, FourIslandsOverMasterAndTwoWorkersAreBitIdenticalToPiezoidIdentify) {
  // The quick job as an archipelago: 4 islands of 30, a ring migration every 4 generations and a
  // gated broadcast every 3 between them,
  // islands restarted after 6 generations of their own stall, each island at its own mutation rate;
  // one dispatch of 4 × 15 per generation.
  job::JobSpec spec = QuickSpec();
  spec.ga->population = 30;
  spec.ga->generations = 16;
  spec.ga->islands = 4;
  spec.ga->migration_interval = 4;
  spec.ga->migrants = 2;
  spec.ga->island_stall_generations = 6;
  spec.ga->island_mutation = {0.01, 0.03, 0.01, 0.05};
  spec.ga->broadcast_interval = 3;  // a gated broadcast at 3, 6, 9, 15 between the migrations
  spec.ga->broadcast_margin = 1e-6;
  std::get<job::HgannProblem>(spec.problem).spread_penalty =
      10;  // with it, the islands' output moves
  const service::JobCheckpoint ref = Reference(spec);

  hgann::IdentifyOptions o;
  o.ga = job::ToGaOptions(spec, job::GenomeLayout{model::kChromosomeBits, 0});
  o.threads = 2;
  o.repair_loops = hgann::HgannRepairsLoops(std::get<job::HgannProblem>(spec.problem).preset);
  // The islands' default: each island's last 2 offspring of its 15 (16 %, rounded) are output moves
  // of its best, made by the master's job runner and by identify alike (a runner without them
  // differs).
  ASSERT_EQ(hgann::HgannOutputMoves(o.ga, 10), 2);
  o.spread_penalty = 10;
  hgann::HgannFitnessConfig config;
  ASSERT_TRUE(
      hgann::HgannConfigFromProblem(std::get<job::HgannProblem>(spec.problem), &config).ok());
  const hgann::HgannFitness fitness(config);
  const io::CaseSet set = hgann::HgannCaseSet(std::get<job::HgannProblem>(spec.problem));
  const hgann::IdentifyResult id = hgann::RunIdentify(o, set, fitness, nullptr);

  service::JobInfo info;
  std::vector<service::ScoredGenome> best;
  std::vector<service::GenerationRecord> log;
  ASSERT_NO_FATAL_FAILURE(RunOnMasterAndTwoWorkers("hgann-islands", spec, &info, &best, &log));
  EXPECT_EQ(info.termination, opt::GaTermination::kMaxGenerations);
  ExpectSameRun(ref, best, log);
  ASSERT_EQ(log.size(), id.log.size());
  for (size_t g = 0; g < log.size(); ++g) EXPECT_EQ(log[g], id.log[g]) << "generation " << g;
  EXPECT_EQ(log[0].evaluations, 4 * 30);
  EXPECT_EQ(log[1].evaluations, 4 * 15);
  EXPECT_EQ(best.front().genome.bits, id.best.chromosome);
  EXPECT_EQ(reports::GaSummaryOfJob({info, spec, best, log, {}}).best_island,
            id.summary.best_island);
}

TEST(ServiceHgann, TrendSeedsOverMasterAndTwoWorkersAreBitIdenticalToPiezoidIdentify) {
  // The new search (issue 36): generation 0 seeded by the master's job runner with the trend seeds
  // (hgann/trend_seeds.h), 2 islands with their output moves, the spread penalty; the same run as
  // `piezoid identify --trend-seeds true` bit for bit.
  job::JobSpec spec = QuickSpec();
  spec.ga->population = 30;
  spec.ga->generations = 8;
  spec.ga->islands = 2;
  auto& h = std::get<job::HgannProblem>(spec.problem);
  h.spread_penalty = 10;
  h.trend_seeds = true;
  // The user's feasible points for the next case (hgann.next_candidates, identify's
  // --next-candidates): the master's committee on the job's best is identify's, bit for bit.
  h.next_candidates = {{600, 0.4}, {750, 1.0}, {400, 0.8}};
  const service::JobCheckpoint ref = Reference(spec);

  hgann::IdentifyOptions o;
  o.ga = job::ToGaOptions(spec, job::GenomeLayout{model::kChromosomeBits, 0});
  o.threads = 2;
  o.repair_loops = hgann::HgannRepairsLoops(h.preset);
  o.spread_penalty = 10;
  o.trend_seeds = true;
  o.next_candidates = h.next_candidates;
  hgann::HgannFitnessConfig config;
  ASSERT_TRUE(hgann::HgannConfigFromProblem(h, &config).ok());
  const hgann::HgannFitness fitness(config);
  const io::CaseSet set = hgann::HgannCaseSet(h);
  const hgann::IdentifyResult id = hgann::RunIdentify(o, set, fitness, nullptr);
  ASSERT_TRUE(id.seeds.has_value());
  ASSERT_FALSE(id.seeds->genomes.empty());
  // The seeds are in generation 0: its best is no worse than the best seed.
  EXPECT_LE(id.log.front().best_cost, id.seeds->costs.front());

  service::JobInfo info;
  std::vector<service::ScoredGenome> best;
  std::vector<service::GenerationRecord> log;
  std::optional<job::LawCommittee> committee;
  ASSERT_NO_FATAL_FAILURE(
      RunOnMasterAndTwoWorkers("hgann-seeds", spec, &info, &best, &log, &committee));
  ExpectSameRun(ref, best, log);
  ASSERT_TRUE(id.committee.has_value());
  ASSERT_TRUE(committee.has_value());
  EXPECT_TRUE(*committee == *id.committee);
  ASSERT_EQ(committee->candidates.size(), 3u);  // the user's points, not the withheld cases
  EXPECT_EQ(committee->candidates.front().case_index, -1);
  EXPECT_EQ(committee->next.size(), 3u);
  ASSERT_EQ(log.size(), id.log.size());
  for (size_t g = 0; g < log.size(); ++g) EXPECT_EQ(log[g], id.log[g]) << "generation " << g;
  EXPECT_EQ(best.front().genome.bits, id.best.chromosome);
}

/// FNV-1a over what a run chose: its generation log's evaluations and its best genomes' bits.
/// The same on any arithmetic: a last-bit change in a cost flips a selection only between two
/// costs equal to 1e-12, which a population of 20 does not hold.
uint64_t ChoiceDigest(const service::JobCheckpoint& run) {
  uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](const void* p, size_t n) {
    for (size_t i = 0; i < n; ++i)
      h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ull;
  };
  for (const service::GenerationRecord& g : run.log) mix(&g.evaluations, sizeof g.evaluations);
  for (const service::ScoredGenome& b : run.best)
    for (bool bit : b.genome.bits) mix(&bit, 1);
  return h;
}

/// FNV-1a over a run's generation log (best cost's bits, evaluations) and best genomes (bits,
/// cost): the whole run, bit for bit.
uint64_t RunDigest(const service::JobCheckpoint& run) {
  uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](const void* p, size_t n) {
    for (size_t i = 0; i < n; ++i)
      h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ull;
  };
  for (const service::GenerationRecord& g : run.log) {
    mix(&g.best_cost, sizeof g.best_cost);
    mix(&g.evaluations, sizeof g.evaluations);
  }
  for (const service::ScoredGenome& b : run.best) {
    for (bool bit : b.genome.bits) mix(&bit, 1);
    mix(&b.fitness.cost, sizeof b.fitness.cost);
  }
  return h;
}

/// The costs a run found: each generation's best, then the best genomes'.
std::vector<double> RunCosts(const service::JobCheckpoint& run) {
  std::vector<double> c;
  for (const service::GenerationRecord& g : run.log) c.push_back(g.best_cost);
  for (const service::ScoredGenome& b : run.best) c.push_back(b.fitness.cost);
  return c;
}

/// A small job of the nominal bench as a user writes it: only the population, generations and the
/// fields in `extra`; everything else the spec's defaults.
job::JobSpec SmallJsonSpec(const std::string& extra) {
  job::JobSpec s;
  std::vector<job::FieldViolation> v;
  const std::string json = R"({"version": 1, "seed": "3", "hgann": {"case_set_dir": "nominal")" +
                           extra + R"(}, "ga": {"population": 20, "generations": 6}})";
  const Status st =
      svcclient::JobSpecFromJsonFile(json, fs::path(PIEZOID_DATA_DIR) / "bimorph-fin", &s, &v);
  PZ_CHECK_MSG(st.ok(), st.message());
  return s;
}

// The run of the paper preset's small job (below), pinned on tests/testing/pinned.h's arithmetic.
constexpr uint64_t kPaperChoices = 0x5075acffa0487a93ull;
const std::vector<double> kPaperCosts = {
    0x1.1c4ef5f3e0cf4p+11, 0x1.1c4ef5f3e0cf4p+11, 0x1.a31af9d6015f4p+9, 0x1.a31af9d6015f4p+9,
    0x1.920f5c75f5e3ap+9,  0x1.920f5c75f5e3ap+9,  0x1.84d66f19d3363p+9, 0x1.84d66f19d3363p+9,
    0x1.920f5c75f5e3ap+9,  0x1.920f5c75f5e3ap+9,  0x1.920f5c75f5e3ap+9, 0x1.920f5c75f5e3ap+9,
    0x1.920f5c75f5e3ap+9,  0x1.920f5c75f5e3ap+9,  0x1.920f5c75f5e3ap+9, 0x1.920f5c75f5e3ap+9,
    0x1.920f5c75f5e3ap+9,  0x1.9a29a17f5fc6cp+9,  0x1.a31af9d6015f4p+9, 0x1.a31af9d6015f4p+9,
    0x1.a372196154d14p+9,  0x1.2622200df4a6ep+10, 0x1.28bc67ce7527ep+10, 0x1.2a1b0ed385f9p+10,
    0x1.8bbd7121bda8cp+11, 0x1.b0c33fb58c118p+11, 0x1.8ae9c3de3c701p+13};

TEST(ServiceHgann, ThePaperPresetReproducesTheRunOfTheSpecDefaultsBeforeTheRobustOnes) {
  // Pinned from the same JSON without a preset before the spec's defaults became the robust
  // preset (one island, λ 0, no trend seeds): the paper preset gives that run bit for bit.
  // Its choices are pinned exactly (any arithmetic), its costs on the pins' arithmetic bit for bit
  // and elsewhere to 1e-9 relative: each is one simulation's PI summed over the training cases,
  // which another libm variant or kernel copy moves by ≈ 1e-13.
  const job::JobSpec paper = SmallJsonSpec(R"(, "preset": "paper")");
  const service::JobCheckpoint run = Reference(paper);
  EXPECT_EQ(ChoiceDigest(run), kPaperChoices) << std::hex << ChoiceDigest(run);
  const pz::testing::Pins pins(pz::testing::kPinnedArithmetic);
  if (pins.exact()) EXPECT_EQ(RunDigest(run), 0x2642364f9f918defull) << std::hex << RunDigest(run);
  EXPECT_TRUE(pins.Rel(RunCosts(run), kPaperCosts, 1e-9)) << [&run] {
    std::string s;  // the run's costs as hex-float literals, to pin them again
    for (double c : RunCosts(run)) {
      char b[32];
      std::snprintf(b, sizeof b, "%a, ", c);
      s += b;
    }
    return s;
  }();
  EXPECT_EQ(run.log[0].evaluations, 20u);

  // Without a preset the same JSON is the robust search: 4 islands of 20, λ 10, generation 0
  // seeded with the trend seeds (its best is no worse than theirs).
  const job::JobSpec robust = SmallJsonSpec("");
  const service::JobCheckpoint r = Reference(robust);
  EXPECT_EQ(r.log[0].evaluations, 80u);
  std::vector<opt::Genome> seeds;
  ASSERT_TRUE(kinds::All().Seeds(robust, &seeds).ok());
  ASSERT_FALSE(seeds.empty());
  EXPECT_LT(r.log[0].best_cost, 2.0);  // the seeds' ≈ 0.64 deg²; uniform bits start far above
  EXPECT_NE(ChoiceDigest(r), ChoiceDigest(run));
}

TEST(ServiceHgann, CliSubmitWatchFetchWritesTheNetworksAndTheIdentifyReport) {
  Cluster c("hgann-cli");
  c.AddWorker(1);
  c.AddWorker(1);
  const std::string ep = c.client_endpoint();
  std::string out, err;
  ASSERT_EQ(
      RunCli({"submit", (kExamples / "hgann_quick.json").string(), "--master", ep}, &out, &err), 0)
      << err;
  const std::string id = out.substr(0, out.find('\n'));
  ASSERT_EQ(id.size(), 16u) << out;

  EXPECT_EQ(RunCli({"watch", id, "--master", ep}, &out, &err), 0) << out << err;
  EXPECT_EQ(RunCli({"status", id, "--master", ep}, &out, &err), 0) << err;
  EXPECT_NE(out.find("succeeded"), std::string::npos) << out;
  EXPECT_EQ(RunCli({"list", "--master", ep}, &out, &err), 0) << err;
  EXPECT_NE(out.find(id), std::string::npos) << out;
  EXPECT_NE(out.find("2 workers"), std::string::npos) << out;

  const fs::path dir = c.dir() / "result";
  ASSERT_EQ(
      RunCli({"fetch", id, "--best", "3", "--out", dir.string(), "--no-plots", "--master", ep},
             &out, &err),
      0)
      << out << err;
  EXPECT_NE(out.find("report: " + (dir / "report.md").string()), std::string::npos) << out;
  for (const char* f : {"report.md", "network.pb", "network.json", "progress.csv", "validation.csv",
                        "parameters.csv", "networks/best-1.pb", "networks/best-1.json",
                        "networks/best-3.pb", "networks/best-3.json", "traces/case2.csv"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_FALSE(fs::exists(dir / "networks/best-4.pb"));

  // The networks are the job's best, with provenance; the report is the identify report.
  const service::JobCheckpoint& ref = QuickReference();
  io::SavedNetwork best, best1, third;
  ASSERT_TRUE(io::LoadNetwork((dir / "network.pb").string(), &best).ok());
  ASSERT_TRUE(io::LoadNetwork((dir / "networks/best-1.json").string(), &best1).ok());
  ASSERT_TRUE(io::LoadNetwork((dir / "networks/best-3.pb").string(), &third).ok());
  EXPECT_EQ(best.chromosome, ref.best[0].genome.bits);
  EXPECT_EQ(best1.network, best.network);
  EXPECT_EQ(third.chromosome, ref.best[2].genome.bits);
  EXPECT_EQ(best.provenance.job_id, id);
  EXPECT_EQ(best.provenance.seed, 7u);
  EXPECT_EQ(best.provenance.fitness, ref.best[0].fitness.cost);
  const std::vector<std::string> training = {"case1", "case5", "case6", "case7"};
  EXPECT_EQ(best.provenance.training_cases, training);
  const std::string report = Slurp(dir / "report.md");
  EXPECT_NE(report.find("# HGANN identification of "), std::string::npos);
  EXPECT_NE(report.find("MAX_GENERATIONS after 40 generations"), std::string::npos) << report;
  EXPECT_NE(report.find("population 60, seed 7"), std::string::npos) << report;
  EXPECT_NE(report.find("Performance index per case"), std::string::npos);
  const std::string progress = Slurp(dir / "progress.csv");
  EXPECT_EQ(std::count(progress.begin(), progress.end(), '\n'), 42);  // header + generations 0 … 40

  // Cancelling a finished job is refused (5); an unknown job is 4.
  EXPECT_EQ(RunCli({"cancel", id, "--master", ep}, &out, &err), 5) << err;
  EXPECT_EQ(
      RunCli({"fetch", "j0000000000000000", "--master", ep, "--out", (c.dir() / "x").string()},
             &out, &err),
      4);
  EXPECT_NE(err.find("no such job"), std::string::npos) << err;
}

TEST(ServiceHgann, BadHgannSpecsAreRejectedWithTheField) {
  job::JobSpec spec = QuickSpec();
  auto& h = std::get<job::HgannProblem>(spec.problem);
  h.cases[3].angle_deg[17] = std::nan("");
  h.cases[2].role = job::CaseRole::kUnspecified;
  h.cases[5].number = h.cases[0].number;
  h.ranges_preset = "papier";
  h.spread_penalty = -1;
  h.geometry["tip_length_m"] = -0.01;
  spec.ga->population = 1;

  // The master answers every violated field.
  Cluster c("hgann-bad");
  auto client = c.Client();
  svcclient::SubmitResult r;
  std::vector<job::FieldViolation> v;
  Status st = client.Submit(spec, &r, &v);
  ASSERT_EQ(st.code(), StatusCode::kInvalidArgument) << st.message();
  for (const char* f : {"hgann.cases[3].angle_deg[17]", "hgann.cases[2].role",
                        "hgann.cases[5].number", "hgann.ranges_preset", "hgann.spread_penalty",
                        "hgann.geometry.tip_length_m", "ga.population"})
    EXPECT_TRUE(HasField(v, f)) << f << " in: " << st.message();
  EXPECT_NE(st.message().find("hgann.cases[3].angle_deg[17] = nan: must be finite"),
            std::string::npos)
      << st.message();

  // A spec naming a client folder never reaches a master's disk.
  job::JobSpec dir_spec = QuickSpec();
  std::get<job::HgannProblem>(dir_spec.problem).case_set_dir = "/etc";
  EXPECT_EQ(client.Submit(dir_spec, &r, &v).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(HasField(v, "hgann.case_set_dir"));

  // The CLI refuses a bad JSON spec itself (exit 2, every violation printed), master or not.
  const fs::path bad = c.dir() / "bad.json";
  std::ofstream(bad) << R"({"version": 1, "seed": "1",
    "hgann": {"case_set_dir": ")"
                     << (fs::path(PIEZOID_DATA_DIR) / "bimorph-fin/nominal").string() << R"(",
              "ranges": [{"name": "alfa", "min": 0, "max": 1}, {"name": "beta", "min": 1,
              "max": 0}],
              "spread_penalty": -2},
    "ga": {"population": 1}})";
  std::string out, err;
  EXPECT_EQ(RunCli({"submit", bad.string(), "--master", "tcp://127.0.0.1:1", "--timeout-ms", "100"},
                   &out, &err),
            2);
  EXPECT_NE(
      err.find(
          "hgann.ranges[0].name = \"alfa\": must be one of mu, delta, alpha, beta, gamma, a1, a2"),
      std::string::npos)
      << err;
  EXPECT_NE(err.find("hgann.ranges[1].max = 0: must be finite and >= min (1)"), std::string::npos)
      << err;
  EXPECT_NE(err.find("hgann.spread_penalty = -2"), std::string::npos) << err;
  EXPECT_NE(err.find("ga.population = 1"), std::string::npos) << err;
  EXPECT_TRUE(out.empty()) << out;

  // A folder that is not a case set names the field and the file.
  std::ofstream(bad) << R"({"version": 1, "hgann": {"case_set_dir": "no-such-folder"}, "ga": {}})";
  EXPECT_EQ(RunCli({"submit", bad.string()}, &out, &err), 2);
  EXPECT_NE(err.find("hgann.case_set_dir = \"no-such-folder\": cannot be read"), std::string::npos)
      << err;

  // The master still serves.
  EXPECT_TRUE(client.Submit(SyntheticSpec(1, 10, 2), &r).ok());
}

TEST(ServiceHgann, UnreachableMasterGivesItsMessageAndExitCode3) {
  const std::string ep = "tcp://127.0.0.1:" + std::to_string(FreePort());
  std::string out, err;
  for (const std::vector<std::string>& cmd :
       {std::vector<std::string>{"status"},
        {"list"},
        {"watch", "j1"},
        {"fetch", "j1"},
        {"cancel", "j1"},
        {"submit", (kExamples / "synthetic_job.json").string()}}) {
    std::vector<std::string> args = cmd;
    args.insert(args.end(), {"--master", ep, "--timeout-ms", "150", "--retries", "2"});
    EXPECT_EQ(RunCli(args, &out, &err), 3) << cmd[0] << ": " << err;
    EXPECT_NE(err.find("cannot reach the master at " + ep + ": is piezoid-master running?"),
              std::string::npos)
        << cmd[0] << ": " << err;
  }
  // A bad command line is bad input (2); --help is 0.
  EXPECT_EQ(RunCli({"fetch"}, &out, &err), 2);
  EXPECT_EQ(RunCli({"fetch", "j1", "--best", "0"}, &out, &err), 2);
  EXPECT_EQ(RunCli({"--help"}, &out, &err), 0);
  EXPECT_NE(out.find("Exit codes"), std::string::npos);
}

}  // namespace
}  // namespace pz::testing
