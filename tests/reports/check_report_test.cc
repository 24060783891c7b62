// The report of `piezoid diagnose-check` (reports/check_report.h), one writer for both forms of the
// check: check.json through its message (proto/diagnosis.proto DiagnosisCheck, io/proto_json.h)
// parses back with the confusion matrix, the trials and a non-finite share closed as null, and
// reads back into its message and prints back to the same bytes; a trial's line and the summary
// read as the form's text says (the share closed and wall time on a bench's line, not a record's;
// the trials' noun).
#include "reports/check_report.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "diagnosis.pb.h"
#include "io/proto_json.h"
#include "records/fin_effects.h"
#include "tests/testing/expect_error.h"

namespace pz::reports {
namespace {

using model::EffectKind;

// The fin bench's form: the fin library's effects.
diagnose::CheckSummary FinSummary() {
  std::vector<EffectKind> effects;
  for (const auto& e : records::FinEffects()) effects.push_back(e.kind);
  return diagnose::CheckSummary({}, effects);
}

TEST(CheckReport, CheckJsonHasTheConfusionMatrixAndTheTrials) {
  diagnose::CheckSummary s = FinSummary();
  diagnose::CheckTrial t;
  t.seed = 1000;
  t.verdict_kind = "none";
  t.description = "seed 1000: none";
  t.closed = NAN;
  s.Tally(t);
  std::ostringstream out;
  WriteCheckJson(out, s);
  PZ_EXPECT_HAS(out.str(), "\"closed\": null");  // the trial's share closed: not finite
  PZ_EXPECT_HAS(out.str(), "\"truth_description\": \"seed 1000: none\"");
  proto::DiagnosisCheck back;  // reads into its message and prints back to the same bytes
  io::ReadJsonMessage("check.json", out.str(), &back);
  EXPECT_EQ(io::PrintJson(back, "check.json"), out.str());
  const int effects = static_cast<int>(records::FinEffects().size());
  ASSERT_EQ(back.columns_size(), effects + 2);
  EXPECT_EQ(back.columns(0), "none");
  EXPECT_EQ(back.columns(effects + 1), "unexplained");
  EXPECT_EQ(static_cast<int>(back.confusion().size()), effects + 1);
  EXPECT_EQ(back.confusion().at("none").values(0).number_value(), 1);  // none → none
  EXPECT_EQ(back.clean(), 1);
  EXPECT_EQ(back.clean_alarms(), 0);
  ASSERT_EQ(back.trials_size(), 1);
  EXPECT_EQ(back.trials(0).seed(), 1000u);
  EXPECT_TRUE(back.trials(0).correct());
  EXPECT_EQ(back.trials(0).named(), "none");
}

TEST(CheckReport, TrialLinesAndTheSummaryReadAsTheFormSays) {
  diagnose::CheckTrial t;
  t.truth = EffectKind::Named("delay");
  t.description = "delay 0.01, sine";
  t.verdict_kind = "effect";
  t.named = "delay";
  t.confidence = 0.995;
  t.rms_ratio = 4.21;
  t.significant = true;
  t.closed = 0.87;
  t.wall_time_s = 12.4;
  t.correct = true;
  const diagnose::CheckText bench,
      rec{.noun = "records", .description_width = 42, .closed_per_trial = false};
  EXPECT_EQ(CheckTrialLine(rec, t, 1),
            "trial   2 right  delay 0.01, sine                           -> effect      delay  "
            "          ratio   4.21 conf 0.99");
  const std::string line = CheckTrialLine(bench, t, 1);
  EXPECT_EQ(line.substr(line.size() - 21), " closed    87% (12 s)");
  diagnose::CheckSummary s({.noun = "records"}, {EffectKind::Named("delay")});
  s.Tally(t);
  std::ostringstream out;
  PrintCheckSummary(out, s);
  PZ_EXPECT_HAS(out.str(), "columns: named; 1 records)");
  PZ_EXPECT_HAS(out.str(), "  delay             0           1           0");
  PZ_EXPECT_HAS(out.str(), "records with an effect and a significant gap: 1, right effect named");
}

}  // namespace
}  // namespace pz::reports
