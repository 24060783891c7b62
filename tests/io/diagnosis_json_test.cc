// diagnosis.json's codec (io/diagnosis_json.h over io/proto_json.h), for both diagnoses: the files
// of tests/data/diagnosis-json (written by `piezoid diagnose` before the codec, when both writers
// built the file key by key) read and are written back to the same bytes; a message of each kind
// round-trips; the fields of the other kind are neither written nor read; a bad field is named.
// And check.json of `diagnose-check` (proto::DiagnosisCheck, through io/proto_json.h).
#include "io/diagnosis_json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "diagnosis.pb.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "model/status.h"
#include "tests/testing/text_edit.h"

namespace pz::io {
namespace {

namespace fs = std::filesystem;
using testing::Replaced;
using testing::ValueReplaced;

fs::path Data(const std::string& name) {
  return fs::path(PIEZOID_TEST_DATA_DIR) / "diagnosis-json" / name;
}

std::string ErrorOf(const std::string& text) {
  proto::Diagnosis d;
  try {
    ReadDiagnosisFile("x/diagnosis.json", text, &d);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(read)";
}

TEST(DiagnosisCodec, AnOldDiagnosisJsonOfEitherKindReadsAndIsWrittenBackToTheSameBytes) {
  for (const char* name :
       {"records-none.json", "records-effect.json", "records-auto.json", "bench.json"}) {
    const std::string text = ReadTextFile(Data(name));
    proto::Diagnosis d;
    ReadDiagnosisFile(name, text, &d);
    EXPECT_FALSE(d.verdict().empty()) << name;
    EXPECT_EQ(WriteDiagnosisFile(d), text) << name;
  }
  proto::Diagnosis d;
  ReadDiagnosisFile("records-none.json", ReadTextFile(Data("records-none.json")), &d);
  EXPECT_TRUE(IsRecordsDiagnosis(d));
  EXPECT_EQ(d.named().kind_case(), google::protobuf::Value::kNullValue);
  EXPECT_EQ(d.candidates_size(), 2);
  EXPECT_TRUE(d.has_excitation());
  EXPECT_FALSE(d.has_selection());
  EXPECT_TRUE(d.rounds().empty());
  ReadDiagnosisFile("records-effect.json", ReadTextFile(Data("records-effect.json")), &d);
  EXPECT_EQ(d.named().string_value(), "delay");
  EXPECT_EQ(d.verdict_kind(), "effect");
  ReadDiagnosisFile("records-auto.json", ReadTextFile(Data("records-auto.json")), &d);
  EXPECT_TRUE(d.has_selection());
  EXPECT_FALSE(d.selection().ranking().empty());
  ReadDiagnosisFile("bench.json", ReadTextFile(Data("bench.json")), &d);
  EXPECT_FALSE(IsRecordsDiagnosis(d));
  EXPECT_EQ(d.bench(), "data/bimorph-fin/delay");
  ASSERT_EQ(d.named().list_value().values_size(), 1);
  EXPECT_EQ(d.named().list_value().values(0).string_value(), "delay");
  ASSERT_EQ(d.rounds_size(), 2);
  EXPECT_EQ(d.rounds(0).named().string_value(), "delay");
  EXPECT_EQ(d.rounds(1).named().kind_case(), google::protobuf::Value::kNullValue);
  EXPECT_TRUE(d.rounds(0).candidates(0).has_fit());
  EXPECT_EQ(d.base_residuals().cases_size(), 9);
  EXPECT_TRUE(d.candidates().empty());
  EXPECT_FALSE(d.has_noise_floor());
}

/// A records diagnosis with every optional part but the selection (a next measurement, a
/// diverged candidate, a non-finite number).
proto::Diagnosis RecordsMessage() {
  proto::Diagnosis d;
  d.set_records("runs/set \"a\"");
  d.set_family("prandtl-ishlinskii");
  d.set_verdict_kind("inseparable");
  d.set_verdict("delay or driver-lowpass\nline 2");
  d.mutable_named()->set_string_value("delay");
  d.set_confidence(0.62);
  d.mutable_noise_floor()->set_sigma(0.05);
  d.mutable_noise_floor()->add_estimates()->set_samples(int64_t{1} << 40);
  proto::DiagnosisCandidate& c = *d.add_candidates();
  c.set_effect("delay");
  c.set_closed(0.9);
  c.set_z_vs_base(4.5);
  d.add_diverged("creep");
  d.set_withheld_samples(1200);
  d.mutable_runner_up()->set_effect("driver-lowpass");
  d.mutable_runner_up()->set_z(0.8);
  d.mutable_next_measurement()->set_waveform("sine");
  d.mutable_next_measurement()->set_frequency_hz(12.5);
  d.mutable_excitation()->set_excitation_gap(true);
  return d;
}

proto::Diagnosis BenchMessage() {
  proto::Diagnosis d;
  d.set_bench("data/bimorph-fin/delay");
  d.set_verdict_kind("effect");
  d.set_verdict("The gap is delay.");
  d.mutable_named()->mutable_list_value()->add_values()->set_string_value("delay");
  d.set_confidence(0.97);
  proto::DiagnosisRound& r = *d.add_rounds();
  r.add_from("delay");
  r.mutable_named()->set_string_value("creep");
  r.mutable_runner_up()->set_effect("drift");
  r.mutable_runner_up()->set_z(1.5);
  proto::DiagnosisCandidate& c = *r.add_candidates();
  c.set_effect("creep");
  c.set_added_parameters(2);
  c.set_weight(0.25);
  c.mutable_fit()->add_case_pi_deg2(0.5);
  d.add_trends()->set_slope_per_v(1e-3);
  d.mutable_gap()->add_cases()->set_case_(3);
  d.set_evaluations(int64_t{1} << 50);
  return d;
}

TEST(DiagnosisCodec, AMessageOfEitherKindRoundTripsWithOnlyItsKindsFields) {
  for (const proto::Diagnosis& d : {RecordsMessage(), BenchMessage()}) {
    const std::string text = WriteDiagnosisFile(d);
    proto::Diagnosis back;
    ReadDiagnosisFile("x", text, &back);
    EXPECT_EQ(back.DebugString(), d.DebugString()) << text;
    EXPECT_EQ(WriteDiagnosisFile(back), text);
  }
  const std::string records = WriteDiagnosisFile(RecordsMessage());
  for (const char* key : {"\"diverged\"", "\"candidates\"", "\"next_measurement\"", "\"runner_up\"",
                          "\"z_vs_base\"", "\"noise_floor\"", "\"excitation_gap_note\""})
    EXPECT_NE(records.find(key), std::string::npos) << key;
  // the bench's fields, a list or a number at its default, are not written
  for (const char* key :
       {"\"rounds\"", "\"trends\"", "\"absorbed\"", "\"absorbed_by\"", "\"wall_time_s\"",
        "\"evaluations\"", "\"added_parameters\"", "\"weight\"", "\"bench\""})
    EXPECT_EQ(records.find(key), std::string::npos) << key;
  const std::string bench = WriteDiagnosisFile(BenchMessage());
  for (const char* key : {"\"diverged\"", "\n \"candidates\"", "\"z_vs_base\"",
                          "\"withheld_samples\"", "\"family\"", "\"records\""})
    EXPECT_EQ(bench.find(key), std::string::npos) << key;
  EXPECT_NE(bench.find("\"added_parameters\": 2"), std::string::npos) << bench;
  EXPECT_NE(bench.find("\"runner_up\": {\n    \"effect\": \"drift\""), std::string::npos) << bench;
  EXPECT_NE(bench.find("\"evaluations\": 1125899906842624"), std::string::npos) << bench;
}

TEST(DiagnosisCodec, ANonFiniteNumberIsNullAndReadsBackAsNaN) {
  proto::Diagnosis d = BenchMessage();
  d.set_confidence(NAN);  // nothing named
  d.mutable_rounds(0)->mutable_candidates(0)->set_closed(INFINITY);
  const std::string text = WriteDiagnosisFile(d);
  EXPECT_NE(text.find("\"confidence\": null"), std::string::npos) << text;
  EXPECT_NE(text.find("\"closed\": null"), std::string::npos) << text;
  proto::Diagnosis back;
  ReadDiagnosisFile("x", text, &back);
  EXPECT_TRUE(std::isnan(back.confidence()));
  EXPECT_TRUE(std::isnan(back.rounds(0).candidates(0).closed()));
}

TEST(DiagnosisCodec, AFileOfOneKindWithAFieldOfTheOtherIsRefusedByName) {
  const std::string records = ReadTextFile(Data("records-none.json"));
  const std::string trends = ErrorOf(Replaced(records, "{", "{", "{\n \"trends\": [],"));
  EXPECT_NE(trends.find("x/diagnosis.json: trends: a field of the fin bench's diagnosis in a "
                        "records diagnosis"),
            std::string::npos)
      << trends;
  const std::string weight =
      ErrorOf(Replaced(records, "\"candidates\"", "\"effect\"", "\"weight\": 1, \"effect\""));
  EXPECT_NE(weight.find("x/diagnosis.json: candidates[0].weight: a field of the fin bench's"),
            std::string::npos)
      << weight;
  const std::string bench = ReadTextFile(Data("bench.json"));
  const std::string z =
      ErrorOf(Replaced(bench, "\"rounds\"", "\"effect\"", "\"z_vs_base\": 1, \"effect\""));
  EXPECT_NE(z.find("x/diagnosis.json: rounds[0].candidates[0].z_vs_base: a field of a records "
                   "diagnosis in the fin bench's diagnosis"),
            std::string::npos)
      << z;
  EXPECT_NE(ErrorOf(Replaced(bench, "{", "{", "{\n \"records\": \"set\",")).find("both"),
            std::string::npos);
  EXPECT_NE(ErrorOf("{\"verdict\": \"x\"}").find("x/diagnosis.json: neither \"records\""),
            std::string::npos);
  EXPECT_NE(ErrorOf("[1]").find("x/diagnosis.json: not a JSON object"), std::string::npos);
  EXPECT_NE(ErrorOf(ValueReplaced(records, "\"records\": ", "null"))
                .find("x/diagnosis.json: records: not a string (the record set)"),
            std::string::npos);
}

TEST(DiagnosisCodec, ABadFieldOrANamedOfTheWrongShapeIsNamed) {
  const std::string records = ReadTextFile(Data("records-none.json"));
  const std::string unknown = ErrorOf(Replaced(records, "\"candidates\"", "\"score\"", "\"scor\""));
  EXPECT_NE(unknown.find("x/diagnosis.json: candidates[0].scor: Cannot find field"),
            std::string::npos)
      << unknown;
  const std::string typed = ErrorOf(ValueReplaced(records, "\"withheld_samples\": ", "\"many\""));
  EXPECT_NE(typed.find("x/diagnosis.json: withheld_samples"), std::string::npos) << typed;
  const std::string list =
      ErrorOf(Replaced(records, "\"named\"", "\"named\": null", "\"named\": [\"delay\"]"));
  EXPECT_NE(list.find("x/diagnosis.json: named: not the effect named (a string) or null"),
            std::string::npos)
      << list;
  const std::string bench = ReadTextFile(Data("bench.json"));
  const std::string one =
      ErrorOf(Replaced(bench, "\"named\": [", "\"named\": [\n  \"delay\"\n ]", "\"named\": 1"));
  EXPECT_NE(one.find("x/diagnosis.json: named: not a list of the effects named"), std::string::npos)
      << one;
  const std::string round =
      ErrorOf(Replaced(bench, "\"rounds\"", "\"named\": \"delay\"", "\"named\": 2"));
  EXPECT_NE(round.find("x/diagnosis.json: rounds[0].named: not the effect named"),
            std::string::npos)
      << round;
}

TEST(DiagnosisCodec, TheWriterRefusesAMessageOfNoKindOrAFieldOfTheOtherKind) {
  proto::Diagnosis none;
  EXPECT_THROW(WriteDiagnosisFile(none), std::logic_error);
  proto::Diagnosis both = RecordsMessage();
  both.set_bench("b");
  EXPECT_THROW(WriteDiagnosisFile(both), std::logic_error);
  proto::Diagnosis mixed = RecordsMessage();
  mixed.set_absorbed_by("creep");
  EXPECT_THROW(WriteDiagnosisFile(mixed), std::logic_error);
  proto::Diagnosis shape = BenchMessage();
  shape.mutable_named()->set_string_value("delay");
  EXPECT_THROW(WriteDiagnosisFile(shape), std::logic_error);
}

TEST(DiagnosisCheckFile, AnOldCheckJsonReadsAndPrintsBackToTheSameBytes) {
  const std::string text = ReadTextFile(Data("check.json"));
  proto::DiagnosisCheck c;
  ReadJsonMessage("check.json", text, &c);
  EXPECT_EQ(PrintJson(c, "check.json"), text);
  ASSERT_EQ(c.trials_size(), 3);
  EXPECT_EQ(c.trials(0).seed(), 1u);
  EXPECT_EQ(c.columns_size(), static_cast<int>(c.confusion().size()) + 1);  // + unexplained
  ASSERT_TRUE(c.confusion().contains("none"));
  EXPECT_EQ(c.confusion().at("none").values_size(), c.columns_size());
}

}  // namespace
}  // namespace pz::io
