// The job-spec codec (service/wire_codec.h) on real specs: an hgann spec survives the binary wire
// and JSON bit for bit (but for the sign of a zero sample in JSON); bad enums in JSON are named.
#include <gtest/gtest.h>

#include <cmath>

#include "hgann/hgann_job.h"
#include "job.pb.h"
#include "kinds/kinds.h"
#include "service/wire_codec.h"
#include "tests/testing/hgann_spec.h"

namespace pz::service {
namespace {

using testing::Descriptions;
using testing::HasViolation;
job::JobSpec NominalSpec(int population, int generations) {
  return testing::NominalHgannSpec(population, generations);
}
bool HasField(const std::vector<job::FieldViolation>& v, const std::string& field,
              const std::string& text = "") {
  return HasViolation(v, field, text);
}
std::string All(const std::vector<job::FieldViolation>& v) { return Descriptions(v); }

using hgann::HgannConfigFromProblem;
using hgann::HgannFitnessConfig;
using job::FieldViolation;
using job::HgannProblem;
using job::JobSpec;

TEST(SpecCodec, SpecSurvivesTheWireAndJsonBitForBit) {
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

TEST(SpecCodec, IslandSettingsRoundTripAndBadOnesAreNamedWithTheirRange) {
  JobSpec s = NominalSpec(10, 1);
  const std::string one_island = EncodeJobSpec(s);
  s.ga->migration_interval = 7;  // not used with one island: the spec encodes as before islands
  EXPECT_TRUE(EncodeJobSpec(s) == one_island);
  s.ga->islands = 4;
  s.ga->migrants = 3;
  s.ga->topology = opt::MigrationTopology::kRandom;
  s.ga->island_stall_generations = 9;
  s.ga->migration_margin = 0.2;
  s.ga->island_mutation = {0.01, 0.02, 0.03, 0.05};
  JobSpec no_broadcast = s;
  no_broadcast.ga->broadcast_margin =
      0.5;  // not used without an interval: encoded as before broadcasts
  s.ga->broadcast_interval = 25;
  s.ga->broadcast_margin = 0.3;
  JobSpec back;
  std::vector<FieldViolation> v;
  ASSERT_TRUE(DecodeJobSpec(EncodeJobSpec(s), &back, &v).ok());
  EXPECT_EQ(back.ga->islands, 4);
  EXPECT_EQ(back.ga->migration_interval, 7);
  EXPECT_EQ(back.ga->migrants, 3);
  EXPECT_EQ(back.ga->topology, opt::MigrationTopology::kRandom);
  EXPECT_EQ(back.ga->island_stall_generations, 9);
  EXPECT_EQ(back.ga->migration_margin, 0.2);
  EXPECT_EQ(back.ga->island_mutation, (std::vector<double>{0.01, 0.02, 0.03, 0.05}));
  EXPECT_EQ(back.ga->broadcast_interval, 25);
  EXPECT_EQ(back.ga->broadcast_margin, 0.3);
  back = JobSpec{};
  ASSERT_TRUE(JobSpecFromJson(JobSpecToJson(s), &back, &v).ok());
  ASSERT_TRUE(back.ga.has_value());
  EXPECT_EQ(back.ga->islands, 4);
  EXPECT_EQ(back.ga->migrants, 3);
  EXPECT_EQ(back.ga->topology, opt::MigrationTopology::kRandom);
  EXPECT_EQ(back.ga->island_stall_generations, 9);
  EXPECT_EQ(back.ga->migration_margin, 0.2);
  EXPECT_EQ(back.ga->island_mutation, (std::vector<double>{0.01, 0.02, 0.03, 0.05}));
  EXPECT_EQ(back.ga->broadcast_interval, 25);
  EXPECT_EQ(back.ga->broadcast_margin, 0.3);
  EXPECT_NE(JobSpecToJson(s).find("\"MIGRATION_TOPOLOGY_RANDOM\""), std::string::npos);
  EXPECT_EQ(JobSpecToJson(no_broadcast).find("broadcast"), std::string::npos);
  // A margin of 0 (every source) is not the default (0.2): it is written, and comes back as 0; a
  // spec that names only its islands gets the measured defaults.
  JobSpec ungated = s;
  ungated.ga->migration_margin = 0;
  ASSERT_TRUE(DecodeJobSpec(EncodeJobSpec(ungated), &back, &v).ok());
  EXPECT_EQ(back.ga->migration_margin, 0);
  back = JobSpec{};
  ASSERT_TRUE(JobSpecFromJson(JobSpecToJson(ungated), &back, &v).ok());
  EXPECT_EQ(back.ga->migration_margin, 0);
  back = JobSpec{};
  ASSERT_TRUE(JobSpecFromJson(R"({"version": 1, "ga": {"islands": 4}})", &back, &v).ok());
  ASSERT_TRUE(back.ga.has_value());
  EXPECT_EQ(back.ga->migration_interval, 25);
  EXPECT_EQ(back.ga->topology, opt::MigrationTopology::kFullyConnected);
  EXPECT_EQ(back.ga->migration_margin, 0.2);
  EXPECT_TRUE(back.ga->island_mutation.empty());
  EXPECT_EQ(back.ga->output_moves, opt::GaOptions::kAutoOutputMoves)
      << "unset: 16 % of the offspring with several islands, 0 with one";
  EXPECT_EQ(JobSpecToJson(s).find("output"), std::string::npos) << "auto is not written";
  // Output moves, 0 (none) included, are written and come back.
  for (int moves : {0, 16}) {
    JobSpec m = s;
    m.ga->output_moves = moves;
    back = JobSpec{};
    ASSERT_TRUE(DecodeJobSpec(EncodeJobSpec(m), &back, &v).ok());
    EXPECT_EQ(back.ga->output_moves, moves);
    back = JobSpec{};
    ASSERT_TRUE(JobSpecFromJson(JobSpecToJson(m), &back, &v).ok());
    EXPECT_EQ(back.ga->output_moves, moves);
  }

  auto violations = [&](auto mutate) {
    JobSpec bad = s;
    mutate(*bad.ga);
    return bad.Validate();
  };
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) { g.islands = 0; }), "ga.islands",
                       "must be in [1, 1024]"));
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) { g.migrants = 10; }), "ga.migrants",
                       "must be in [0, 9]"));
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) { g.migrants = 0; }), "ga.migrants",
                       "must be ≥ 1 when ga.migration_interval > 0"));
  EXPECT_TRUE(HasField(
      violations([](job::GaSettings& g) { g.topology = static_cast<opt::MigrationTopology>(5); }),
      "ga.topology", "MIGRATION_TOPOLOGY_RING"));
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) { g.migration_margin = 1; }),
                       "ga.migration_margin", "must be in [0, 1)"));
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) { g.migration_margin = std::nan(""); }),
                       "ga.migration_margin", "must be in [0, 1)"));
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) { g.broadcast_margin = 0; }),
                       "ga.broadcast_margin", "must be in (0, 1)"));
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) { g.broadcast_margin = std::nan(""); }),
                       "ga.broadcast_margin", "must be in (0, 1)"));
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) {
                         g.migration_interval = 0;
                         g.migrants = 0;
                       }),
                       "ga.migrants", "must be ≥ 1 when ga.broadcast_interval > 0"));
  EXPECT_TRUE(HasField(
      violations([](job::GaSettings& g) {
        g.island_mutation = {0.01, 0.02};
      }),
      "ga.island_mutation.size()",
      "must be 0 (the default ladder: ga.mutation_probability × 1, 2, 3, 5) or ga.islands = 4"));
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) { g.island_mutation[2] = -0.1; }),
                       "ga.island_mutation[2]", "must be in [0, 1]"));
  EXPECT_TRUE(violations([](job::GaSettings& g) { g.island_mutation.clear(); }).empty());
  // population 10, elite 5: 0 … 5 offspring made by moves.
  EXPECT_TRUE(HasField(
      violations([](job::GaSettings& g) { g.output_moves = 6; }), "ga.output_moves",
      "must be in [0, population − round(population · elite_fraction) = 5] (unset: 0 with one "
      "island, 16 % of the offspring with several)"));
  EXPECT_TRUE(HasField(violations([](job::GaSettings& g) { g.output_moves = -2; }),
                       "ga.output_moves", "must be in [0, "));
  EXPECT_TRUE(violations([](job::GaSettings& g) { g.output_moves = 5; }).empty());
  // Both population and elite fraction out of range (the fuzzer's input: 1826206566 − −774244904
  // overflowed an int): every field named, the offspring counted in 64 bits.
  const auto wild = violations([](job::GaSettings& g) {
    g.population = 1826206566;
    g.elite_fraction = -0.42396;
    g.output_moves = 3;
  });
  EXPECT_TRUE(HasField(wild, "ga.population", "must be in [2, 1000000]"));
  EXPECT_TRUE(HasField(wild, "ga.elite_fraction", "must be in (0, 1)"));
  EXPECT_TRUE(violations([](job::GaSettings& g) {
                g.migration_interval = 0, g.migrants = 0, g.broadcast_interval = 0;
              }).empty());
  // A topology name JSON does not know is refused naming the field and the names allowed.
  const Status st = JobSpecFromJson(R"({"version": 1, "ga": {"topology": "STAR"}})", &back, &v);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("(ga.topology)"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("\"STAR\""), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("(allowed: MIGRATION_TOPOLOGY_UNSPECIFIED, MIGRATION_TOPOLOGY_RING, "
                              "MIGRATION_TOPOLOGY_FULLY_CONNECTED, MIGRATION_TOPOLOGY_RANDOM)"),
            std::string::npos)
      << st.message();
  // A negative count is refused by the JSON's unsigned type, naming the field.
  const Status negative = JobSpecFromJson(R"({"version": 1, "ga": {"islands": -1}})", &back, &v);
  EXPECT_NE(negative.message().find("(ga.islands)"), std::string::npos) << negative.message();
}

/// The hgann spec of the nominal bench with `extra` fields in "hgann" and `ga` as "ga", as JSON.
JobSpec FromJson(const std::string& extra, const std::string& ga, std::vector<FieldViolation>* v) {
  JobSpec s;
  const std::string json = R"({"version": 1, "hgann": {"cases": [{"number": 1, "amplitude_v": 500,
      "frequency_hz": 0.5, "role": "CASE_ROLE_TRAIN", "sample_rate_hz": 100,
      "angle_deg": [0, 0.1, -0.2]}])" +
                           extra + "}, \"ga\": " + ga + "}";
  EXPECT_TRUE(JobSpecFromJson(json, &s, v).ok()) << json;
  return s;
}

TEST(SpecCodec, AnEmptyHgannSpecIsTheRobustPresetAndThePaperPresetIsNamed) {
  std::vector<FieldViolation> v;
  // Nothing said: the robust preset (identify's default), for the problem and the GA alike.
  const JobSpec robust = FromJson("", "{}", &v);
  const auto preset = job::HgannSearchPreset("robust");
  ASSERT_TRUE(preset.has_value());
  const auto& hr = std::get<HgannProblem>(robust.problem);
  EXPECT_EQ(robust.ga->islands, 4);
  EXPECT_EQ(robust.ga->generations, 250);
  EXPECT_EQ(hr.spread_penalty, 10);
  EXPECT_TRUE(hr.trend_seeds);
  EXPECT_EQ(robust.ga->islands, preset->islands);
  EXPECT_EQ(robust.ga->generations, preset->generations);
  EXPECT_EQ(job::ToGaOptions(robust, job::GenomeLayout{1415, 0}).OutputMoves(), 32);
  EXPECT_EQ(robust.ga->population, 400);

  // The paper's settings by name: one island, 1000 generations, the paper's cost, uniform bits.
  const JobSpec paper = FromJson(R"(, "preset": "paper")", "{}", &v);
  const auto& hp = std::get<HgannProblem>(paper.problem);
  EXPECT_EQ(paper.ga->islands, 1);
  EXPECT_EQ(paper.ga->generations, 1000);
  EXPECT_EQ(hp.spread_penalty, 0);
  EXPECT_FALSE(hp.trend_seeds);
  EXPECT_EQ(hp.preset, "paper");
  EXPECT_EQ(job::ToGaOptions(paper, job::GenomeLayout{1415, 0}).OutputMoves(), 0);
  // Encoded, a paper-preset spec leaves out what the preset gives (as before presets: islands,
  // λ and the seeds unset).
  wire::JobSpec pw;
  ASSERT_TRUE(pw.ParseFromString(EncodeJobSpec(paper)));
  EXPECT_FALSE(pw.hgann().has_spread_penalty());
  EXPECT_FALSE(pw.hgann().has_trend_seeds());
  EXPECT_FALSE(pw.ga().has_islands());
  EXPECT_EQ(pw.hgann().preset(), "paper");

  // A field given beside a preset is kept, and every spec survives the wire: a robust spec with
  // the paper's values spelled out, a paper spec with the robust ones.
  const JobSpec mixed =
      FromJson(R"(, "spread_penalty": 0, "trend_seeds": false)", R"({"islands": 1})", &v);
  EXPECT_EQ(mixed.ga->islands, 1);
  EXPECT_EQ(std::get<HgannProblem>(mixed.problem).spread_penalty, 0);
  EXPECT_FALSE(std::get<HgannProblem>(mixed.problem).trend_seeds);
  const JobSpec paper_robust = FromJson(R"(, "preset": "paper", "spread_penalty": 10,
      "trend_seeds": true)",
                                        R"({"islands": 4, "generations": 250})", &v);
  EXPECT_EQ(paper_robust.ga->islands, 4);
  EXPECT_TRUE(std::get<HgannProblem>(paper_robust.problem).trend_seeds);
  for (const JobSpec* s : {&robust, &paper, &mixed, &paper_robust}) {
    JobSpec back;
    ASSERT_TRUE(DecodeJobSpec(EncodeJobSpec(*s), &back, &v).ok());
    EXPECT_TRUE(EncodeJobSpec(back) == EncodeJobSpec(*s));
    EXPECT_EQ(back.ga->islands, s->ga->islands);
    EXPECT_EQ(back.ga->generations, s->ga->generations);
    EXPECT_EQ(std::get<HgannProblem>(back.problem).spread_penalty,
              std::get<HgannProblem>(s->problem).spread_penalty);
    EXPECT_EQ(std::get<HgannProblem>(back.problem).trend_seeds,
              std::get<HgannProblem>(s->problem).trend_seeds);
    EXPECT_TRUE(kinds::All().Validate(back).empty()) << All(kinds::All().Validate(back));
  }

  // An unknown preset is named with the allowed ones.
  const JobSpec bad = FromJson(R"(, "preset": "fast")", "{}", &v);
  const auto violations = kinds::All().Validate(bad);
  EXPECT_TRUE(HasField(violations, "hgann.preset", "hgann.preset = \"fast\": must be \"robust\""))
      << All(violations);
}

TEST(SpecCodec, BadEnumsInJsonAreNamed) {
  JobSpec s;
  std::vector<FieldViolation> v;
  ASSERT_TRUE(JobSpecFromJson(
                  R"({"version": 1, "hgann": {"saturation": 7, "cases": [{"role": 9}]}})", &s, &v)
                  .ok());
  EXPECT_TRUE(HasField(v, "hgann.saturation")) << All(v);
  EXPECT_TRUE(HasField(v, "hgann.cases[0].role")) << All(v);
}

// The removed "diagnose" kind (issue 38): its tag and name are reserved in proto/job.proto, and an
// old spec holding one is refused naming the kind, from JSON and from the wire (where the problem
// arrives as an unknown field), instead of being read as a spec without a problem.
TEST(SpecCodec, ASpecOfTheRemovedDiagnoseKindIsRefusedNamingIt) {
  JobSpec s;
  std::vector<FieldViolation> v;
  const Status json = JobSpecFromJson(
      R"({"version": 1, "diagnose": {"structure": ["creep"]}, "external": {}})", &s, &v);
  ASSERT_FALSE(json.ok());
  EXPECT_NE(json.message().find("the job kind \"diagnose\" (the fin engine's fits) was removed"),
            std::string::npos)
      << json.message();
  JobSpec old;
  old.external = job::ExternalSettings{};
  pz::wire::JobSpec p;
  ASSERT_TRUE(p.ParseFromString(EncodeJobSpec(old)));
  p.GetReflection()->MutableUnknownFields(&p)->AddLengthDelimited(13,
                                                                  std::string("\x1a\x05creep", 7));
  ASSERT_TRUE(DecodeJobSpec(p.SerializeAsString(), &s, &v).ok());
  EXPECT_TRUE(HasField(v, "problem", "the job kind \"diagnose\"")) << All(v);
  EXPECT_EQ(s.kind(), "");
  // Without it, the same spec decodes without a violation (the kinds' check then names the kinds).
  v.clear();
  ASSERT_TRUE(DecodeJobSpec(EncodeJobSpec(old), &s, &v).ok());
  EXPECT_TRUE(v.empty()) << All(v);
}

}  // namespace
}  // namespace pz::service
