// The "hgann" job kind: a spec built from the bundled case set gives the same fitness as
// `piezoid identify` on that folder, and the same run (in-process job runner vs RunIdentify);
// the spec survives the wire and JSON bit for bit; every bad field is named; the client embeds a
// case_set_dir relative to the job file.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "hgann/identify.h"
#include "client/job_file.h"
#include "hgann/hgann_job.h"
#include "master/job_runner.h"
#include "service/wire_codec.h"
#include "model/chromosome.h"
#include "kinds/kinds.h"

namespace pz::hgann {

using job::CaseRole;
using job::FieldViolation;
using job::GaSettings;
using job::GenomeLayout;
using job::HgannProblem;
using job::JobKind;
using job::JobKindRegistry;
using job::JobSpec;
using opt::EvaluateGuarded;
using opt::FitnessFunction;
using opt::FitnessResult;
using opt::Genome;
using service::DecodeJobSpec;
using service::EncodeJobSpec;
using service::JobCheckpoint;
using master::RunJobInProcess;
using master::ToGaOptions;
using service::JobSpecFromJson;
using service::JobSpecToJson;
namespace {

namespace fs = std::filesystem;
const fs::path kNominal = fs::path(PIEZOID_DATA_DIR) / "bimorph-fin" / "nominal";
const fs::path kExamples = fs::path(PIEZOID_DATA_DIR) / ".." / "examples";

const io::CaseSet& Nominal() {
  static const io::CaseSet set = io::LoadCaseSet(kNominal);
  return set;
}

JobSpec NominalSpec(int population, int generations) {
  JobSpec s;
  s.name = "nominal";
  s.seed = 11;
  s.problem = HgannProblemFromCaseSet(Nominal());
  GaSettings ga;
  ga.population = population;
  ga.generations = generations;
  ga.stall_generations = 0;
  s.ga = ga;
  return s;
}

bool HasField(const std::vector<FieldViolation>& v, const std::string& field, const std::string& text = "") {
  for (const auto& x : v)
    if (x.field == field && x.description.find(text) != std::string::npos) return true;
  return false;
}

std::string All(const std::vector<FieldViolation>& v) {
  std::string s;
  for (const auto& x : v) s += x.description + "\n";
  return s;
}

TEST(HgannJob, KindIsRegisteredWithThe1415BitLayout) {
  const JobKind* k = kinds::All().Find("hgann");
  ASSERT_NE(k, nullptr);
  GenomeLayout l;
  ASSERT_TRUE(kinds::All().Layout(NominalSpec(10, 1), &l).ok());
  EXPECT_EQ(l.bits, 1415);
  EXPECT_TRUE(kinds::All().Validate(NominalSpec(10, 1)).empty());
}

TEST(HgannJob, SpecOfTheCaseSetBuildsTheSameFitnessAsIdentify) {
  const HgannFitnessConfig direct = HgannConfigFromCaseSet(Nominal(), model::ParameterRanges{});
  HgannFitnessConfig via;
  ASSERT_TRUE(HgannConfigFromProblem(std::get<HgannProblem>(NominalSpec(10, 1).problem), &via).ok());
  ASSERT_EQ(via.cases.size(), direct.cases.size());
  for (size_t i = 0; i < via.cases.size(); ++i) {
    EXPECT_EQ(via.cases[i].number, direct.cases[i].number);
    EXPECT_EQ(via.cases[i].drive.amplitude_v, direct.cases[i].drive.amplitude_v);
    EXPECT_EQ(via.cases[i].drive.frequency_hz, direct.cases[i].drive.frequency_hz);
    EXPECT_EQ(via.cases[i].drive.sample_rate_hz, direct.cases[i].drive.sample_rate_hz);
    EXPECT_EQ(via.cases[i].drive.cycles, direct.cases[i].drive.cycles);
    EXPECT_EQ(via.cases[i].measured_deg, direct.cases[i].measured_deg);
    EXPECT_EQ(via.cases[i].b1, direct.cases[i].b1);
    EXPECT_EQ(via.cases[i].b2, direct.cases[i].b2);
    EXPECT_EQ(via.cases[i].training, direct.cases[i].training);
  }
  EXPECT_EQ(via.normalization, direct.normalization);
  EXPECT_EQ(via.ranges, direct.ranges);

  // And so the same cost for any genome, through the registry's factory.
  std::unique_ptr<FitnessFunction> f;
  ASSERT_TRUE(kinds::All().MakeFitness(NominalSpec(10, 1), &f).ok());
  const HgannFitness reference(direct);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 20; ++i) {
    Genome g;
    for (int b = 0; b < model::kChromosomeBits; ++b) g.bits.push_back(rng() & 1);
    const FitnessResult a = f->Evaluate(g), b = reference.Evaluate(g);
    EXPECT_EQ(a.cost, b.cost);
    EXPECT_EQ(a.status, b.status);
  }
}

TEST(HgannJob, InProcessJobRunsExactlyAsPiezoidIdentify) {
  const JobSpec spec = NominalSpec(16, 4);
  JobCheckpoint job;
  ASSERT_TRUE(RunJobInProcess("t", spec, kinds::All(), &job).ok());

  IdentifyOptions o;
  GenomeLayout layout{model::kChromosomeBits, 0};
  o.ga = ToGaOptions(spec, layout);
  o.threads = 2;
  const HgannFitness fitness(HgannConfigFromCaseSet(Nominal(), model::ParameterRanges{}));
  const IdentifyResult id = RunIdentify(o, Nominal(), fitness, nullptr);

  ASSERT_EQ(job.log.size(), id.log.size());
  for (size_t g = 0; g < job.log.size(); ++g) {
    EXPECT_EQ(job.log[g].best_cost, id.log[g].best_cost) << g;
    EXPECT_EQ(job.log[g].mean_cost, id.log[g].mean_cost) << g;
    EXPECT_EQ(job.log[g].worst_cost, id.log[g].worst_cost) << g;
    EXPECT_EQ(job.log[g].best_description, id.log[g].best_description) << g;
  }
  EXPECT_EQ(job.best.front().genome.bits, id.best.chromosome);
  EXPECT_EQ(job.best.front().fitness.cost, id.summary.best_fitness.cost);
}

TEST(HgannJob, SpecSurvivesTheWireAndJsonBitForBit) {
  JobSpec s = NominalSpec(10, 1);
  auto& h = std::get<HgannProblem>(s.problem);
  h.ranges_preset = "paper";
  h.ranges = {{"alpha", -0.05, 0.0}, {"mu", 10, 200}};
  h.spread_penalty = 0.25;
  h.geometry = {{"tip_length_m", 0.02}, {"n_active", 6}};
  h.saturation = HgannProblem::Saturation::kGiven;
  for (auto& c : h.cases) {
    c.b1 = 10.5 + c.number;
    c.b2 = -10.25 - c.number;
  }
  h.cases[0].angle_deg[3] = 0.1 + 0.2;  // not a short decimal
  const std::string bytes = EncodeJobSpec(s);
  JobSpec back;
  std::vector<FieldViolation> v;
  ASSERT_TRUE(DecodeJobSpec(bytes, &back, &v).ok());
  EXPECT_TRUE(v.empty());
  EXPECT_TRUE(EncodeJobSpec(back) == bytes);  // (not EXPECT_EQ: the bytes are 100 kB)
  // JSON keeps every value; only the sign of a zero sample (the bench files have "-0") is lost,
  // which no cost can see. The service itself sends binary.
  JobSpec from_json;
  ASSERT_TRUE(JobSpecFromJson(JobSpecToJson(s), &from_json, &v).ok());
  auto unsign_zeros = [](JobSpec x) {
    for (auto& c : std::get<HgannProblem>(x.problem).cases)
      for (double& y : c.angle_deg) y = y == 0 ? 0.0 : y;
    return EncodeJobSpec(x);
  };
  EXPECT_TRUE(unsign_zeros(from_json) == unsign_zeros(s));
  const auto& hb = std::get<HgannProblem>(from_json.problem);
  EXPECT_EQ(hb.cases[0].angle_deg[3], 0.1 + 0.2);
  EXPECT_EQ(hb.geometry.at("n_active"), 6);
  EXPECT_TRUE(kinds::All().Validate(from_json).empty()) << All(kinds::All().Validate(from_json));

  HgannFitnessConfig c;
  ASSERT_TRUE(HgannConfigFromProblem(hb, &c).ok());
  EXPECT_EQ(c.ranges.alpha, (model::ParameterRange{-0.05, 0.0}));
  EXPECT_EQ(c.ranges.beta, model::ParameterRanges::PaperTable3().beta);
  EXPECT_EQ(c.ranges.mu, (model::ParameterRange{10, 200}));
  EXPECT_EQ(c.geometry.tip_length_m, 0.02);
  EXPECT_EQ(c.geometry.n_active, 6);
  EXPECT_EQ(c.spread_penalty, 0.25);
  EXPECT_EQ(c.cases[2].b1, 10.5 + h.cases[2].number);
  EXPECT_EQ(c.cases[2].b2, -10.25 - h.cases[2].number);
}

TEST(HgannJob, EveryBadFieldIsNamed) {
  JobSpec s = NominalSpec(10, 1);
  auto& h = std::get<HgannProblem>(s.problem);
  h.cases[3].angle_deg[17] = std::nan("");
  h.cases[1].voltage_v.pop_back();
  h.cases[2].role = CaseRole::kUnspecified;
  h.cases[4].number = h.cases[0].number;
  h.cases[5].frequency_hz = 0;
  h.cases[6].sample_rate_hz = -1;
  h.cases[7].b1 = 3;
  h.ranges_preset = "papier";
  h.ranges = {{"alfa", 0, 1}, {"beta", 1, 0}, {"gamma", 0, 1}, {"gamma", 0, 2}};
  h.spread_penalty = std::nan("");
  h.geometry = {{"tip_lenght_m", 1}, {"n_tip", 2.5}};
  h.case_set_dir = "data/x";
  h.source = std::string(2000, 'x');
  const auto v = kinds::All().Validate(s);
  const std::string all = All(v);
  EXPECT_TRUE(HasField(v, "hgann.cases[3].angle_deg[17]", "hgann.cases[3].angle_deg[17] = nan: must be finite")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[1].voltage_v.size()", "must be 0 or the number of angle samples")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[2].role", "must be CASE_ROLE_TRAIN")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[4].number", "duplicates")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[5].frequency_hz", "= 0: must be finite and > 0")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[6].sample_rate_hz", "= -1")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[7].b1", "only with saturation SATURATION_GIVEN")) << all;
  EXPECT_TRUE(HasField(v, "hgann.ranges_preset", "\"papier\"")) << all;
  EXPECT_TRUE(HasField(v, "hgann.ranges[0].name", "must be one of mu, delta, alpha")) << all;
  EXPECT_TRUE(HasField(v, "hgann.ranges[1].max", ">= min (1)")) << all;
  EXPECT_TRUE(HasField(v, "hgann.ranges[3].name", "given twice")) << all;
  EXPECT_TRUE(HasField(v, "hgann.spread_penalty")) << all;
  EXPECT_TRUE(HasField(v, "hgann.geometry.tip_lenght_m", "unknown field")) << all;
  EXPECT_TRUE(HasField(v, "hgann.case_set_dir", "a master never reads client paths")) << all;
  EXPECT_TRUE(HasField(v, "hgann.source")) << all;

  // Saturations given: both required, with their signs.
  s = NominalSpec(10, 1);
  auto& g = std::get<HgannProblem>(s.problem);
  g.saturation = HgannProblem::Saturation::kGiven;
  for (auto& c : g.cases) c.b1 = 1, c.b2 = -1;
  g.cases[0].b2.reset();
  g.cases[1].b1 = -2;
  g.geometry = {{"n_tip", 2.5}};
  auto w = kinds::All().Validate(s);
  EXPECT_TRUE(HasField(w, "hgann.cases[0].b2", "required")) << All(w);
  EXPECT_TRUE(HasField(w, "hgann.cases[1].b1", "= -2: must be finite and > 0")) << All(w);
  EXPECT_TRUE(HasField(w, "hgann.geometry.n_tip", "whole number")) << All(w);

  // No training case; no case at all; a record that stays at 0 cannot give its saturations.
  s = NominalSpec(10, 1);
  for (auto& c : std::get<HgannProblem>(s.problem).cases) c.role = CaseRole::kValidate;
  EXPECT_TRUE(HasField(kinds::All().Validate(s), "hgann.cases", "CASE_ROLE_TRAIN"));
  std::get<HgannProblem>(s.problem).cases.clear();
  EXPECT_TRUE(HasField(kinds::All().Validate(s), "hgann.cases", "at least one case"));
  s = NominalSpec(10, 1);
  auto& z = std::get<HgannProblem>(s.problem).cases[0].angle_deg;
  std::fill(z.begin(), z.end(), 0.0);
  EXPECT_TRUE(HasField(kinds::All().Validate(s), "hgann.cases[0].angle_deg", "never rises above 0"));

  // Geometry values are checked by the beam's own rules.
  s = NominalSpec(10, 1);
  std::get<HgannProblem>(s.problem).geometry = {{"core_width_m", -1}};
  EXPECT_TRUE(HasField(kinds::All().Validate(s), "hgann.geometry.core_width_m"))
      << All(kinds::All().Validate(s));
}

TEST(HgannJob, ExtremeButValidSpecsNeverCrashAnEvaluation) {
  // What a hostile or careless spec can put in front of a worker: each either fails validation
  // with a named field or evaluates every genome to a finite cost.
  std::mt19937_64 rng(9);
  std::vector<std::function<void(HgannProblem&)>> edits = {
      [](HgannProblem& h) { h.cases[0].sample_rate_hz = 1e-300; },
      [](HgannProblem& h) { h.cases[0].sample_rate_hz = 1e300; },
      [](HgannProblem& h) { h.cases[0].amplitude_v = 1e300; },
      [](HgannProblem& h) { h.cases[0].frequency_hz = 1e300; },
      [](HgannProblem& h) { h.cases[0].frequency_hz = 1e-300; },
      [](HgannProblem& h) { h.cases[0].angle_deg.assign(2, 1e300); h.cases[0].angle_deg[1] = -1e300; h.cases[0].voltage_v.clear(); },
      [](HgannProblem& h) { h.ranges = {{"mu", -1e300, 1e300}, {"alpha", 1e300, 1e300}}; },
      [](HgannProblem& h) { h.geometry = {{"core_modulus_pa", 1e-300}, {"n_active", 200}, {"n_tip", 200}}; },
      [](HgannProblem& h) { h.spread_penalty = 1e300; },
  };
  for (size_t e = 0; e < edits.size(); ++e) {
    JobSpec s = NominalSpec(10, 1);
    edits[e](std::get<HgannProblem>(s.problem));
    const auto v = kinds::All().Validate(s);
    if (!v.empty()) {
      EXPECT_FALSE(v.front().field.empty()) << e;
      std::printf("edit %zu refused: %s\n", e, v.front().description.substr(0, 100).c_str());
      continue;
    }
    std::unique_ptr<FitnessFunction> f;
    if (Status st = kinds::All().MakeFitness(s, &f); !st.ok()) {
      EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << e << ": " << st.message();
      std::printf("edit %zu: no fitness: %s\n", e, st.message().substr(0, 100).c_str());
      continue;
    }
    for (int i = 0; i < 5; ++i) {
      Genome g;
      for (int b = 0; b < model::kChromosomeBits; ++b) g.bits.push_back(rng() & 1);
      EXPECT_TRUE(std::isfinite(EvaluateGuarded(*f, g).cost)) << "edit " << e;
    }
    std::printf("edit %zu evaluated\n", e);
  }
}

TEST(HgannJob, BadEnumsInJsonAreNamed) {
  JobSpec s;
  std::vector<FieldViolation> v;
  ASSERT_TRUE(JobSpecFromJson(R"({"version": 1, "hgann": {"saturation": 7, "cases": [{"role": 9}]}})", &s, &v).ok());
  EXPECT_TRUE(HasField(v, "hgann.saturation")) << All(v);
  EXPECT_TRUE(HasField(v, "hgann.cases[0].role")) << All(v);
}

TEST(HgannJobFile, CaseSetDirIsReadRelativeToTheJobFile) {
  JobSpec s;
  std::vector<FieldViolation> v;
  ASSERT_TRUE(client::LoadJobSpecFile(kExamples / "hgann_quick.json", &s, &v).ok()) << All(v);
  const auto& h = std::get<HgannProblem>(s.problem);
  EXPECT_TRUE(h.case_set_dir.empty());
  ASSERT_EQ(h.cases.size(), Nominal().cases.size());
  EXPECT_EQ(h.cases[4].angle_deg, Nominal().cases[4].angle_deg);
  EXPECT_EQ(h.cases[4].voltage_v, Nominal().cases[4].u);
  EXPECT_EQ(h.cases[4].role, CaseRole::kTrain);
  EXPECT_NE(h.source.find("bimorph-fin/nominal"), std::string::npos) << h.source;
  EXPECT_TRUE(kinds::All().Validate(s).empty());
  EXPECT_EQ(s.ga->population, 60);
  EXPECT_EQ(s.ga->generations, 40);

  JobSpec paper;
  ASSERT_TRUE(client::LoadJobSpecFile(kExamples / "hgann_job.json", &paper, &v).ok()) << All(v);
  EXPECT_EQ(paper.ga->population, 400);
  EXPECT_EQ(paper.ga->generations, 1000);
  EXPECT_EQ(paper.ga->stall_generations, 200);
  EXPECT_EQ(paper.ga->mutation_probability, 0.01);
  EXPECT_TRUE(kinds::All().Validate(paper).empty());

  // Cases and a folder at once, or a folder that is not a case set: named.
  v.clear();
  Status st = client::JobSpecFromJsonFile(
      R"({"version": 1, "hgann": {"case_set_dir": "x", "cases": [{"number": 1}]}, "ga": {}})", ".", &s, &v);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(HasField(v, "hgann.case_set_dir", "cannot be combined")) << All(v);
  v.clear();
  st = client::JobSpecFromJsonFile(R"({"version": 1, "hgann": {"case_set_dir": "nowhere"}, "ga": {}})",
                                   fs::path(PIEZOID_TEST_DATA_DIR), &s, &v);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(HasField(v, "hgann.case_set_dir", "cannot be read")) << All(v);
  EXPECT_NE(st.message().find("nowhere"), std::string::npos);
}

}  // namespace
}  // namespace pz::hgann
