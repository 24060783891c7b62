// The records diagnosis checked on data whose effect is withheld (diagnose/check.h, issue 14): on
// random synthetic stack records it names the right effect, raises no alarm on clean records, and
// its stated confidence is calibrated — when it says ≥ 99 % it is right at least 90 % of the time.
#include "diagnose/check.h"

#include <gtest/gtest.h>

#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

TEST(RecordsCheck, NamesWithheldEffectsWithACalibratedConfidence) {
  RecordsCheckOptions o;
  o.family = "backlash-like";
  o.trials = 24;
  o.seed = 100;
  o.diagnose.fit.search.repetitions = 1;
  o.diagnose.fit.search.pso.particles = 20;
  o.diagnose.fit.search.pso.iterations = 60;
  o.diagnose.fit.lm.max_iterations = 30;
  const RecordsCheckSummary s = RunRecordsCheck(o);
  ASSERT_EQ(s.trials.size(), 24u);
  ASSERT_GT(s.effect_trials, 8);
  EXPECT_GE(s.effect_right, 0.8 * s.effect_trials);
  EXPECT_LE(s.clean_alarms, 1);
  for (const auto& b : s.Reliability()) {
    if (b.lo >= 0.99 && b.count > 0) {
      EXPECT_GE(b.frequency_right, 0.9) << b.count << " records stated ≥ 99 %";
    }
  }
  // Deterministic for a seed.
  o.trials = 3;
  const RecordsCheckSummary a = RunRecordsCheck(o), b = RunRecordsCheck(o);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(a.trials[i].named, b.trials[i].named);
    EXPECT_EQ(a.trials[i].confidence, b.trials[i].confidence);
  }
}

TEST(RecordsCheck, FamiliesWithoutANominalSetAreNamed) {
  RecordsCheckOptions o;
  o.family = "bimorph-fin";
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { RunRecordsCheck(o); }),
                "'bimorph-fin' has no nominal parameter set");
}

}  // namespace
}  // namespace pz::records
