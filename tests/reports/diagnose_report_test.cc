// The one report of `piezoid diagnose` (reports/diagnose_report.h) with the fin bench's grid
// section (reports/bench_grid.h): the grid's part of diagnosis.json (proto::BenchGrid) with its
// names, nulls and rounds, and the whole report folder of a small diagnosis of a bundled bench —
// the records report plus its grid section, diagnosis.json in one shape that reads back.
#include "reports/diagnose_report.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "diagnose/diagnose.h"
#include "diagnosis.pb.h"
#include "io/bench_data.h"
#include "io/csv.h"
#include "io/diagnosis_json.h"
#include "io/fin_records.h"
#include "io/proto_json.h"
#include "records/families.h"
#include "records/model.h"
#include "records/registry.h"
#include "reports/bench_grid.h"

namespace pz::reports {
namespace {

using google::protobuf::Struct;
using google::protobuf::Value;

Struct Parse(const std::string& text) {
  Struct s;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(text, &s).ok()) << text;
  return s;
}

const Value& Field(const Struct& s, const std::string& name) {
  static const Value missing;
  const auto it = s.fields().find(name);
  EXPECT_NE(it, s.fields().end()) << name;
  return it == s.fields().end() ? missing : it->second;
}

// A records fit of bimorph-fin's bench form with `effects`, nothing fitted.
records::FitResult Fit(std::vector<model::EffectKind> effects, int64_t evaluations = 0) {
  records::FamilyOptions fo;
  fo.bench_form = true;
  const records::DataScale scale;
  records::FitResult f;
  f.model = std::make_shared<records::RecordModel>(records::MakeFamily("bimorph-fin", scale, fo),
                                                   std::move(effects), scale);
  f.evaluations = evaluations;
  return f;
}

TEST(DiagnoseReport, TheGridsMessageHasItsNamesAndNulls) {
  diagnose::BenchDiagnosis d;
  d.bench = "bench";
  diagnose::RecordDiagnosis& r = d.records;
  r.verdict_kind = "none";
  r.verdict = "No significant gap.";
  d.quantum_deg = 360.0 / 8192;
  r.s0 = 0.5;
  r.closed_total = NAN;  // no excess: undefined
  r.base = Fit({}, 123456789);
  r.final_fit = std::make_shared<records::FitResult>(r.base);
  diagnose::RecordGap g;
  g.rms_before = 0.0798;
  r.gaps.push_back(g);
  d.cases.emplace_back();
  d.cases.back().number = 3;
  proto::BenchGrid m;
  BenchGridOf(d, &m);
  const Struct s = Parse(io::PrintJson(m, "grid"));
  EXPECT_EQ(Field(s, "evaluations").number_value(), 123456789);
  EXPECT_EQ(Field(Field(s, "noise").struct_value(), "quantum_deg").number_value(), d.quantum_deg);
  EXPECT_EQ(Field(Field(s, "thresholds").struct_value(), "significance_ratio").number_value(),
            d.rules.significance_ratio);
  const Struct& gap = Field(s, "gap").struct_value();
  EXPECT_EQ(Field(gap, "closed").kind_case(), Value::kNullValue);
  EXPECT_EQ(Field(gap, "withheld_pi_before_deg2").number_value(), 0.5);
  ASSERT_EQ(Field(gap, "cases").list_value().values_size(), 1);
  const Struct& c = Field(gap, "cases").list_value().values(0).struct_value();
  EXPECT_EQ(Field(c, "case").number_value(), 3);
  EXPECT_EQ(Field(c, "rms_before_deg").number_value(), 0.0798);
  ASSERT_EQ(Field(s, "rounds").list_value().values_size(), 1);  // no second round run
  const Struct& round = Field(s, "rounds").list_value().values(0).struct_value();
  EXPECT_EQ(Field(round, "withheld_pi_deg2").number_value(), 0.5);
  EXPECT_FALSE(round.fields().contains("named"));  // nothing named
  EXPECT_EQ(Field(Field(s, "base").struct_value(), "structure").string_value(), "base");
  for (const char* name :
       {"base", "final", "base_residuals", "final_residuals", "trends", "absorbed", "wall_time_s"})
    EXPECT_TRUE(s.fields().contains(name)) << name;
}

TEST(DiagnoseReport, ARoundWithARunnerUpNamesItAndItsZ) {
  const model::EffectKind delay = model::EffectKind::Named("delay"),
                          lowpass = model::EffectKind::Named("driver-lowpass");
  diagnose::BenchDiagnosis d;
  diagnose::RecordDiagnosis& r = d.records;
  r.named_effects = {delay};
  r.base = Fit({});
  r.candidates.resize(2);
  r.candidates[0].kind = delay;
  r.candidates[0].fit = Fit({delay});
  r.candidates[1].kind = lowpass;
  r.candidates[1].fit = Fit({lowpass});
  r.named = 0;
  r.runner_up = 1;
  r.z_runner_up = 0.75;
  r.final_fit = std::make_shared<records::FitResult>(r.candidates[0].fit);
  r.second = diagnose::RecordRound{};  // no runner-up: none written
  proto::BenchGrid back;
  BenchGridOf(d, &back);
  ASSERT_EQ(back.rounds_size(), 2);
  EXPECT_EQ(back.rounds(0).named(), "delay");
  EXPECT_EQ(back.rounds(0).runner_up().effect(), "driver-lowpass");
  EXPECT_EQ(back.rounds(0).runner_up().z(), 0.75);
  ASSERT_EQ(back.rounds(1).from_size(), 1);  // the second round starts from the named model
  EXPECT_EQ(back.rounds(1).from(0), "delay");
  EXPECT_FALSE(back.rounds(1).has_runner_up());
  EXPECT_FALSE(back.rounds(1).has_named());
  EXPECT_EQ(back.final().structure(), "base + delay");
  ASSERT_EQ(back.rounds(0).candidates_size(), 2);
  EXPECT_EQ(back.rounds(0).candidates(1).fit().structure(), "base + driver-lowpass");
  EXPECT_EQ(back.rounds(0).candidates(1).added_parameters(), 0);  // no parameter in Fit()
}

// The bench's report is the records report plus its grid section: a small diagnosis of the
// bundled delay bench (one candidate, small searches, no trends, no second round) written whole.
TEST(DiagnoseReport, TheBenchsReportIsTheRecordsReportWithItsGridSection) {
  const io::RecordSet set =
      io::RecordsFromCaseSet(io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/delay"));
  diagnose::DiagnoseOptions o;
  o.candidates = {model::EffectKind::Named("delay")};
  o.de_base = {.population = 10, .generations = 4, .stall_generations = 0};
  o.de_candidate = {.population = 10, .generations = 3, .stall_generations = 0};
  o.lm.max_iterations = 4;
  o.second_effect = false;
  o.trends = false;
  const diagnose::BenchDiagnosis d = diagnose::DiagnoseBench(set, o);
  const auto dir =
      std::filesystem::temp_directory_path() / ("pz_bench_report_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::vector<std::string> warnings =
      WriteDiagnosisFolder(dir, d.set, d.records, {.grid = &d}, false);
  EXPECT_TRUE(warnings.empty());
  const std::string md = io::ReadTextFile(dir / "report.md");
  for (const char* part : {"**Verdict (", "## Noise floor", "## Candidates (ranked by score)",
                           "## The V × f grid", "| 375 V |", "### Round 1", "### How far",
                           "### Identifiability", "figures/case9_loop.png", "## Excitation"})
    EXPECT_NE(md.find(part), std::string::npos) << part;
  EXPECT_TRUE(std::filesystem::exists(dir / "figures" / "case1_trace.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "figures" / "withheld_case2.csv"));
  proto::Diagnosis back;
  io::ReadDiagnosisFile("diagnosis.json", io::ReadTextFile(dir / "diagnosis.json"), &back);
  EXPECT_EQ(back.records(), set.source.string());
  EXPECT_EQ(back.family(), "bimorph-fin");
  EXPECT_EQ(back.response_unit(), "deg");
  EXPECT_EQ(back.verdict(), d.records.verdict);
  ASSERT_TRUE(back.has_grid());
  EXPECT_EQ(back.grid().noise().cases_size(), 9);
  EXPECT_EQ(back.grid().gap().cases_size(), 9);
  ASSERT_EQ(back.grid().rounds_size(), 1);
  ASSERT_EQ(back.candidates_size(), back.grid().rounds(0).candidates_size());
  EXPECT_EQ(back.candidates(0).score(), back.grid().rounds(0).candidates(0).score());
  EXPECT_EQ(back.named_size(), static_cast<int>(d.records.named_effects.size()));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pz::reports
