// bimorph-fin's bench form on the service (issue 38): the "complete_model" job kind carries the
// bench form (bench_form, the fin simulator's options, each record's stated sinusoid, the effects
// in the order given, beam ones included), so that a worker rebuilds from the spec alone the
// fitness of a records fit of the fin bench cost for cost, bit for bit; bad bench-form specs are
// refused field by field; a spec without the bench form encodes as before (no new field on the
// wire: its bytes, hence its job id, unchanged); and a bench-form fit of the nominal bench whose
// search runs on a local master with two workers gives the local fit's parameters and per-case sum
// of squared errors bit for bit, for the base model and for a beam model (hinge-friction on CVODE),
// with the Levenberg–Marquardt polish's residual vectors (the spec's `residuals`) on the workers
// too, as for the fin's refinement of a beam model (no search); `residuals` is refused where
// there are none (a window, the oscillator).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "complete/job_kind.h"
#include "complete_remote.h"
#include "io/bench_data.h"
#include "io/fin_records.h"
#include "job.pb.h"
#include "records/registry.h"
#include "service_harness.h"
#include "svcclient/complete_service.h"
#include "tests/testing/expect_error.h"

namespace pz::testing {
namespace {

using model::EffectKind;

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

io::RecordSet Nominal() {
  return io::RecordsFromCaseSet(
      io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/nominal"));
}

records::FamilyOptions BenchForm() {
  records::FamilyOptions fo;
  fo.bench_form = true;
  return fo;
}

/// The local fitness of a bench-form model on the set's training records (what FitRecords makes).
struct Local {
  Local(const io::RecordSet& set, std::vector<EffectKind> effects, const records::FamilyOptions& fo)
      : train(set.WithRole(model::CaseRole::kTrain)),
        scale(records::MeasureScale(train)),
        model(records::MakeFamily("bimorph-fin", scale, fo), std::move(effects), scale),
        fitness(model, train) {}
  std::vector<const io::Record*> train;
  records::DataScale scale;
  records::RecordModel model;
  records::RecordFitness fitness;
};

/// A point of the model's box at fraction x of each range (γ by its ratio to β, in its own box).
opt::Genome At(const records::RecordModel& m, double x) {
  opt::Genome g;
  for (const auto& p : m.params()) g.reals.push_back(p.lower + x * (p.upper - p.lower));
  g.reals[4] *= g.reals[3];  // γ = (γ/β) β
  return g;
}

TEST(FinRecordsJobKindTest, TheSpecRebuildsTheBenchFormFitnessBitForBit) {
  const io::RecordSet set = Nominal();
  struct Case {
    std::vector<EffectKind> effects;
    std::vector<double> at;
    records::EffectSimOptions sim;
  };
  // Two drive effects out of the library's order (the parameters in the order given), the fast
  // path on another fine grid, the base on CVODE, and a beam effect (CVODE): the simulator's
  // options travel.
  const EffectKind creep = EffectKind::Named("creep"),
                   lowpass = EffectKind::Named("driver-lowpass");
  records::EffectSimOptions coarse, cvode;
  coarse.oversample = 2;
  cvode.force_cvode = true;
  cvode.rtol = 1e-5;
  for (const Case& c : {Case{{}, {0.1, 0.37, 0.8}, {}}, Case{{creep, lowpass}, {0.2, 0.6}, {}},
                        Case{{lowpass}, {0.37}, coarse}, Case{{}, {0.37}, cvode},
                        Case{{EffectKind::Named("hinge-friction")}, {0.05}, {}}}) {
    records::FamilyOptions fo = BenchForm();
    fo.fin_sim = c.sim;
    const Local local(set, c.effects, fo);
    SCOPED_TRACE(local.model.Describe());
    const job::JobSpec spec =
        complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(local.fitness, fo), "test");
    const auto& problem = std::get<job::CompleteModelProblem>(spec.problem);
    EXPECT_TRUE(problem.bench_form);
    ASSERT_TRUE(problem.fin_sim);
    EXPECT_EQ(problem.fin_sim->oversample, c.sim.oversample);
    EXPECT_EQ(problem.fin_sim->force_cvode, c.sim.force_cvode);
    ASSERT_EQ(problem.records.size(), local.train.size());
    for (size_t i = 0; i < problem.records.size(); ++i) {  // whole, with their stated sinusoid
      EXPECT_EQ(problem.records[i].output, local.train[i]->y);
      ASSERT_TRUE(problem.records[i].sinusoid);
      EXPECT_EQ(problem.records[i].sinusoid->frequency_hz, local.train[i]->sinusoid.frequency_hz);
    }
    std::vector<std::string> names;
    for (const EffectKind& e : c.effects) names.push_back(e.name());
    EXPECT_EQ(problem.effects, names);
    for (bool json : {false, true}) {
      SCOPED_TRACE(json ? "json" : "binary");
      // The JSON encoding writes −0 as 0 (the drive's sinusoid is −0 at some samples): the spec
      // with +0 there, to check that it loses nothing else; the form simulates the stated drive.
      job::JobSpec sent = spec;
      if (json)
        for (auto& r : std::get<job::CompleteModelProblem>(sent.problem).records)
          for (auto* v : {&r.input, &r.output})
            for (double& x : *v) x = x == 0 ? 0.0 : x;
      const auto remote = RemoteCompleteFitness(sent, json);
      ASSERT_TRUE(remote);
      for (double x : c.at) {
        const opt::Genome g = At(local.model, x);
        const opt::FitnessResult a = local.fitness.Evaluate(g), b = remote->Evaluate(g);
        EXPECT_EQ(a.status, opt::FitnessStatus::kOk) << a.reason;
        EXPECT_TRUE(SameBits(a.cost, b.cost)) << x << ": " << a.cost << " vs " << b.cost;
        EXPECT_EQ(a.status, b.status);
      }
    }
    // The polish's spec: each result the local residual vector, bit for bit.
    const auto remote = RemoteCompleteFitness(
        complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(local.fitness, fo, true),
                                       "polish"),
        false);
    ASSERT_TRUE(remote);
    const records::RecordResidualFitness residuals(local.fitness);
    const opt::FitnessResult a = residuals.Evaluate(At(local.model, c.at[0])),
                             b = remote->Evaluate(At(local.model, c.at[0]));
    ASSERT_EQ(a.status, opt::FitnessStatus::kOk) << a.reason;
    EXPECT_EQ(a.status, b.status);
    EXPECT_TRUE(SameBits(a.cost, b.cost)) << a.cost << " vs " << b.cost;
    ASSERT_EQ(a.residuals.size(), b.residuals.size());
    EXPECT_GT(a.residuals.size(), 0u);
    for (size_t k = 0; k < a.residuals.size(); ++k)
      ASSERT_TRUE(SameBits(a.residuals[k], b.residuals[k])) << k;
  }
}

// The spec of a records fit without the bench form sets none of its fields: its bytes, and so its
// job id (service/wire_codec.h JobIdOf), are those it had before the form was carried.
TEST(FinRecordsJobKindTest, ASpecWithoutTheBenchFormPutsNoneOfItsFieldsOnTheWire) {
  const io::RecordSet set = Nominal();
  const auto train = set.WithRole(model::CaseRole::kTrain);
  const records::DataScale scale = records::MeasureScale(train);
  records::RecordModel model(records::MakeFamily("backlash-like", scale), {}, scale);
  records::RecordFitness local(model, train);
  const job::JobSpec spec = complete::CompleteModelJobSpec(
      complete::CompleteModelProblemOf(local, records::FamilyOptions{}), "old");
  wire::JobSpec p;
  ASSERT_TRUE(p.ParseFromString(service::EncodeJobSpec(spec)));
  const wire::CompleteModelProblem& m = p.complete_model();
  EXPECT_FALSE(m.bench_form());
  EXPECT_FALSE(m.has_fin_sim());
  EXPECT_FALSE(m.residuals());
  ASSERT_EQ(m.records_size(), static_cast<int>(train.size()));
  for (const auto& r : m.records()) EXPECT_FALSE(r.has_sinusoid());
  // Cleared, the message is the same bytes: nothing else was added.
  wire::JobSpec q = p;
  q.mutable_complete_model()->clear_bench_form();
  q.mutable_complete_model()->clear_fin_sim();
  EXPECT_EQ(q.SerializeAsString(), p.SerializeAsString());
  EXPECT_FALSE(std::get<job::CompleteModelProblem>(spec.problem).bench_form);
}

TEST(FinRecordsJobKindTest, BadBenchFormSpecsAreRefusedFieldByField) {
  const io::RecordSet set = Nominal();
  const records::FamilyOptions fo = BenchForm();
  const Local local(set, {}, fo);
  const job::CompleteModelProblem p = complete::CompleteModelProblemOf(local.fitness, fo);
  job::JobKindRegistry registry;
  registry.Register(complete::CompleteModelJobKind());
  auto errors = [&](job::CompleteModelProblem q) {
    job::JobSpec spec = complete::CompleteModelJobSpec(std::move(q), "bad");
    spec.external = job::ExternalSettings{};
    std::string all;
    for (const auto& v : registry.Validate(spec)) all += v.description + "\n";
    return all.empty() ? std::string("<none>") : all;
  };
  EXPECT_EQ(errors(p), "<none>");
  auto q = p;
  q.residuals = true;  // the polish's spec
  EXPECT_EQ(errors(q), "<none>");
  q.t1_s = 1;
  PZ_EXPECT_HAS(errors(q), "complete_model.residuals = true: only the MSE over the records'");
  q = p;
  q.records[2].sinusoid.reset();
  PZ_EXPECT_HAS(errors(q),
                "complete_model.records[2].sinusoid = unset: bimorph-fin's bench form "
                "simulates each record's stated sinusoid: required");
  q = p;
  q.records[0].sinusoid->cycles += 1;
  PZ_EXPECT_HAS(errors(q), "complete_model.records[0].sinusoid = ");
  PZ_EXPECT_HAS(errors(q), "samples, the record " + std::to_string(p.records[0].input.size()));
  q = p;
  q.records[1].sinusoid->frequency_hz = -1;
  PZ_EXPECT_HAS(errors(q),
                "complete_model.records[1].sinusoid = {V, f, cycles, fs}: "
                "frequency_hz = -1: must be finite and > 0");
  q = p;
  q.records[0].output.assign(q.records[0].output.size(), 0.0);  // no extremes to saturate at
  PZ_EXPECT_HAS(errors(q), "complete_model.records[0].output = ");
  q = p;
  q.fin_sim->rtol = 0.5;
  PZ_EXPECT_HAS(errors(q), "complete_model.fin_sim = {...}: rtol = 0.5");
  q = p;
  q.record_family = "backlash-like";
  PZ_EXPECT_HAS(errors(q),
                "complete_model.bench_form = true: only bimorph-fin has a bench form "
                "(record_family = 'backlash-like')");
  q = p;
  q.t1_s = 1;
  PZ_EXPECT_HAS(errors(q), "the bench form's cost is the sum of squared errors over the records");
  q = p;
  q.effects = {"creep-spectrum"};
  PZ_EXPECT_HAS(errors(q), "effect 'creep-spectrum'");
  q = p;
  q.effects = {"hum"};
  PZ_EXPECT_HAS(errors(q), "effect 'hum' is unknown");
  // Its fields on a spec without the form.
  q = p;
  q.bench_form = false;
  PZ_EXPECT_HAS(errors(q), "complete_model.fin_sim = set: only bimorph-fin's bench form");
  PZ_EXPECT_HAS(errors(q), "complete_model.records[0].sinusoid = set: only bimorph-fin's bench");
  // The client's family options must be the model's (its simulator's options travel).
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  complete::CompleteModelProblemOf(local.fitness, records::FamilyOptions{});
                }),
                "needs the family options it was made with");
}

// The nominal bench's fits with small searches (DE: the fin engine's search): locally, then with
// the search's evaluations as an evaluation session on a master with two workers.
records::FitOptions BenchFit(std::vector<EffectKind> effects, int population, int generations,
                             int lm_iterations) {
  records::FitOptions o;
  o.family = "bimorph-fin";
  o.family_options = BenchForm();
  o.effects = std::move(effects);
  o.search.algorithm = opt::SearchAlgorithm::kDe;
  o.search.de.population = population;
  o.search.de.generations = generations;
  o.search.de.stall_generations = 0;
  o.search.de.seed = 7;
  o.search.repetitions = 1;
  o.lm.max_iterations = lm_iterations;
  o.lm.threads = 2;
  o.uncertainty = false;
  o.threads = 2;
  return o;
}

void ExpectSameFit(const records::FitResult& want, const records::FitResult& got) {
  ASSERT_EQ(want.params.size(), got.params.size());
  for (size_t i = 0; i < want.params.size(); ++i)
    EXPECT_TRUE(SameBits(want.params[i], got.params[i]))
        << want.model->params()[i].name << ": " << want.params[i] << " vs " << got.params[i];
  ASSERT_EQ(want.metrics.size(), got.metrics.size());
  for (size_t c = 0; c < want.metrics.size(); ++c) {
    EXPECT_EQ(want.metrics[c].name, got.metrics[c].name);
    EXPECT_TRUE(SameBits(want.metrics[c].sse, got.metrics[c].sse))
        << want.metrics[c].name << ": " << want.metrics[c].sse << " vs " << got.metrics[c].sse;
  }
  EXPECT_TRUE(SameBits(want.train_sse, got.train_sse)) << want.train_sse << " vs " << got.train_sse;
  EXPECT_EQ(want.search.evaluations, got.search.evaluations);
  EXPECT_EQ(want.evaluations, got.evaluations);
  EXPECT_EQ(want.lm_iterations, got.lm_iterations);
}

svcclient::ServiceEvaluatorOptions ServiceOptions(const Cluster& cluster) {
  svcclient::ServiceEvaluatorOptions so;
  so.client.endpoint = cluster.client_endpoint();
  so.client.timeout_ms = 2000;
  so.client.retries = 3;
  so.batch_timeout_s = 120;
  return so;
}

/// The fit with its evaluations (search and polishes) on the cluster's workers.
records::FitResult FitOnService(const io::RecordSet& set, records::FitOptions o,
                                const Cluster& cluster) {
  o.evaluator_factory =
      svcclient::RecordsServiceFactory(ServiceOptions(cluster), o.family_options, "test");
  try {
    return records::FitRecords(set, o);
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what() << " (see " << cluster.dir() << ")";  // keeps the logs
  }
  return {};
}

/// The sessions on the cluster's master: the searches' (cost) and the polishes' (residuals, named
/// "… (polish)"), each with its evaluations.
struct Sessions {
  uint64_t search = 0, polish = 0;  ///< sessions
  uint64_t search_evals = 0, polish_evals = 0;
};
Sessions SessionsOn(Cluster& cluster) {
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  EXPECT_TRUE(client.List(&jobs).ok());
  Sessions s;
  for (const auto& j : jobs) {
    EXPECT_EQ(j.kind, "complete_model");
    EXPECT_GT(j.evaluations, 0u) << j.name;
    const bool polish = j.name.ends_with(" (polish)");
    (polish ? s.polish : s.search) += 1;
    (polish ? s.polish_evals : s.search_evals) += j.evaluations;
  }
  return s;
}

TEST(FinRecordsServiceTest, ABenchFormFitOnTheServiceIsTheLocalOneBitForBit) {
  Cluster cluster("fin-records-fit");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  const io::RecordSet set = Nominal();
  int64_t search_evals = 0, polish_evals = 0;
  // The base model (the fast path), then a beam model (hinge-friction: every run on CVODE, about
  // 0.1 s each: a search of two generations of 4 and one polish step).
  const std::vector<records::FitOptions> fits = {
      BenchFit({}, 12, 5, 6), BenchFit({EffectKind::Named("hinge-friction")}, 4, 1, 1)};
  for (records::FitOptions o : fits) {
    SCOPED_TRACE(o.effects.empty() ? "base" : "hinge-friction");
    const records::FitResult local = records::FitRecords(set, o);
    const records::FitResult remote = FitOnService(set, o, cluster);
    ExpectSameFit(local, remote);
    search_evals += remote.search.evaluations;
    polish_evals += remote.evaluations - remote.search.evaluations;
  }
  // Each search was one session of the complete_model kind, and each polish one (its residual
  // vectors): every evaluation of both on the workers.
  const Sessions s = SessionsOn(cluster);
  EXPECT_EQ(s.search, 2u);
  EXPECT_EQ(s.polish, 2u);
  EXPECT_EQ(s.search_evals, static_cast<uint64_t>(search_evals));
  EXPECT_EQ(s.polish_evals, static_cast<uint64_t>(polish_evals));
}

// The fin's refinement of a beam model (no search: a Levenberg–Marquardt polish from a base fit
// with hinge-friction's magnitude at two fractions of its range, every run on CVODE): with the
// residual vectors on a master with two workers, the local refinement's parameters and per-case
// sse bit for bit, every evaluation of both polishes on the workers.
TEST(FinRecordsServiceTest, ABeamRefinementWithItsResidualsOnTheServiceIsTheLocalOneBitForBit) {
  Cluster cluster("fin-records-refine");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  const io::RecordSet set = Nominal();
  records::FitOptions o = BenchFit({EffectKind::Named("hinge-friction")}, 4, 1, 1);
  // A base point (the bench's own fit is not needed for the check): the box's lower quarter.
  const records::FitResult probe = [&] {
    records::FitOptions b = BenchFit({}, 4, 1, 1);
    b.polish = false;
    return records::FitRecords(set, b);
  }();
  // The hinge's parameters at the middle of their box (its magnitude set by each start).
  const Local beam(set, o.effects, o.family_options);
  o.polish_from = probe.params;
  for (size_t i = probe.params.size(); i < beam.model.params().size(); ++i)
    o.polish_from.push_back(0.5 * (beam.model.params()[i].lower + beam.model.params()[i].upper));
  o.beam.lm_iterations = 1;
  o.beam.start_fractions = {0.03, 0.15};
  const records::FitResult local = records::FitRecords(set, o);
  EXPECT_EQ(local.polishes, 2);
  EXPECT_EQ(local.search.evaluations, 0);
  ExpectSameFit(local, FitOnService(set, o, cluster));
  const Sessions s = SessionsOn(cluster);
  EXPECT_EQ(s.search, 0u);
  EXPECT_EQ(s.polish, 2u);  // one session per start
  EXPECT_EQ(s.polish_evals, static_cast<uint64_t>(local.evaluations));
}

}  // namespace
}  // namespace pz::testing
