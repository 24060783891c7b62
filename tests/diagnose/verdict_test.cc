// The one verdict of every diagnosis (diagnose/verdict.h): each verdict kind in its words with the
// numbers of the gap and the candidates; what only a protocol knows (a second effect, absorbed
// parameters, the next measurement, a closing note) where it belongs; and the words of a
// calibration check (a trial's line, the tally).
#include "diagnose/verdict.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

// s0 = 400, s_floor = 100 over 100 withheld samples: withheld RMS 2, floor 1, ratio 2.
diagnose::Gap TestGap(double s0 = 400) {
  return diagnose::MeasureGap(s0, 300, 100, 1.0, 1.0, 100, 200, {});
}

diagnose::VerdictText Text() {
  diagnose::VerdictText t;
  t.model = "the base model";
  t.unit = "µm";
  t.floor_source = "rest";
  return t;
}

diagnose::CandidateScore Scored(const diagnose::Gap& g, double s_withheld) {
  diagnose::CandidateScore c;
  diagnose::ScoreCandidate(g, s_withheld, 180, 1, 0.9, {}, c);
  return c;
}

TEST(VerdictTest, ANamedEffectClosesItsShareOfTheGap) {
  const diagnose::Gap g = TestGap();
  diagnose::CandidateScore a = Scored(g, 121), b = Scored(g, 390);
  const std::vector<diagnose::VerdictCandidate> ranked = {{"delay", &a}, {"creep", &b}};
  const diagnose::Naming n{.named = 0, .runner_up = -1, .z_runner_up = 0, .confidence = 0.987};
  EXPECT_EQ(diagnose::ComposeVerdict(g, ranked, n, {}, Text()),
            "The gap is delay (confidence 98.7 %): adding it closes 93 % of the excess withheld "
            "gap; withheld RMS 2 → "
            "1.1 µm against a noise floor of 1 µm (rest).");
  diagnose::VerdictText two = Text();
  two.second = "creep";
  two.second_confidence = 0.9;
  two.s_final = 100;
  two.closing = "Excitation gap: none.";
  EXPECT_EQ(diagnose::ComposeVerdict(g, ranked, n, {}, two),
            "The gap is delay (confidence 98.7 %), with a second effect: creep (confidence 90 %): "
            "adding them closes "
            "100 % of the excess withheld gap; withheld RMS 2 → 1 µm against a noise floor of 1 µm "
            "(rest). "
            "Excitation gap: none.");
}

TEST(VerdictTest, ATieSaysWhatWouldSeparateIt) {
  const diagnose::Gap g = TestGap();
  diagnose::CandidateScore a = Scored(g, 121), b = Scored(g, 144);
  const std::vector<diagnose::VerdictCandidate> ranked = {{"driver-lowpass", &a}, {"delay", &b}};
  diagnose::VerdictText t = Text();
  t.next = "a square wave";
  const std::string v = diagnose::ComposeVerdict(
      g, ranked, {.named = 0, .runner_up = 1, .z_runner_up = 1.234, .confidence = 0.6}, {}, t);
  EXPECT_EQ(v,
            "The data cannot separate driver-lowpass from delay: both bring the withheld gap to "
            "the noise floor (1.1 × "
            "and 1.2 ×, at most 1.25; they close 93 % and 85.3 %) and the paired block test does "
            "not separate them "
            "(z = 1.2 < 2); confidence in driver-lowpass 60 %. Next measurement: a square wave.");
  t.second = "creep";
  t.second_confidence = 0.75;
  t.s_final = 110.25;
  PZ_EXPECT_HAS(
      ComposeVerdict(g, ranked,
                     {.named = 0, .runner_up = 1, .z_runner_up = 1.234, .confidence = 0.6}, {}, t),
      "A second effect on top of driver-lowpass: creep (confidence 75 %); the two close 96.6 % of "
      "the excess "
      "withheld gap; withheld RMS 2 → 1.05 µm. Next measurement");
}

TEST(VerdictTest, NoGapNamesTheBestCandidateAndWhatAbsorbsIt) {
  const diagnose::Gap g = TestGap(110);
  diagnose::CandidateScore a = Scored(g, 90), b = Scored(g, 112);
  const std::vector<diagnose::VerdictCandidate> ranked = {{"creep", &a}, {"drift", &b}};
  diagnose::VerdictText t = Text();
  t.floor = 1.0;
  t.absorbed = {"alpha (1 without it, 2 with it)", "beta (3 without it, 4 with it)"};
  EXPECT_EQ(diagnose::ComposeVerdict(g, ranked, {}, {}, t),
            "No significant gap: the withheld RMS error of the base model is 1.05 × the noise "
            "floor (1 µm, from rest), "
            "at most 1.25. The best candidate, creep, would lower it to 0.949 µm, within the floor "
            "band; what it would "
            "explain is absorbed by the base model's alpha (1 without it, 2 with it), beta (3 "
            "without it, 4 with it).");
  a.score = -1;  // nothing scores above 0: nothing more to say
  EXPECT_EQ(diagnose::ComposeVerdict(g, ranked, {}, {}, Text()),
            "No significant gap: the withheld RMS error of the base model is 1.05 × the noise "
            "floor (1 µm, from rest), "
            "at most 1.25.");
}

TEST(VerdictTest, AnUnexplainedGapSaysWhyTheBestCandidateFails) {
  const diagnose::Gap g = TestGap();
  diagnose::CandidateScore a = Scored(g, 300);
  const std::vector<diagnose::VerdictCandidate> ranked = {{"creep", &a}};
  ASSERT_FALSE(a.qualifies);
  EXPECT_EQ(diagnose::ComposeVerdict(g, ranked, {}, {}, Text()),
            "A significant gap (withheld RMS 2 µm = 2 × the noise floor of 1 µm, from rest) that "
            "no candidate explains "
            "by the rules. Best candidate: creep (closes 33 % of the gap (< 50 %)).");
}

TEST(VerdictTest, ACheckSpeaksOnceForEveryDataShape) {
  diagnose::TrialVerdict v;
  v.verdict_kind = "effect";
  v.named = "delay";
  v.confidence = 0.987;
  v.rms_ratio = 2.346;
  EXPECT_EQ(diagnose::TrialLine(3, "right", "delay 0.01, sine", 20, v),
            "trial   3 right  delay 0.01, sine     -> effect      delay            ratio   2.35 "
            "conf 0.99");
  EXPECT_EQ(
      diagnose::TrialLine(12, "", "plant", 0, v, " (in truth)", "; said"),
      "trial  12 plant -> effect      delay            (in truth) ratio   2.35 conf 0.99; said");
  diagnose::CalibrationTally t;
  t.Add(false, true, "effect", true, 0.995);
  t.Add(true, false, "none", false, 0);
  EXPECT_EQ(diagnose::TallyText(t, "records"),
            "records with an effect and a significant gap: 1, right effect named in 1 (100 %); "
            "verdicts 'cannot "
            "separate': 0\nclean records: 1, false alarms 0 (0 %)\ncalibration of the stated "
            "confidence (1 records "
            "with a named effect):\n  confidence 0.99 – 1.00:   1 records, mean stated  99.5 %, "
            "right 100.0 %\n");
}

}  // namespace
}  // namespace pz::records
