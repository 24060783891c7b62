// The JSON of `piezoid diagnose` (reports/diagnose_report.h) through its message
// (proto/diagnosis.proto): diagnosis.json by its codec (io/diagnosis_json.h). Each parses back, a
// string with quotes and a newline keeps them, a non-finite number is null, the names the users
// read are there, and each reads back into its message and prints back to the same bytes.
#include "reports/diagnose_report.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "diagnose/diagnose.h"
#include "diagnosis.pb.h"
#include "io/diagnosis_json.h"
#include "io/proto_json.h"
#include "records/families.h"
#include "records/model.h"
#include "records/registry.h"

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

TEST(DiagnoseReport, DiagnosisJsonParsesBackWithItsNamesNullsAndEscapes) {
  diagnose::BenchDiagnosis d;
  d.bench = "bench \"a\"\nline 2";
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
  diagnose::DiagnoseOptions o;
  std::ostringstream out;
  WriteDiagnosisJson(out, d, o);
  const Struct s = Parse(out.str());
  EXPECT_EQ(Field(s, "bench").string_value(), d.bench);
  EXPECT_EQ(Field(s, "verdict_kind").string_value(), "none");
  EXPECT_EQ(Field(s, "confidence").kind_case(), Value::kNullValue);  // nothing named
  EXPECT_EQ(Field(s, "evaluations").number_value(), 123456789);
  EXPECT_EQ(Field(Field(s, "noise").struct_value(), "quantum_deg").number_value(), d.quantum_deg);
  EXPECT_EQ(Field(Field(s, "thresholds").struct_value(), "significance_ratio").number_value(),
            o.rules.significance_ratio);
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
  EXPECT_EQ(Field(round, "named").kind_case(), Value::kNullValue);
  EXPECT_EQ(Field(Field(s, "base").struct_value(), "structure").string_value(), "base");
  for (const char* name : {"base", "final", "base_residuals", "final_residuals", "trends",
                           "absorbed", "absorbed_by", "named", "wall_time_s"})
    EXPECT_TRUE(s.fields().contains(name)) << name;
  for (const char* name : {"candidates", "diverged", "records", "noise_floor", "excitation"})
    EXPECT_FALSE(s.fields().contains(name)) << name;  // the records diagnosis's
  // The file reads back into the message it was written from: the same bytes again, and the same
  // message but for the non-finite numbers (null reads as NaN, which equals nothing).
  proto::Diagnosis m, back;
  BenchDiagnosisOf(d, o, &m);
  io::ReadDiagnosisFile("diagnosis.json", out.str(), &back);
  EXPECT_EQ(io::WriteDiagnosisFile(back), out.str());
  EXPECT_TRUE(std::isnan(back.confidence()));
  EXPECT_TRUE(std::isnan(back.gap().closed()));
  m.clear_confidence();
  back.clear_confidence();
  m.clear_gap();  // closed; remaining_over_floor: no floor
  back.clear_gap();
  m.clear_base();  // train_rms_deg, withheld_rms_deg: no samples
  back.clear_base();
  m.clear_final();
  back.clear_final();
  m.clear_rounds();  // rms_over_floor of no floor
  back.clear_rounds();
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(m, back)) << out.str();
  EXPECT_EQ(back.bench(), d.bench);
  EXPECT_EQ(back.named().list_value().values_size(), 0);
}

TEST(DiagnoseReport, ARoundWithARunnerUpNamesItAndItsZ) {
  const model::EffectKind delay = model::EffectKind::Named("delay"),
                          lowpass = model::EffectKind::Named("driver-lowpass");
  diagnose::BenchDiagnosis d;
  d.bench = "bench";
  diagnose::RecordDiagnosis& r = d.records;
  r.verdict_kind = "inseparable";
  r.named_effects = {delay};
  r.confidence = 0.6;
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
  std::ostringstream out;
  WriteDiagnosisJson(out, d, diagnose::DiagnoseOptions{});
  proto::Diagnosis back;
  io::ReadDiagnosisFile("diagnosis.json", out.str(), &back);
  ASSERT_EQ(back.rounds_size(), 2);
  EXPECT_EQ(back.rounds(0).named().string_value(), "delay");
  EXPECT_EQ(back.rounds(0).runner_up().effect(), "driver-lowpass");
  EXPECT_EQ(back.rounds(0).runner_up().z(), 0.75);
  ASSERT_EQ(back.rounds(1).from_size(), 1);  // the second round starts from the named model
  EXPECT_EQ(back.rounds(1).from(0), "delay");
  EXPECT_FALSE(back.rounds(1).has_runner_up());
  EXPECT_FALSE(back.has_runner_up());  // the bench's is in its round
  EXPECT_EQ(back.named().list_value().values(0).string_value(), "delay");
  EXPECT_EQ(back.confidence(), 0.6);
  EXPECT_EQ(back.final().structure(), "base + delay");
  ASSERT_EQ(back.rounds(0).candidates_size(), 2);
  EXPECT_EQ(back.rounds(0).candidates(1).fit().structure(), "base + driver-lowpass");
}

}  // namespace
}  // namespace pz::reports
