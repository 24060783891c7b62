// The families with return-point memory on records (records/preisach_family.h, issue 22):
// generalisation is the score. A known Preisach plant — a fine grid of relays written here, not
// with the family's code — is identified on a major-loop record and must predict a record whose
// amplitude ramps down to zero and back (nested minor loops) within the noise; the extrapolation
// guard flags a record beyond the training range and not one inside it; records that cannot
// support a Preisach grid get an error that says what is missing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "records/extrapolation.h"
#include "records/fit.h"
#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

using model::CaseRole;

constexpr double kFs = 1000, kRest = 0.5, kNoise = 0.05;

/// A Preisach plant of L × L relays over [0, 100] V (L = 400: its own staircase, steps of 0.25 V,
/// stays well below the noise) (α = (a + ½) h ≥ β = (b + ½) h), density
/// smooth in the width and leaning with the centre (an asymmetric loop), a reversible diagonal;
/// all relays off at rest at 0 V.
class RelayPlant {
 public:
  explicit RelayPlant(int levels = 400) : L_(levels), h_(100.0 / levels) {
    for (int a = 0; a < L_; ++a) {
      for (int b = 0; b <= a; ++b) {
        const double al = (a + 0.5) * h_, be = (b + 0.5) * h_, width = al - be,
                     centre = 0.5 * (al + be);
        double rho = std::exp(-width / 25) * (1 + 0.6 * (centre - 50) / 50);
        if (a == b) rho *= 6;
        alpha_.push_back(al);
        beta_.push_back(be);
        weight_.push_back(rho * 0.011 * h_ * h_);
      }
    }
  }
  std::vector<double> Run(const std::vector<double>& u) const {
    std::vector<char> on(alpha_.size(), 0);
    std::vector<double> y(u.size());
    for (size_t k = 0; k < u.size(); ++k) {
      double acc = 0;
      for (size_t q = 0; q < on.size(); ++q) {
        if (u[k] >= alpha_[q])
          on[q] = 1;
        else if (u[k] <= beta_[q])
          on[q] = 0;
        if (on[q]) acc += weight_[q];
      }
      y[k] = acc;
    }
    return y;
  }

 private:
  int L_;
  double h_;
  std::vector<double> alpha_, beta_, weight_;
};

/// A record from the drive after `kRest` s at 0 V, noise added, scored after the rest.
io::Record MakeRecord(const std::string& name, CaseRole role, const std::vector<double>& drive,
                      uint64_t seed, const RelayPlant& plant) {
  io::Record r;
  r.name = name;
  r.role = role;
  const size_t rest = static_cast<size_t>(kRest * kFs);
  r.u.assign(rest, drive.front());
  r.u.insert(r.u.end(), drive.begin(), drive.end());
  r.y = plant.Run(r.u);
  std::mt19937_64 g(seed);
  std::normal_distribution<double> n(0, kNoise);
  for (double& y : r.y) y += n(g) - 1.3;  // a sensor offset
  r.dt = 1 / kFs;
  for (size_t k = 0; k < r.u.size(); ++k) r.t.push_back(static_cast<double>(k) * r.dt);
  r.rest_samples = rest;
  r.first_scored = rest;
  r.end_scored = r.u.size();
  return r;
}

/// u = c − A a(t) cos 2π f t over `seconds`, a(t) from `envelope`.
template <class Env>
std::vector<double> Drive(double seconds, double centre, double amplitude, Env envelope) {
  std::vector<double> u;
  const size_t n = static_cast<size_t>(seconds * kFs);
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / kFs;
    u.push_back(centre - amplitude * envelope(t / seconds) * std::cos(2 * std::numbers::pi * t));
  }
  return u;
}

io::RecordSet MakeSet(const RelayPlant& plant) {
  io::RecordSet set;
  set.source = "relay plant";
  set.format = "synthetic";
  // Training: 4 periods of the major loop 0 … 100 V. Withheld: the amplitude ramps down to zero
  // and back over 10 s (nested minor loops about 50 V); and a larger drive (beyond the range).
  set.records.push_back(MakeRecord("major", CaseRole::kTrain,
                                   Drive(4, 50, 50, [](double) { return 1.0; }), 1, plant));
  set.records.push_back(MakeRecord("ramp", CaseRole::kValidate,
                                   Drive(10, 50, 50, [](double x) { return std::abs(1 - 2 * x); }),
                                   2, plant));
  set.records.push_back(MakeRecord("beyond", CaseRole::kTest,
                                   Drive(3, 60, 60, [](double) { return 1.0; }), 3, plant));
  return set;
}

const io::RecordSet& MajorLoopSet() {
  static const io::RecordSet set = [] {
    const RelayPlant plant;
    return MakeSet(plant);
  }();
  return set;
}

FitOptions Options(const std::string& family) {
  FitOptions o;
  o.family = family;
  o.threads = 2;
  return o;
}

TEST(PreisachFamily, IdentifiedOnAMajorLoopPredictsNestedMinorLoopsWithinTheNoise) {
  const io::RecordSet& set = MajorLoopSet();
  const FitResult f = FitRecords(set, Options("preisach"));
  ASSERT_EQ(f.metrics.size(), 3u);
  std::cout << "preisach: train " << f.metrics[0].rmse << ", minor loops " << f.metrics[1].rmse
            << ", beyond " << f.metrics[2].rmse << "; " << f.regularisation.Describe() << "\n";
  EXPECT_TRUE(f.regularisation.used);
  EXPECT_EQ(f.regularisation.cv_rmse.size(), f.regularisation.relatives.size());
  // The floor: the noise, and the plant's own 0.25 V staircase (about 0.025 in quadrature).
  EXPECT_LT(f.metrics[0].rmse, 1.3 * kNoise);
  EXPECT_LT(f.metrics[1].rmse, 1.3 * kNoise);
  for (double w : f.weights) EXPECT_GE(w, 0);
  // The same fit, bit for bit (deterministic whatever the threads).
  FitOptions one = Options("preisach");
  one.threads = 1;
  const FitResult g = FitRecords(set, one);
  EXPECT_EQ(g.weights, f.weights);
  EXPECT_EQ(g.metrics[1].rmse, f.metrics[1].rmse);
}

TEST(PreisachFamily, TheAsymmetricPiBeatsTheSymmetricOne) {
  const io::RecordSet& set = MajorLoopSet();
  const FitResult f = FitRecords(set, Options("asymmetric-pi"));
  std::cout << "asymmetric-pi: train " << f.metrics[0].rmse << ", minor loops " << f.metrics[1].rmse
            << "; " << f.regularisation.Describe() << "\n";
  // The plant's density leans with the relay centre (not a bend of the centre line alone): the
  // asymmetric PI cannot reach the noise, but halves the symmetric PI's error on both records.
  const FitResult pi = FitRecords(set, Options("prandtl-ishlinskii"));
  std::cout << "prandtl-ishlinskii: train " << pi.metrics[0].rmse << ", minor loops "
            << pi.metrics[1].rmse << "\n";
  EXPECT_LT(f.metrics[0].rmse, 0.6 * pi.metrics[0].rmse);
  EXPECT_LT(f.metrics[1].rmse, 0.6 * pi.metrics[1].rmse);
  for (double w : f.weights) EXPECT_GE(w, 0);
}

TEST(PreisachFamily, TheExtrapolationGuardFlagsADriveBeyondTheTrainingRangeOnly) {
  const io::RecordSet& set = MajorLoopSet();
  for (const std::string family : {"preisach", "asymmetric-pi"}) {
    const FitResult f = FitRecords(set, Options(family));
    const auto checks = CheckExtrapolation(set, f);
    ASSERT_EQ(checks.size(), 2u);
    EXPECT_EQ(checks[0].record, "ramp");
    EXPECT_FALSE(checks[0].flagged) << checks[0].Describe("V", "um");
    EXPECT_EQ(checks[0].drive_beyond, 0);
    EXPECT_TRUE(checks[1].flagged) << checks[1].Describe("V", "um");
    EXPECT_NEAR(checks[1].drive_beyond, 20, 0.01);
    PZ_EXPECT_HAS(checks[1].Describe("V", "um"), "beyond the training drive range");
  }
}

// Issue 37: a withheld record whose scored window starts inside its leading rest (the manifest's
// t_start_s before the drive moves) made CheckExtrapolation read its regressor rows at k − from
// with k < from, a size_t that wrapped (a segmentation fault). Every window of the set starts in
// the middle of the rest here; the rows before the first simulated sample are the rest row.
TEST(PreisachFamily, AWindowStartingInsideTheRestIsFittedAndChecked) {
  io::RecordSet set = MajorLoopSet();
  for (io::Record& r : set.records) r.first_scored = r.rest_samples / 2;
  for (const std::string family : {"preisach", "asymmetric-pi", "prandtl-ishlinskii"}) {
    const FitResult f = FitRecords(set, Options(family));
    ASSERT_EQ(f.metrics.size(), 3u);
    for (const auto& m : f.metrics) EXPECT_TRUE(std::isfinite(m.rmse)) << family;
    const auto checks = CheckExtrapolation(set, f);
    ASSERT_EQ(checks.size(), 2u);
    EXPECT_FALSE(checks[0].flagged) << family << ": " << checks[0].Describe("V", "um");
    EXPECT_TRUE(checks[1].flagged) << family << ": " << checks[1].Describe("V", "um");
    EXPECT_TRUE(std::isfinite(checks[1].term_rms)) << family;
  }
}

TEST(PreisachFamily, ErrorAgainstReversalDepthBinsEveryMonotonePiece) {
  io::Record r;
  for (double x : {0.0, 100.0, 55.0, 100.0, 0.0}) {  // swings 100, 45, 45, 100 % of the range
    const double from = r.u.empty() ? x : r.u.back();
    for (int k = 1; k <= 200 || r.u.empty(); ++k) {
      r.u.push_back(from + (x - from) * k / 200);
      if (r.u.size() == 1) break;
    }
  }
  r.y = r.u;
  r.first_scored = 0;
  r.end_scored = r.u.size();
  std::vector<double> yhat(r.y);
  for (size_t k = 0; k < yhat.size(); ++k) yhat[k] += r.u[k] < 50 ? 0.2 : 0.1;
  const auto bins = ErrorByReversalDepth(r, yhat, 100);
  ASSERT_EQ(bins.size(), 5u);
  EXPECT_EQ(bins[2].pieces, 2u);  // 100 → 55 → 100
  EXPECT_NEAR(bins[2].rmse, 0.1, 1e-12);
  EXPECT_EQ(bins[4].pieces, 2u);  // the full rise and fall
  EXPECT_GT(bins[4].rmse, 0.1);
  EXPECT_EQ(bins[0].samples + bins[1].samples + bins[3].samples, 0u);
  EXPECT_EQ(bins[2].samples + bins[4].samples, r.scored());
  PZ_EXPECT_HAS(DescribeDepthBins(bins), "swing 40–60 %: RMSE 0.1 (2 piece(s)");
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { ErrorByReversalDepth(r, yhat, 0); }),
                "range must be > 0");
}

TEST(PreisachFamily, ResidualTrendAveragesOnePeriodAndLeavesTheDrift) {
  // A residual of a 1 Hz loop error (0.5 µm) over a slow drift of 0.1 µm/s, sampled at 100 Hz, the
  // window starting at sample 50: averaged over one period the loop error is gone, the drift stays.
  io::Record r;
  r.dt = 0.01;
  for (int k = 0; k < 1050; ++k) {
    r.t.push_back(k * r.dt);
    r.u.push_back(0);
    r.y.push_back(0.5 * std::sin(2 * std::numbers::pi * k * r.dt) + 0.1 * k * r.dt);
  }
  r.first_scored = 50;
  r.end_scored = r.u.size();
  const std::vector<double> yhat(r.u.size(), 0.0);
  const std::vector<double> trend = ResidualTrend(r, yhat, 1.0);
  ASSERT_EQ(trend.size(), r.scored());
  for (size_t i = 50; i + 50 < trend.size();
       ++i) {  // full windows: 101 samples, one period and one sample
    const double t = (r.first_scored + i) * r.dt;
    ASSERT_NEAR(trend[i], 0.1 * t, 0.006) << "at " << t << " s";
  }
  EXPECT_NE(trend.front(), trend.back());  // truncated at the ends, still finite
  for (double x : trend) ASSERT_TRUE(std::isfinite(x));
  const std::vector<double> raw = ResidualTrend(r, yhat, 0);  // no window: the residual itself
  EXPECT_DOUBLE_EQ(raw[7], r.y[57]);
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { ResidualTrend(r, yhat, -1); }), "averaging window");
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { ResidualTrend(r, std::vector<double>(10), 1); }),
                "shorter");
  // A window far longer than the record (a drive whose dominant frequency is ~0: `piezoid fit`'s
  // averaging window is one period of it): the whole window's mean everywhere, not a cast of a
  // count beyond size_t (undefined; the sanitizer run stops on it).
  for (double w : {1e6, 1e300}) {
    const std::vector<double> whole = ResidualTrend(r, yhat, w);
    ASSERT_EQ(whole.size(), r.scored());
    double mean = 0;
    for (size_t k = r.first_scored; k < r.end_scored; ++k) mean += r.y[k];
    mean /= static_cast<double>(r.scored());
    EXPECT_NEAR(whole.front(), mean, 1e-12);
    EXPECT_NEAR(whole.back(), mean, 1e-12);
  }
}

TEST(PreisachFamily, RecordsThatCannotSupportTheGridSayWhatIsMissing) {
  const RelayPlant plant(20);
  io::RecordSet set;
  set.source = "bad";
  // A single rise: no reversals.
  std::vector<double> ramp;
  for (int k = 0; k < 2000; ++k) ramp.push_back(100.0 * k / 1999);
  set.records = {MakeRecord("rise", CaseRole::kTrain, ramp, 4, plant)};
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { FitRecords(set, Options("preisach")); }),
                "0 reversal(s)");
  // A square wave: up and down, but nothing between its two levels.
  std::vector<double> square;
  for (int k = 0; k < 4000; ++k) square.push_back((k / 500) % 2 ? 100.0 : 0.0);
  set.records = {MakeRecord("square", CaseRole::kTrain, square, 5, plant)};
  const std::string e = testing::InputErrorOf([&] { FitRecords(set, Options("preisach")); });
  PZ_EXPECT_HAS(e, "sample(s) between");
  PZ_EXPECT_HAS(e, "fewer levels");
  // Too many levels for the family.
  set.records = {MakeRecord("major", CaseRole::kTrain, Drive(2, 50, 50, [](double) { return 1.0; }),
                            6, plant)};
  FitOptions o = Options("preisach");
  o.family_options.pi_operators = 300;
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { FitRecords(set, o); }), "preisach.levels");
}

TEST(PreisachFamily, EffectsAreSearchedWithTheValidatedStrengthAndStayFinite) {
  const io::RecordSet& set = MajorLoopSet();
  const FitResult base = FitRecords(set, Options("preisach"));
  FitOptions o = Options("preisach");
  o.effects = {EffectKind::Named("delay")};
  o.search.repetitions = 1;
  o.search.pso.particles = 8;
  o.search.pso.iterations = 6;
  o.lm.max_iterations = 5;
  const FitResult f = FitRecords(set, o);
  ASSERT_EQ(f.params.size(), 1u);
  // The strength is chosen with the effect at its neutral value (the base fit's), then re-chosen
  // at the solution: the reported one is the validation's choice there.
  RecordFitness at_solution(*f.model, set.WithRole(CaseRole::kTrain));
  EXPECT_EQ(at_solution.validation().relative, base.regularisation.relative);
  at_solution.Revalidate(f.params);
  EXPECT_EQ(f.regularisation.relative, at_solution.validation().relative);
  for (const auto& m : f.metrics) EXPECT_TRUE(std::isfinite(m.rmse));
  EXPECT_LT(f.metrics[0].rmse, 1.02 * base.metrics[0].rmse);
}

}  // namespace
}  // namespace pz::records
