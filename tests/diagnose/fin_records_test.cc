// Issue 38, part 1: the bimorph-fin bench (io::CaseSet) fitted by the records engine — the
// bimorph-fin family in its bench form over io::RecordsFromCaseSet's records — gives the fin
// engine's fit (diagnose::FitGlobal) with the same DE and LM settings and seed: the same
// parameters and per-case PI, for the base model (differential evolution + Levenberg–Marquardt)
// and for a beam candidate (hinge-friction on CVODE, refined from the base fit at the fin's start
// magnitudes), on the nominal bench and on the hinge-friction bench. The budgets are small: what is
// compared is the arithmetic, not the optimum.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "diagnose/fin_fit.h"
#include "diagnose/problem.h"
#include "io/bench_data.h"
#include "io/fin_records.h"
#include "records/fit.h"

namespace pz::records {
namespace {

using model::EffectKind;

io::CaseSet Bench(const char* name) {
  return io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/" + name);
}

opt::DeOptions SmallDe() {
  opt::DeOptions d;
  d.population = 12;
  d.generations = 5;
  d.stall_generations = 0;
  d.seed = 7;
  return d;
}

opt::LmOptions SmallLm() {
  opt::LmOptions l;
  l.max_iterations = 6;
  l.threads = 2;
  return l;
}

constexpr int kBeamIterations = 2;
const std::vector<double> kFractions = {0.03, 0.15};

FitOptions RecordsOptions(std::vector<EffectKind> effects, int threads = 2) {
  FitOptions o;
  o.family = "bimorph-fin";
  o.family_options.bench_form = true;
  o.effects = std::move(effects);
  o.search.algorithm = opt::SearchAlgorithm::kDe;
  o.search.de = SmallDe();
  o.search.repetitions = 1;
  o.lm = SmallLm();
  o.uncertainty = false;
  o.threads = threads;
  o.beam.lm_iterations = kBeamIterations;
  o.beam.start_fractions = kFractions;
  return o;
}

// The fin engine's base fit (diagnose/fin_diagnose.cc FitStructure without a `from`).
diagnose::FitResult FinBase(const diagnose::DiagnosisModel& m) {
  diagnose::FitOptions fo;
  fo.threads = 2;
  fo.de = SmallDe();
  fo.lm = SmallLm();
  fo.uncertainty = false;
  return diagnose::FitGlobal(m, diagnose::ParameterLayout({}), fo);
}

// The fin engine's beam candidate (FitStructure with a beam effect): no search, a forward-
// difference polish from the base with the effect's magnitude at each start fraction.
diagnose::FitResult FinBeam(const diagnose::DiagnosisModel& m, const diagnose::FitResult& base,
                            EffectKind effect) {
  const diagnose::ParameterLayout from({}), layout({effect});
  const std::vector<double> x0 = layout.Extend(base.x, from);
  const int mag = diagnose::ParameterLayout::kBase + model::GetEffectInfo(effect).magnitude_param;
  diagnose::FitOptions fo;
  fo.threads = 2;
  fo.lm = SmallLm();
  fo.global_search = false;
  fo.lm.max_iterations = kBeamIterations;
  fo.lm.central = false;
  fo.uncertainty = false;
  const diagnose::ParamSpec& s = layout.specs()[static_cast<size_t>(mag)];
  const bool both = s.lower < 0 && s.upper > 0;
  for (size_t j = 0; j < kFractions.size(); ++j) {
    std::vector<double> x = x0;
    const double f = both ? kFractions[0] : kFractions[j];
    x[static_cast<size_t>(mag)] = both && j % 2 == 1 ? f * s.lower : f * s.upper;
    fo.starts.push_back(x);
  }
  return diagnose::FitGlobal(m, layout, fo);
}

// The two fits agree bit for bit: the same unit ↔ physical arithmetic, the same simulations and
// the same residuals (the bench form's cost is the fin's sum, Family::sums_errors), so the same
// search and the same polish. The training sums are added in another order (per sample, per case).
void ExpectSame(const diagnose::FitResult& fin, const FitResult& rec,
                const diagnose::ParameterLayout& layout, const io::RecordSet& set) {
  ASSERT_TRUE(fin.ok) << fin.message;
  ASSERT_EQ(rec.params.size(), fin.x.size());
  for (size_t i = 0; i < fin.x.size(); ++i)
    EXPECT_EQ(rec.params[i], fin.x[i]) << layout.specs()[i].name;
  ASSERT_EQ(rec.metrics.size(), fin.case_pi.size());
  double train = 0;
  for (size_t c = 0; c < fin.case_pi.size(); ++c) {
    EXPECT_EQ(rec.metrics[c].name, set.records[c].name);
    EXPECT_EQ(rec.metrics[c].sse, fin.case_pi[c]) << rec.metrics[c].name;
    if (set.records[c].role == model::CaseRole::kTrain) train += rec.metrics[c].sse;
  }
  EXPECT_NEAR(rec.train_sse, fin.train_pi, 1e-12 * fin.train_pi);
  EXPECT_EQ(train, fin.train_pi);
}

class FinRecordsTest : public ::testing::TestWithParam<const char*> {};

TEST_P(FinRecordsTest, BaseAndBeamCandidateFitAsTheFinEngine) {
  const io::CaseSet bench = Bench(GetParam());
  const io::RecordSet set = io::RecordsFromCaseSet(bench);
  const diagnose::DiagnosisModel m(std::make_shared<const model::BimorphPlant>(),
                                   diagnose::CasesFromCaseSet(bench));
  const diagnose::FitResult fin = FinBase(m);
  const FitResult rec = FitRecords(set, RecordsOptions({}));
  ExpectSame(fin, rec, diagnose::ParameterLayout({}), set);

  const EffectKind hinge = EffectKind::Named("hinge-friction");
  const diagnose::FitResult fin_beam = FinBeam(m, fin, hinge);
  FitOptions o = RecordsOptions({hinge});
  o.polish_from = diagnose::ParameterLayout({hinge}).Extend(fin.x, diagnose::ParameterLayout({}));
  const FitResult rec_beam = FitRecords(set, o);
  ExpectSame(fin_beam, rec_beam, diagnose::ParameterLayout({hinge}), set);
}

// A drive-effect candidate as the fin engine fits it (FitStructure without a beam): a search
// seeded with the base (its effect at zero) and the start magnitudes, the base polished besides.
TEST(FinRecords, ADriveEffectCandidateIsSearchedAsTheFinEngineSearchesIt) {
  const io::CaseSet bench = Bench("nominal");
  const io::RecordSet set = io::RecordsFromCaseSet(bench);
  const diagnose::DiagnosisModel m(std::make_shared<const model::BimorphPlant>(),
                                   diagnose::CasesFromCaseSet(bench));
  const diagnose::FitResult base = FinBase(m);
  const EffectKind lowpass = EffectKind::Named("driver-lowpass");
  const diagnose::ParameterLayout layout({lowpass});
  const std::vector<double> x0 = layout.Extend(base.x, diagnose::ParameterLayout({}));
  const size_t mag = diagnose::ParameterLayout::kBase;  // tau_s, its only parameter
  std::vector<std::vector<double>> seeds = {x0};
  for (double f : kFractions) {
    seeds.push_back(x0);
    seeds.back()[mag] = f * layout.specs()[mag].upper;
  }
  diagnose::FitOptions fo;
  fo.threads = 2;
  fo.de = SmallDe();
  fo.de.seed = 7 + 1000 * (static_cast<uint64_t>(model::FinIndex(lowpass)) + 1) + 17;
  fo.lm = SmallLm();
  fo.uncertainty = false;
  fo.seeds = seeds;
  fo.starts = {x0};
  const diagnose::FitResult fin = diagnose::FitGlobal(m, layout, fo);
  FitOptions o = RecordsOptions({lowpass});
  o.search.de.seed = fo.de.seed;
  o.seed_points = seeds;
  o.start_points = {x0};
  ExpectSame(fin, FitRecords(set, o), layout, set);
}

TEST(FinRecords, TheUncertaintyTableIsTheFinEngines) {
  const io::CaseSet bench = Bench("nominal");
  const diagnose::DiagnosisModel m(std::make_shared<const model::BimorphPlant>(),
                                   diagnose::CasesFromCaseSet(bench));
  diagnose::FitOptions fo;
  fo.threads = 2;
  fo.de = SmallDe();
  fo.lm = SmallLm();
  const diagnose::FitResult fin = diagnose::FitGlobal(m, diagnose::ParameterLayout({}), fo);
  FitOptions o = RecordsOptions({});
  o.uncertainty = true;  // its steps are lm.fd_step, the fin's 1e-3
  const FitResult rec = FitRecords(io::RecordsFromCaseSet(bench), o);
  ASSERT_TRUE(fin.ok);
  ASSERT_EQ(rec.uncertainty.params.size(), fin.params.size());
  for (size_t i = 0; i < fin.params.size(); ++i) {
    EXPECT_EQ(rec.uncertainty.params[i].name, fin.params[i].name);
    EXPECT_EQ(rec.uncertainty.params[i].std_error, fin.params[i].std_error) << i;
    EXPECT_EQ(rec.uncertainty.params[i].sensitivity, fin.params[i].sensitivity) << i;
    EXPECT_EQ(rec.uncertainty.params[i].identifiability, fin.params[i].identifiability) << i;
  }
  EXPECT_EQ(rec.uncertainty.residual_sigma, fin.residual_sigma);
  EXPECT_EQ(rec.uncertainty.singular_values, fin.singular_values);
}

TEST(FinRecords, TheBenchFormFitIsTheSameOnOneThreadAndOnTwo) {
  const io::RecordSet set = io::RecordsFromCaseSet(Bench("nominal"));
  const FitResult one = FitRecords(set, RecordsOptions({}, 1));
  const FitResult two = FitRecords(set, RecordsOptions({}, 2));
  ASSERT_EQ(one.params.size(), two.params.size());
  for (size_t i = 0; i < one.params.size(); ++i) EXPECT_EQ(one.params[i], two.params[i]) << i;
  EXPECT_EQ(one.train_sse, two.train_sse);
}

TEST(FinRecords, TheRecordsOfABenchKeepItsCasesAndTheirStatedSinusoid) {
  const io::CaseSet bench = Bench("nominal");
  const io::RecordSet set = io::RecordsFromCaseSet(bench);
  EXPECT_EQ(set.format, "bimorph-fin-bench");
  EXPECT_EQ(set.response_unit, "deg");
  ASSERT_EQ(set.records.size(), bench.cases.size());
  for (size_t c = 0; c < bench.cases.size(); ++c) {
    const io::BenchCase& bc = bench.cases[c];
    const io::Record& r = set.records[c];
    EXPECT_EQ(r.name, "case" + std::to_string(bc.number));
    EXPECT_EQ(r.role, bc.role);
    EXPECT_EQ(r.sinusoid.case_number, bc.number);
    EXPECT_EQ(r.sinusoid.amplitude_v, bc.amplitude_v);
    EXPECT_EQ(r.sinusoid.frequency_hz, bc.frequency_hz);
    EXPECT_EQ(r.sinusoid.sample_rate_hz, bc.sample_rate_hz);
    EXPECT_EQ(r.frequency_hz, bc.frequency_hz);
    EXPECT_EQ(r.y, bc.angle_deg);
    EXPECT_EQ(r.offset_mode, io::OffsetMode::kFixed);
    EXPECT_EQ(r.offset, 0.0);
    ASSERT_EQ(r.u.size(), bc.t.size());
    for (size_t k = 0; k < r.u.size(); ++k) EXPECT_EQ(r.u[k], bc.Drive().Value(bc.t[k])) << k;
    EXPECT_EQ(r.end_scored, r.size());
  }
}

TEST(FinRecords, RecordMapIsTheFinLayoutsArithmetic) {
  const io::RecordSet set = io::RecordsFromCaseSet(Bench("nominal"));
  const EffectKind creep = EffectKind::Named("creep"), hinge = EffectKind::Named("hinge-friction");
  FamilyOptions fo;
  fo.bench_form = true;
  const DataScale scale = MeasureScale(set.WithRole(model::CaseRole::kTrain));
  const RecordModel model(MakeFamily("bimorph-fin", scale, fo), {creep, hinge}, scale);
  const RecordMap map(model);
  const diagnose::ParameterLayout layout({creep, hinge});
  const diagnose::LayoutMap fin(layout);
  ASSERT_EQ(map.size(), fin.size());
  std::vector<double> u(static_cast<size_t>(map.size()));
  for (int trial = 0; trial < 50; ++trial) {
    for (size_t i = 0; i < u.size(); ++i)
      u[i] = std::fmod(0.37 * static_cast<double>(trial + 1) * static_cast<double>(i + 3), 1.0);
    const std::vector<double> x = map.ToPhysical(u);
    EXPECT_EQ(x, fin.ToPhysical(u));
    EXPECT_EQ(map.ToUnit(x), fin.ToUnit(x));
    for (int i = 0; i < map.size(); ++i) {
      EXPECT_EQ(map.name(i), fin.name(i));
      EXPECT_EQ(map.Scale(x, i), fin.Scale(x, i)) << i;
      double lo = 0, hi = 0, flo = 0, fhi = 0;
      map.Bounds(x, i, &lo, &hi);
      fin.Bounds(x, i, &flo, &fhi);
      EXPECT_EQ(lo, flo) << i;
      EXPECT_EQ(hi, fhi) << i;
    }
  }
}

TEST(FinRecords, TheBenchFormSaysWhatItCannotRun) {
  const io::RecordSet bench = io::RecordsFromCaseSet(Bench("nominal"));
  FitOptions o = RecordsOptions({});
  // A record without a stated sinusoid (read from its files, the drive as measured).
  io::RecordSet plain = bench;
  for (io::Record& r : plain.records) r.sinusoid = {};
  try {
    FitRecords(plain, o);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stated sinusoid"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("case1"), std::string::npos) << e.what();
  }
  // An effect the fin bench does not offer.
  o.effects = {EffectKind::Named("creep-spectrum")};
  try {
    FitRecords(bench, o);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("creep-spectrum"), std::string::npos) << e.what();
  }
  // The service's evaluation does not carry the bench form.
  o.effects = {};
  o.evaluator_factory = [](const RecordFitness&) -> std::unique_ptr<opt::BatchEvaluator> {
    return nullptr;
  };
  try {
    FitRecords(bench, o);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bench form"), std::string::npos) << e.what();
  }
  o.evaluator_factory = nullptr;
  // A beam effect is refined from a fit: its starts checked.
  o.effects = {EffectKind::Named("hinge-friction")};
  o.polish_from.assign(9, 0.0);
  o.beam.start_fractions = {1.5};
  try {
    FitRecords(bench, o);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("beam.start_fractions"), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Benches, FinRecordsTest, ::testing::Values("nominal", "hinge-friction"),
                         [](const auto& info) {
                           std::string s = info.param;
                           for (char& ch : s)
                             if (ch == '-') ch = '_';
                           return s;
                         });

}  // namespace
}  // namespace pz::records
