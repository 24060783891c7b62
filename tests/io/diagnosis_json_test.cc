// diagnosis.json's codec (io/diagnosis_json.h over io/proto_json.h): the version-1 files of
// tests/data/diagnosis-json (two kinds, written by `piezoid diagnose` before issue 46) read,
// converted to version 2's one shape (the bench's parts in "grid", "named" a list), and written
// back in version 2, which reads back to the same bytes; a record set's and a bench's message
// round-trip; an unknown version, a "named" of the wrong shape and a bad field are named.
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

TEST(DiagnosisCodec, AVersionOneFileOfEitherKindReadsConvertedToVersionTwo) {
  for (const char* name :
       {"records-none.json", "records-effect.json", "records-auto.json", "bench.json"}) {
    const std::string text = ReadTextFile(Data(name));
    proto::Diagnosis d;
    ReadDiagnosisFile(name, text, &d);
    EXPECT_FALSE(d.verdict().empty()) << name;
    EXPECT_EQ(d.format_version(), static_cast<uint32_t>(kDiagnosisFormatVersion)) << name;
    const std::string two = WriteDiagnosisFile(d);
    EXPECT_NE(two.find("\"format_version\": 2"), std::string::npos) << name;
    EXPECT_EQ(two.find("\"bench\""), std::string::npos) << name;
    proto::Diagnosis back;  // version 2 reads back to the same bytes
    ReadDiagnosisFile(name, two, &back);
    EXPECT_EQ(WriteDiagnosisFile(back), two) << name;
  }
  proto::Diagnosis d;
  ReadDiagnosisFile("records-none.json", ReadTextFile(Data("records-none.json")), &d);
  EXPECT_FALSE(IsBenchDiagnosis(d));
  EXPECT_TRUE(d.named().empty());  // null: nothing named
  EXPECT_EQ(d.candidates_size(), 2);
  EXPECT_TRUE(d.has_excitation());
  EXPECT_FALSE(d.has_selection());
  EXPECT_FALSE(d.has_grid());
  ReadDiagnosisFile("records-effect.json", ReadTextFile(Data("records-effect.json")), &d);
  ASSERT_EQ(d.named_size(), 1);
  EXPECT_EQ(d.named(0), "delay");
  EXPECT_EQ(d.verdict_kind(), "effect");
  ReadDiagnosisFile("records-auto.json", ReadTextFile(Data("records-auto.json")), &d);
  EXPECT_TRUE(d.has_selection());
  EXPECT_FALSE(d.selection().ranking().empty());
  ReadDiagnosisFile("bench.json", ReadTextFile(Data("bench.json")), &d);
  EXPECT_TRUE(IsBenchDiagnosis(d));
  EXPECT_EQ(d.records(), "data/bimorph-fin/delay");
  ASSERT_EQ(d.named_size(), 1);
  EXPECT_EQ(d.named(0), "delay");
  EXPECT_NEAR(d.confidence(), 0.967, 1e-3);
  const proto::BenchGrid& g = d.grid();
  ASSERT_EQ(g.rounds_size(), 2);
  EXPECT_EQ(g.rounds(0).named(), "delay");
  EXPECT_FALSE(g.rounds(1).has_named());  // null: nothing named
  EXPECT_TRUE(g.rounds(0).candidates(0).has_fit());
  EXPECT_EQ(g.base_residuals().cases_size(), 9);
  EXPECT_EQ(g.noise().cases_size(), 9);
  EXPECT_EQ(g.gap().cases_size(), 9);
  EXPECT_FALSE(g.trends().empty());
  EXPECT_GT(g.evaluations(), 0);
  EXPECT_TRUE(d.candidates().empty());
  EXPECT_FALSE(d.has_noise_floor());
}

/// A record set's diagnosis with every optional part but the selection (a next measurement, a
/// diverged candidate, a non-finite number).
proto::Diagnosis RecordsMessage() {
  proto::Diagnosis d;
  d.set_records("runs/set \"a\"");
  d.set_family("prandtl-ishlinskii");
  d.set_verdict_kind("inseparable");
  d.set_verdict("delay or driver-lowpass\nline 2");
  d.add_named("delay");
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

/// The fin bench's: the records diagnosis's fields and its grid.
proto::Diagnosis BenchMessage() {
  proto::Diagnosis d;
  d.set_records("data/bimorph-fin/delay");
  d.set_family("bimorph-fin");
  d.set_verdict_kind("effect");
  d.set_verdict("The gap is delay.");
  d.add_named("delay");
  d.add_named("creep");
  d.set_confidence(0.97);
  proto::BenchGrid& g = *d.mutable_grid();
  proto::DiagnosisRound& r = *g.add_rounds();
  r.add_from("delay");
  r.set_named("creep");
  r.mutable_runner_up()->set_effect("drift");
  r.mutable_runner_up()->set_z(1.5);
  proto::DiagnosisCandidate& c = *r.add_candidates();
  c.set_effect("creep");
  c.set_added_parameters(2);
  c.set_weight(0.25);
  c.mutable_fit()->add_case_pi_deg2(0.5);
  g.add_trends()->set_slope_per_v(1e-3);
  g.mutable_gap()->add_cases()->set_case_(3);
  g.set_evaluations(int64_t{1} << 50);
  return d;
}

TEST(DiagnosisCodec, AMessageOfEitherDiagnosisRoundTrips) {
  for (proto::Diagnosis d : {RecordsMessage(), BenchMessage()}) {
    const std::string text = WriteDiagnosisFile(d);
    proto::Diagnosis back;
    ReadDiagnosisFile("x", text, &back);
    d.set_format_version(kDiagnosisFormatVersion);
    EXPECT_EQ(back.DebugString(), d.DebugString()) << text;
    EXPECT_EQ(WriteDiagnosisFile(back), text);
  }
  const std::string records = WriteDiagnosisFile(RecordsMessage());
  for (const char* key : {"\"diverged\"", "\"candidates\"", "\"next_measurement\"", "\"runner_up\"",
                          "\"z_vs_base\"", "\"noise_floor\"", "\"named\": [\n  \"delay\"\n ]"})
    EXPECT_NE(records.find(key), std::string::npos) << key;
  EXPECT_EQ(records.find("\"grid\""), std::string::npos);  // a record set's: no grid
  const std::string bench = WriteDiagnosisFile(BenchMessage());
  EXPECT_NE(bench.find("\"added_parameters\": 2"), std::string::npos) << bench;
  EXPECT_NE(bench.find("\"named\": \"creep\""), std::string::npos) << bench;
  EXPECT_NE(bench.find("\"evaluations\": 1125899906842624"), std::string::npos) << bench;
}

TEST(DiagnosisCodec, ANonFiniteNumberIsNullAndReadsBackAsNaN) {
  proto::Diagnosis d = BenchMessage();
  d.set_confidence(NAN);  // nothing named
  d.mutable_grid()->mutable_rounds(0)->mutable_candidates(0)->set_closed(INFINITY);
  const std::string text = WriteDiagnosisFile(d);
  EXPECT_NE(text.find("\"confidence\": null"), std::string::npos) << text;
  EXPECT_NE(text.find("\"closed\": null"), std::string::npos) << text;
  proto::Diagnosis back;
  ReadDiagnosisFile("x", text, &back);
  EXPECT_TRUE(std::isnan(back.confidence()));
  EXPECT_TRUE(std::isnan(back.grid().rounds(0).candidates(0).closed()));
}

TEST(DiagnosisCodec, AVersionOneFileOfNoKindOrBothIsRefused) {
  const std::string records = ReadTextFile(Data("records-none.json"));
  const std::string bench = ReadTextFile(Data("bench.json"));
  EXPECT_NE(ErrorOf(Replaced(bench, "{", "{", "{\n \"records\": \"set\",")).find("both"),
            std::string::npos);
  EXPECT_NE(ErrorOf("{\"verdict\": \"x\"}").find("x/diagnosis.json: no format_version"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[1]").find("x/diagnosis.json: not a JSON object"), std::string::npos);
  EXPECT_NE(ErrorOf(ValueReplaced(records, "\"records\": ", "null"))
                .find("x/diagnosis.json: records: not a string (the record set)"),
            std::string::npos);
  // version 2's file of another version
  const std::string two = WriteDiagnosisFile(RecordsMessage());
  const std::string three = ErrorOf(ValueReplaced(two, "\"format_version\": ", "3"));
  EXPECT_NE(three.find("x/diagnosis.json: format_version 3: this piezoid reads diagnosis.json "
                       "format_version 2 and 1"),
            std::string::npos)
      << three;
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
      ErrorOf(Replaced(records, "\"named\"", "\"named\": null", "\"named\": 2"));
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
  // version 2: "named" a list of strings, the round's a string
  const std::string two = WriteDiagnosisFile(BenchMessage());
  const std::string v2 =
      ErrorOf(Replaced(two, "\"grid\"", "\"named\": \"creep\"", "\"named\": [\"creep\"]"));
  EXPECT_NE(v2.find("x/diagnosis.json: grid.rounds[0].named"), std::string::npos) << v2;
}

TEST(DiagnosisCodec, TheWriterRefusesAMessageWithoutItsRecordSet) {
  proto::Diagnosis none;
  EXPECT_THROW(WriteDiagnosisFile(none), std::logic_error);
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
