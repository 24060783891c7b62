// The diagnosis on the service: the "diagnose" job kind builds, from its spec alone, the fitness
// the client has (costs and residual vectors bit for bit; bad specs refused field by field), and a
// whole diagnosis whose fits run as evaluation sessions on a local master with two workers equals
// the local run bit for bit.
#include <gtest/gtest.h>

#include <cstring>

#include "svcclient/complete_service.h"
#include "svcclient/service_evaluator.h"
#include "diagnose/fin_diagnose.h"
#include "diagnose/job_kind.h"
#include "diagnose/synthetic.h"
#include "opt/inline_evaluator.h"
#include "tests/system/service_harness.h"
#include "kinds/kinds.h"

namespace pz::diagnose {
namespace {

using model::EffectKind;

std::vector<DiagCase> SmallBench(bool with_delay) {
  const model::BimorphPlant plant;
  records::FinTrialOptions so;
  model::BimorphParams p;
  std::vector<std::pair<double, double>> sat;
  for (double v : {375.0, 500.0, 750.0})
    for (double f : {0.25, 0.5, 1.0})
      sat.push_back({0.0065 * v - 0.85 * f - 0.63, -0.0062 * v + 0.68 * f + 0.71});
  opt::Rng rng(3);
  std::vector<model::Effect> effects;
  if (with_delay) effects = {{EffectKind::Named("delay"), {0.02}}};
  return CasesFromCaseSet(records::SimulateBench(plant, p, effects, sat, so, rng));
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void ExpectSameVector(const std::vector<double>& a, const std::vector<double>& b,
                      const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i)
    EXPECT_TRUE(SameBits(a[i], b[i])) << what << "[" << i << "]: " << a[i] << " vs " << b[i];
}

// A small diagnosis: two candidates (a drive effect, a beam effect on CVODE), small searches.
DiagnoseOptions SmallOptions() {
  DiagnoseOptions o;
  o.candidates = {EffectKind::Named("delay"), EffectKind::Named("cubic-stiffening")};
  o.de_base.population = 12;
  o.de_base.generations = 8;
  o.de_candidate.population = 12;
  o.de_candidate.generations = 5;
  o.lm.max_iterations = 6;
  o.cvode_lm_iterations = 2;
  o.cvode_start_fractions = {0.05};
  o.second_effect = false;
  o.trends = false;
  return o;
}

client::ServiceEvaluatorOptions ServiceOptions(testing::Cluster& cluster) {
  client::ServiceEvaluatorOptions so;
  so.client.endpoint = cluster.client_endpoint();
  so.client.timeout_ms = 2000;
  so.client.retries = 3;
  so.batch_timeout_s = 300;
  return so;
}

// The first round's candidates, the naming and the verdict, bit for bit.
void ExpectSameRounds(const Diagnosis& remote, const Diagnosis& local) {
  ASSERT_EQ(remote.rounds.size(), local.rounds.size());
  ASSERT_EQ(remote.rounds[0].candidates.size(), local.rounds[0].candidates.size());
  for (size_t i = 0; i < local.rounds[0].candidates.size(); ++i) {
    const auto& a = remote.rounds[0].candidates[i];
    const auto& b = local.rounds[0].candidates[i];
    EXPECT_EQ(a.kind, b.kind);
    ExpectSameVector(a.fit.x, b.fit.x, std::string(model::EffectName(b.kind)) + ".x");
    EXPECT_TRUE(SameBits(a.fit.withheld_pi, b.fit.withheld_pi));
    EXPECT_TRUE(SameBits(a.score, b.score));
  }
  EXPECT_EQ(remote.named, local.named);
  EXPECT_EQ(remote.verdict, local.verdict);
}

TEST(DiagnoseJobKindTest, TheSpecRebuildsTheFitnessBitForBit) {
  auto plant = std::make_shared<const model::BimorphPlant>();
  const DiagnosisModel m(plant, SmallBench(true));
  for (const bool residuals : {false, true}) {
    const DiagnosisFitness local(
        m, ParameterLayout({EffectKind::Named("delay"), EffectKind::Named("driver-lowpass")}),
        residuals);
    const job::JobSpec spec = DiagnoseJobSpec(local, "test");
    // Through the wire encoding, as a worker gets it.
    job::JobSpec decoded;
    ASSERT_TRUE(service::DecodeJobSpec(service::EncodeJobSpec(spec), &decoded).ok());
    job::JobKindRegistry registry;
    registry.Register(DiagnoseJobKind());
    decoded.external = job::ExternalSettings{};
    EXPECT_TRUE(registry.Validate(decoded).empty());
    job::GenomeLayout layout;
    ASSERT_TRUE(registry.Layout(decoded, &layout).ok());
    EXPECT_EQ(layout.reals, local.layout().size());
    EXPECT_EQ(layout.bits, 0);
    std::unique_ptr<opt::FitnessFunction> remote;
    ASSERT_TRUE(registry.MakeFitness(decoded, &remote).ok());
    opt::Rng rng(5);
    for (int k = 0; k < 3; ++k) {
      opt::Genome g;
      for (int i = 0; i < layout.reals; ++i) g.reals.push_back(rng.Uniform01());
      if (k == 0) g.reals[7] = 0;  // the delay at zero
      const opt::FitnessResult a = local.Evaluate(g), b = remote->Evaluate(g);
      EXPECT_TRUE(SameBits(a.cost, b.cost)) << a.cost << " vs " << b.cost;
      EXPECT_EQ(a.status, b.status);
      EXPECT_EQ(a.residuals.empty(), !residuals || a.status != opt::FitnessStatus::kOk);
      ExpectSameVector(a.residuals, b.residuals, "residuals");
    }
  }
}

TEST(DiagnoseJobKindTest, BadSpecsAreRefusedFieldByField) {
  auto plant = std::make_shared<const model::BimorphPlant>();
  const DiagnosisModel m(plant, SmallBench(false));
  const DiagnosisFitness f(m, ParameterLayout({EffectKind::Named("creep")}));
  job::JobKindRegistry registry;
  registry.Register(DiagnoseJobKind());
  auto violations = [&](const job::JobSpec& s) {
    std::string all;
    for (const auto& v : registry.Validate(s)) all += v.description + "\n";
    return all;
  };
  job::JobSpec ok = DiagnoseJobSpec(f, "ok");
  ok.external = job::ExternalSettings{};
  EXPECT_EQ(violations(ok), "");
  job::JobSpec s = ok;
  auto& d = std::get<job::DiagnoseProblem>(s.problem);
  d.structure = {"creep", "friction-of-the-gods"};
  EXPECT_NE(violations(s).find("diagnose.structure[1] = friction-of-the-gods: not an effect"),
            std::string::npos)
      << violations(s);
  s = ok;
  std::get<job::DiagnoseProblem>(s.problem).params[7].upper *= 2;
  EXPECT_NE(violations(s).find("diagnose.params[7] = creep."), std::string::npos) << violations(s);
  s = ok;
  std::get<job::DiagnoseProblem>(s.problem).cycles[2] = 2.5;
  EXPECT_NE(violations(s).find("diagnose.cycles[2] = 2.5: gives"), std::string::npos)
      << violations(s);
  s = ok;
  std::get<job::DiagnoseProblem>(s.problem).cases[4].angle_deg[3] = NAN;
  EXPECT_NE(violations(s).find("diagnose.cases[4].angle_deg[3] = nan: must be finite"),
            std::string::npos)
      << violations(s);
  s = ok;
  for (auto& c : std::get<job::DiagnoseProblem>(s.problem).cases) c.role = job::CaseRole::kTest;
  EXPECT_NE(violations(s).find("no case with role CASE_ROLE_TRAIN"), std::string::npos)
      << violations(s);
  s = ok;
  std::get<job::DiagnoseProblem>(s.problem).rtol = 0.5;
  EXPECT_NE(violations(s).find("rtol"), std::string::npos) << violations(s);
}

TEST(DiagnoseServiceTest, TheDiagnosisOnTheServiceIsTheLocalOneBitForBit) {
  testing::Cluster cluster("diagnose-service");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  auto plant = std::make_shared<const model::BimorphPlant>();
  const DiagnosisModel m(plant, SmallBench(true));
  DiagnoseOptions o = SmallOptions();
  const Diagnosis local = RunDiagnosis(m, o);

  const client::ServiceEvaluatorOptions so = ServiceOptions(cluster);
  int sessions = 0;
  o.evaluator_factory = [&](const DiagnosisFitness& f) -> std::unique_ptr<opt::BatchEvaluator> {
    ++sessions;
    return std::make_unique<client::ServiceEvaluator>(
        so, DiagnoseJobSpec(f, "test " + f.layout().Describe()));
  };
  const Diagnosis remote = RunDiagnosis(m, o);
  // base: DE + LM; delay: DE + LM; cubic stiffening (beam): LM only.
  EXPECT_EQ(sessions, 5);
  ExpectSameVector(remote.base.x, local.base.x, "base.x");
  EXPECT_TRUE(SameBits(remote.base.train_pi, local.base.train_pi));
  EXPECT_EQ(remote.base.evaluations, local.base.evaluations);
  ExpectSameRounds(remote, local);
  EXPECT_EQ(remote.evaluations, local.evaluations);
  // Every session was closed: all succeeded.
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  EXPECT_EQ(jobs.size(), 5u);
  for (const auto& j : jobs) {
    EXPECT_EQ(j.kind, "diagnose");
    EXPECT_GT(j.evaluations, 0u);
  }
}

// piezoid diagnose --cases --master: the records engine (DiagnoseBench) with every fit's search as
// a complete_model session (bimorph-fin's bench form on the workers) gives the local diagnosis
// bit for bit.
TEST(DiagnoseServiceTest, TheRecordsEngineOnTheServiceIsTheLocalOneBitForBit) {
  testing::Cluster cluster("diagnose-records-service");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  auto plant = std::make_shared<const model::BimorphPlant>();
  const DiagnosisModel m(plant, SmallBench(true));
  DiagnoseOptions o = SmallOptions();
  const Diagnosis local = DiagnoseBench(m, o);

  const client::ServiceEvaluatorOptions so = ServiceOptions(cluster);
  int factories = 0;
  o.records_service = [&](const records::FamilyOptions& f) {
    ++factories;
    EXPECT_TRUE(f.bench_form);
    return client::RecordsServiceFactory(so, f, "test");
  };
  const Diagnosis remote = DiagnoseBench(m, o);
  EXPECT_GE(factories, 1);
  ExpectSameVector(remote.base.x, local.base.x, "base.x");
  EXPECT_TRUE(SameBits(remote.base.train_pi, local.base.train_pi));
  ExpectSameVector(remote.base.case_pi, local.base.case_pi, "base.case_pi");
  ExpectSameRounds(remote, local);
  // The searches ran on the workers: complete_model sessions, each with evaluations.
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  EXPECT_GE(jobs.size(), 2u);
  for (const auto& j : jobs) {
    EXPECT_EQ(j.kind, "complete_model");
    EXPECT_GT(j.evaluations, 0u);
  }
}

}  // namespace
}  // namespace pz::diagnose
