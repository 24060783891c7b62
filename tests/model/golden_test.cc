// Golden vectors of the bimorph-fin model (tests/data/golden: README.md says how they were made,
// and that an implementation must reproduce every file to 1e-5 deg in theta_linear_deg and
// angle_deg), on both solver paths through model::Simulate. Then the fast path's own reference
// problems: its sampled-signal branch against the goldens, the reusable ModalSimulator (workspace
// cache, threads, errors), and the modal discretisation against an augmented matrix exponential in
// every regime.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/property_tree/json_parser.hpp>
#include <boost/property_tree/ptree.hpp>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "model/bimorph.h"
#include "model/modal_discretise.h"
#include "model/modal_simulator.h"
#include "model/modal_solver.h"
#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

constexpr double kGoldenTolDeg = 1e-5;  // README.md: max abs error in both angle columns

const std::string kGoldenDir = std::string(PIEZOID_TEST_DATA_DIR) + "/golden";

const std::vector<std::string> kGoldenFiles = {"case1",   "case2",   "case3",  "case4", "case5",
                                               "case6",   "case7",   "case8",  "case9", "random1",
                                               "random2", "random3", "random4"};

struct GoldenCase {
  std::string name;
  Sinusoid drive;
  BimorphParams params;
  std::vector<double> t, u, theta, angle;  // the file's columns
};

GoldenCase LoadGolden(const std::string& name) {
  GoldenCase g;
  g.name = name;
  boost::property_tree::ptree index;
  boost::property_tree::read_json(kGoldenDir + "/index.json", index);
  bool found = false;
  for (const auto& [key, entry] : index) {
    if (entry.get<std::string>("name") != name) continue;
    found = true;
    g.drive =
        Sinusoid{entry.get<double>("amplitude_V"), entry.get<double>("frequency_Hz"), 3.0, 100.0};
    const auto& p = entry.get_child("params");
    g.params.mu = p.get<double>("mu");
    g.params.delta = p.get<double>("delta");
    g.params.alpha = p.get<double>("alpha");
    g.params.beta = p.get<double>("beta");
    g.params.gamma = p.get<double>("gamma");
    g.params.a1 = p.get<double>("a1");
    g.params.a2 = p.get<double>("a2");
    g.params.b1 = p.get<double>("b1");
    g.params.b2 = p.get<double>("b2");
  }
  EXPECT_TRUE(found) << name << " is not in index.json";
  std::ifstream in(kGoldenDir + "/" + name + ".csv");
  EXPECT_TRUE(in.good()) << "cannot open " << name << ".csv";
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t_s,voltage_V,theta_linear_deg,angle_deg");
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream row(line);
    double t, u, th, an;
    row >> t >> u >> th >> an;
    EXPECT_FALSE(row.fail()) << name << ": bad row '" << line << "'";
    g.t.push_back(t);
    g.u.push_back(u);
    g.theta.push_back(th);
    g.angle.push_back(an);
  }
  return g;
}

const BimorphPlant& DefaultPlant() {
  static const BimorphPlant plant;
  return plant;
}

struct MaxErrors {
  double theta = 0, angle = 0;
  size_t theta_at = 0, angle_at = 0;
};

MaxErrors Compare(const GoldenCase& g, const std::vector<double>& theta,
                  const std::vector<double>& angle) {
  MaxErrors e;
  for (size_t k = 0; k < g.theta.size(); ++k) {
    const double dt = std::abs(theta[k] - g.theta[k]), da = std::abs(angle[k] - g.angle[k]);
    if (!(dt <= e.theta)) e.theta = dt, e.theta_at = k;
    if (!(da <= e.angle)) e.angle = da, e.angle_at = k;
  }
  return e;
}

TEST(GoldenIndex, ListsExactlyTheThirteenFiles) {
  boost::property_tree::ptree index;
  boost::property_tree::read_json(kGoldenDir + "/index.json", index);
  std::vector<std::string> names;
  for (const auto& [key, entry] : index) names.push_back(entry.get<std::string>("name"));
  EXPECT_EQ(names, kGoldenFiles);
}

// ---- Both solvers, every file
// --------------------------------------------------------------------

class GoldenTest : public ::testing::TestWithParam<std::tuple<Solver, std::string>> {};

TEST_P(GoldenTest, ReproducesFileWithinTolerance) {
  const auto& [solver, name] = GetParam();
  const GoldenCase g = LoadGolden(name);
  SimulateOptions options;
  options.solver = solver;
  const BimorphTrace tr = Simulate(DefaultPlant(), g.params, g.drive, options);
  ASSERT_TRUE(tr.summary.ok()) << SolverName(solver) << " " << name << ": "
                               << tr.summary.BriefReport();
  ASSERT_EQ(tr.theta_deg.size(), g.theta.size());
  ASSERT_EQ(tr.angle_deg.size(), g.angle.size());
  for (size_t k = 0; k < g.t.size(); ++k) {
    ASSERT_NEAR(tr.t[k], g.t[k], 1e-12) << k;
    ASSERT_NEAR(tr.u[k], g.u[k], 1e-9 * g.drive.amplitude_v) << k;
  }
  const MaxErrors e = Compare(g, tr.theta_deg, tr.angle_deg);
  std::cout << "[golden] " << SolverName(solver) << " " << name << ": max |theta err| = " << e.theta
            << " deg (sample " << e.theta_at << "), max |angle err| = " << e.angle
            << " deg (sample " << e.angle_at << "); " << tr.summary.BriefReport() << "\n";
  RecordProperty("max_theta_err_deg", std::to_string(e.theta));
  RecordProperty("max_angle_err_deg", std::to_string(e.angle));
  EXPECT_LE(e.theta, kGoldenTolDeg) << "at sample " << e.theta_at;
  EXPECT_LE(e.angle, kGoldenTolDeg) << "at sample " << e.angle_at;
}

INSTANTIATE_TEST_SUITE_P(AllFiles, GoldenTest,
                         ::testing::Combine(::testing::Values(Solver::kModal, Solver::kCvode),
                                            ::testing::ValuesIn(kGoldenFiles)),
                         [](const ::testing::TestParamInfo<GoldenTest::ParamType>& info) {
                           return std::string(SolverName(std::get<0>(info.param))) + "_" +
                                  std::get<1>(info.param);
                         });

// ---- The fast path's own checks
// ------------------------------------------------------------------

// The sinusoid sampled `refine` times finer than its own grid, as a sampled signal.
SampledSignal FineSamples(const Sinusoid& drive, int refine) {
  SampledSignal s;
  const size_t n = static_cast<size_t>(drive.NumSamples() - 1) * refine + 1;
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / (drive.sample_rate_hz * refine);
    s.t.push_back(t);
    s.u.push_back(drive.Value(t));
  }
  return s;
}

// A sampled drive (u linear between samples) takes the general branch of the fast path: sampling
// the sinusoid at 10 kHz (linear-interpolation error (Ωh)²V/8 ≤ 4e-5 V) must land on the goldens' θ
// at their sample times. Files: stiff overdamped (case1), δ = 0 (case6), sharp loop (random3).
TEST(ModalSampledDrive, FinelySampledSinusoidMatchesGoldenTheta) {
  for (const std::string name : {"case1", "case6", "random3"}) {
    const GoldenCase g = LoadGolden(name);
    constexpr int kRefine = 100;
    const BimorphTrace tr = Simulate(DefaultPlant(), g.params, FineSamples(g.drive, kRefine));
    ASSERT_TRUE(tr.summary.ok()) << name << ": " << tr.summary.BriefReport();
    double worst = 0;
    for (size_t k = 0; k < g.t.size(); ++k)
      worst = std::max(worst, std::abs(tr.theta_deg[k * kRefine] - g.theta[k]));
    EXPECT_LE(worst, kGoldenTolDeg) << name;
  }
}

// Off the goldens' grid: reversals between samples (0.3 Hz), a fast drive (7 Hz, Ωh = 0.44) and a
// sharp loop that the sinusoid branch sub-steps (m > 1), against the same sinusoid sampled at 20
// kHz.
TEST(ModalSinusoidDrive, OffGridReversalsAndSubstepsMatchFineSampledDrive) {
  struct Case {
    Sinusoid drive;
    double beta, gamma;
  };
  const Case cases[] = {{{600, 0.3, 2, 100}, 6e-3, 4e-3},
                        {{400, 7.0, 2, 100}, 6e-3, 4e-3},
                        {{700, 1.3, 2, 100}, 0.05, 0.02}};
  for (const Case& c : cases) {
    BimorphParams p;
    p.beta = c.beta;
    p.gamma = c.gamma;
    p.a1 = p.a2 = 0.05;
    p.b1 = 20;
    p.b2 = -20;
    const BimorphTrace a = Simulate(DefaultPlant(), p, c.drive);
    ASSERT_TRUE(a.summary.ok()) << a.summary.BriefReport();
    constexpr int kRefine = 200;
    const BimorphTrace b = Simulate(DefaultPlant(), p, FineSamples(c.drive, kRefine));
    ASSERT_TRUE(b.summary.ok()) << b.summary.BriefReport();
    double worst_theta = 0, worst_z = 0;
    for (size_t k = 0; k < a.t.size(); ++k) {
      worst_theta = std::max(worst_theta, std::abs(a.theta_deg[k] - b.theta_deg[k * kRefine]));
      worst_z = std::max(worst_z, std::abs(a.z[k] - b.z[k * kRefine]));
    }
    // z depends on the values of u only, but the polyline's peaks between samples fall short of the
    // sinusoid's by up to V (Ωh)²/8 (2.4e-4 V at 7 Hz), which shifts z after each reversal.
    EXPECT_LT(worst_z, 2e-6) << Describe(c.drive);
    EXPECT_LT(worst_theta, 1e-6) << Describe(c.drive);
  }
}

// A coarse sampled drive with steep slopes is split into sub-steps (κ u̇ τ ≤ 1/2) and at the zero
// crossings of z; refining the same piecewise-linear input by inserting midpoints cannot change it.
TEST(ModalSampledDrive, InsertingSamplesOnTheSameLinesChangesNothing) {
  BimorphParams p;
  p.beta = 0.03;  // sharp loop: κ u̇ τ up to ~8 on the coarse grid
  p.gamma = 0.01;
  p.a1 = p.a2 = 0;
  p.b1 = 50;
  p.b2 = -50;
  SampledSignal coarse;
  const double us[] = {0, 300, 420, -200, -640, -100, 500, 500, 80, -700, 0};
  for (int k = 0; k < 11; ++k) {
    coarse.t.push_back(0.05 * k);
    coarse.u.push_back(us[k]);
  }
  SampledSignal fine;
  for (size_t k = 0; k + 1 < coarse.t.size(); ++k) {
    for (int q = 0; q < 8; ++q) {
      fine.t.push_back(coarse.t[k] + (coarse.t[k + 1] - coarse.t[k]) * q / 8.0);
      fine.u.push_back(coarse.u[k] + (coarse.u[k + 1] - coarse.u[k]) * q / 8.0);
    }
  }
  fine.t.push_back(coarse.t.back());
  fine.u.push_back(coarse.u.back());
  const BimorphTrace a = Simulate(DefaultPlant(), p, coarse), b = Simulate(DefaultPlant(), p, fine);
  ASSERT_TRUE(a.summary.ok()) << a.summary.BriefReport();
  ASSERT_TRUE(b.summary.ok()) << b.summary.BriefReport();
  for (size_t k = 0; k < coarse.t.size(); ++k) {
    EXPECT_NEAR(a.z[k], b.z[8 * k], 1e-12) << k;
    EXPECT_NEAR(a.theta_deg[k], b.theta_deg[8 * k], 1e-7) << k;
  }
}

// The sampled path is the C step kernel's step (model/kernels/fin_modal.h): its walk, the kernel's
// arithmetic four modes a vector; a piece cut at a zero crossing is discretised by DiscretiseBatch
// (a few ulps from the kernel's). On a grid the kernel's fixed step meets exactly (1/128 s) the
// angles are the records kernel's (pzk_fin_step), bit for bit on the samples without a cut piece —
// the code makes them so, one build, one libm; a one-rounding change of the mode loop fails it —
// and within 1e-12 on those with one (the two discretisations' few ulps, which another libm moves);
// on a drive with rests, jumps that sub-step (κ u̇ τ > 1/2), reversals and minor loops, for a
// light and a stiff damping and without hysteresis.
TEST(ModalSampledDrive, StepsAsTheKernelBitForBit) {
  const ModalSimulator sim(DefaultPlant());
  const int n = sim.num_modes();
  std::vector<double> w{1.0 / sim.length_m()};
  for (auto v : {sim.omega2(), sim.tip_gain_u(), sim.tip_gain_z()})
    w.insert(w.end(), v.begin(), v.end());
  SampledSignal drive;
  for (int k = 0; k < 640; ++k) {
    const double t = k / 128.0;
    double u = 500 * std::sin(2 * 3.141592653589793 * 0.7 * t) + 150 * std::sin(11.0 * t);
    if (k % 97 > 85) u = 120;                      // a rest
    if (k % 61 == 30) u = k % 2 ? 700.0 : -650.0;  // a jump
    drive.t.push_back(t);
    drive.u.push_back(u);
  }
  for (int c = 0; c < 3; ++c) {
    BimorphParams p;
    p.mu = 95;
    p.delta = c == 1 ? 0.3 : 0.0;
    p.alpha = c == 2 ? 0.0 : 2.5e-3;
    p.beta = 0.02;
    p.gamma = 0.01;
    p.a1 = 0.1;
    p.a2 = 0.15;
    p.b1 = 3.0;
    p.b2 = -2.5;
    std::vector<double> y(drive.t.size());
    ModalWorkspace ws;
    const SimulationSummary sum = sim.SimulateAngle(p, DriveSignal{drive}, y, ws);
    ASSERT_TRUE(sum.ok()) << sum.BriefReport();
    const double pk[11] = {p.mu, p.delta, p.alpha, p.beta, p.gamma, p.a1, p.a2, p.b1, -p.b2, 1, 0};
    pzk::pzk_block b{};
    b.kind = pzk::PZK_BIMORPH_FIN;
    b.n = n;
    b.dt = 1.0 / 128;
    b.p = pk;
    b.np = 11;
    b.w = w.data();
    b.nw = static_cast<int>(w.size());
    std::vector<double> cs(static_cast<size_t>(PZK_FIN_C * n)), ds(static_cast<size_t>(2 * n + 4));
    EXPECT_EQ(pzk::pzk_fin_init(&b, cs.data(), ds.data(), drive.u[0]), y[0]) << "case " << c;
    long substepped = 0, cut = 0;  // samples sub-stepped, pieces cut at a zero crossing of z
    for (size_t k = 1; k < drive.u.size(); ++k) {
      const double u0 = ds[2 * n], tau = b.dt;
      const int nsub = pzk::pzk_fin_substeps(1, p.beta + p.gamma, (drive.u[k] - u0) / tau, tau);
      substepped += nsub > 1;
      const long cut_before = cut;
      pzk::pzk_fin_sample(
          p.alpha, p.beta, p.gamma, u0, ds[2 * n + 1], drive.u[k], tau, nsub,
          [](void* ctx, double, int regular, pzk::pzk_fin_zdata, pzk::pzk_fin_zdata, double,
             double) { *static_cast<long*>(ctx) += regular == 0; },
          &cut);
      const double stepped = pzk::pzk_fin_step(&b, cs.data(), ds.data(), ds.data(), drive.u[k]);
      if (cut == cut_before) {  // one arithmetic on both sides: the same bits on any machine
        ASSERT_EQ(stepped, y[k]) << "case " << c << ", sample " << k;
      } else {  // a cut piece: DiscretiseBatch against the kernel's per-mode discretisation
        ASSERT_NEAR(stepped, y[k], 1e-12 * (1 + std::abs(y[k])))
            << "case " << c << ", sample " << k << " (a piece cut at a zero crossing)";
      }
    }
    EXPECT_GT(substepped, 10) << "the drive must sub-step";
    if (p.alpha != 0) {
      EXPECT_GT(cut, 10) << "z must cross zero inside samples";
    }
  }
}

// DiscretiseBatch (the sinusoid path's cut steps) gives the kernel's discretisation to a few ulps
// of each entry's scale (its e^x is ExpReduced, within 2 ulps of std::exp).
TEST(ModalDiscretisation, BatchAgreesWithTheKernel) {
  const ModalBasis& mb = DefaultPlant().modal();
  const int n = static_cast<int>(mb.omega.size());
  std::vector<modal::ModePoles> poles(static_cast<size_t>(n));
  std::vector<modal::ModeStep> batch(static_cast<size_t>(n));
  std::vector<double> scratch(16 * static_cast<size_t>(n));
  std::vector<int> idx(static_cast<size_t>(n));
  for (double delta : {0.0, 1e-4, 0.3})
    for (double tau : {1e-6, 1e-3, 0.01}) {
      for (int i = 0; i < n; ++i) {
        const double w2 = mb.omega(i) * mb.omega(i);
        poles[static_cast<size_t>(i)] = pzk::pzk_fin_make_poles(w2, 95.0 + delta * w2);
      }
      modal::DiscretiseBatch(n, poles.data(), tau, batch.data(), scratch.data(), idx.data());
      for (int i = 0; i < n; ++i) {
        modal::ModeStep k;
        pzk::pzk_fin_discretise(&poles[static_cast<size_t>(i)], tau, &k);
        const modal::ModeStep& b = batch[static_cast<size_t>(i)];
        const std::string where = "mode " + std::to_string(i) + " delta " + std::to_string(delta) +
                                  " tau " + std::to_string(tau);
        const double e = std::max({std::abs(k.e11), std::abs(k.e22), 1e-300});
        EXPECT_NEAR(b.e11, k.e11, 1e-14 * e) << where;
        EXPECT_NEAR(b.e22, k.e22, 1e-14 * e) << where;
        EXPECT_NEAR(b.e12, k.e12, 1e-14 * std::abs(k.e12) + 1e-300) << where;
        EXPECT_NEAR(b.e21, k.e21, 1e-14 * std::abs(k.e21) + 1e-300) << where;
        for (int j = 0; j <= modal::kMaxPhi; ++j)
          EXPECT_NEAR(b.d[j], k.d[j], 1e-14 * std::abs(k.d[j]) + 1e-300) << where << " D_" << j;
      }
    }
}

TEST(ModalSimulator, AngleOnlyRunEqualsFullTraceAndSurvivesWorkspaceReuse) {
  const ModalSimulator sim(DefaultPlant());
  const GoldenCase a = LoadGolden("case7"), b = LoadGolden("random3");
  ModalWorkspace ws;
  std::vector<double> ya(a.drive.NumSamples()), yb(b.drive.NumSamples()), ya2(a.drive.NumSamples());
  ASSERT_TRUE(sim.SimulateAngle(a.params, a.drive, ya, ws).ok());
  ASSERT_TRUE(sim.SimulateAngle(b.params, b.drive, yb, ws).ok());  // other μ, δ: cache replaced
  ASSERT_TRUE(sim.SimulateAngle(a.params, a.drive, ya2, ws).ok());
  EXPECT_EQ(ya, ya2);
  BimorphTrace tr;
  ModalWorkspace fresh;
  sim.Simulate(a.params, a.drive, tr, fresh);
  ASSERT_TRUE(tr.summary.ok());
  EXPECT_EQ(ya, tr.angle_deg);
  EXPECT_LE(Compare(a, tr.theta_deg, ya).angle, kGoldenTolDeg);
}

// One immutable plant and simulator, several threads with their own (thread_local) workspaces.
TEST(ModalSimulator, ThreadsSharingOneSimulatorGetSerialResults) {
  const ModalSimulator sim(DefaultPlant());
  std::vector<GoldenCase> cases;
  for (const std::string name : {"case1", "case6", "random1", "random3"})
    cases.push_back(LoadGolden(name));
  std::vector<std::vector<double>> serial(cases.size());
  for (size_t c = 0; c < cases.size(); ++c) {
    serial[c].resize(cases[c].drive.NumSamples());
    ASSERT_TRUE(sim.SimulateAngle(cases[c].params, cases[c].drive, serial[c]).ok());
  }
  std::vector<std::vector<std::vector<double>>> got(2,
                                                    std::vector<std::vector<double>>(cases.size()));
  auto work = [&](int id) {
    for (int rep = 0; rep < 20; ++rep) {
      for (size_t c = 0; c < cases.size(); ++c) {
        const size_t cc = (c + id) % cases.size();
        got[id][cc].assign(cases[cc].drive.NumSamples(), 0.0);
        if (!sim.SimulateAngle(cases[cc].params, cases[cc].drive, got[id][cc]).ok())
          got[id][cc].clear();
      }
    }
  };
  std::thread t0(work, 0), t1(work, 1);
  t0.join();
  t1.join();
  for (int id = 0; id < 2; ++id)
    for (size_t c = 0; c < cases.size(); ++c)
      EXPECT_EQ(got[id][c], serial[c]) << "thread " << id << " case " << c;
}

TEST(ModalSimulator, RejectsWrongOutputSizeAndBadInputWithoutThrowing) {
  const ModalSimulator sim(DefaultPlant());
  BimorphParams p;
  const Sinusoid s{375, 0.25, 3, 100};
  std::vector<double> y(10);
  SimulationSummary r = sim.SimulateAngle(p, s, y);
  EXPECT_EQ(r.status, SimStatus::kInvalidInput);
  PZ_EXPECT_HAS(r.message, "angle_deg.size()");
  y.resize(s.NumSamples());
  p.delta = -1;
  r = sim.SimulateAngle(p, s, y);
  EXPECT_EQ(r.status, SimStatus::kInvalidInput);
  PZ_EXPECT_HAS(r.message, "delta");
  p = BimorphParams{};
  r = sim.SimulateAngle(p, Sinusoid{375, 0.0, 3, 100}, y);
  EXPECT_EQ(r.status, SimStatus::kInvalidInput);
  PZ_EXPECT_HAS(r.message, "frequency_hz");
  p.gamma = 0.01;  // β − γ < 0
  r = sim.SimulateAngle(p, s, y);
  EXPECT_EQ(r.status, SimStatus::kUnboundedHysteresis);
}

TEST(ModalSimulator, FillsEveryTraceFieldConsistently) {
  const GoldenCase g = LoadGolden("case4");
  const BimorphTrace tr = SimulateModal(DefaultPlant(), g.params, g.drive);
  ASSERT_TRUE(tr.summary.ok()) << tr.summary.BriefReport();
  const size_t n = g.t.size();
  for (const auto* v : {&tr.t, &tr.u, &tr.z, &tr.w_tip, &tr.theta_deg, &tr.angle_deg})
    ASSERT_EQ(v->size(), n);
  EXPECT_GE(tr.summary.steps, static_cast<long>(n - 1));
  EXPECT_GT(tr.summary.wall_time_s, 0.0);
  std::vector<double> y(n);
  ApplyBacklash(g.params.backlash(), tr.theta_deg, y);
  for (size_t k = 0; k < n; ++k) {
    EXPECT_DOUBLE_EQ(tr.theta_deg[k], DefaultPlant().TipToDegrees(tr.w_tip[k])) << k;
    EXPECT_EQ(tr.angle_deg[k], y[k]) << k;
    EXPECT_LE(std::abs(tr.z[k]), g.params.alpha / (g.params.beta + g.params.gamma) * (1 + 1e-12))
        << k;
  }
}

// ---- Modal discretisation: against exp of the augmented matrix
// ------------------------------------
//
// In the scaled time σ = t/τ and state y = (η/τ, η̇) a step is exp of [[τA', B eᵀ], [0, N]] with
// τA' = [[0, 1], [−(ωτ)², −cτ]], B = [0, 1]ᵀ and the 6×6 shift N: its top-right block holds
// φ_{j+1}(τA') B = [D_{j+1}/τ, D_j/τ], and its top-left block e^{τA'} = [[E11, E12/τ], [τ E21,
// E22]]. All entries are O(1), so Eigen's Padé scaling-and-squaring is a fair reference while ‖τA‖
// is moderate — which still covers each regime of Discretise(): the series (|τλ| ≤ 1), separated
// roots (real and complex), and the near-critical midpoint form.
TEST(ModalDiscretisation, MatchesAugmentedMatrixExponentialInEveryRegime) {
  struct Case {
    double omega, c, tau;
  };
  std::vector<Case> cases;
  for (double omega : {0.0, 3.0, 40.0, 368.0})
    for (double tau : {1e-6, 1e-3, 4e-3, 0.01, 0.03})
      for (double c : {0.0, 0.2 * omega, 1.999999 * omega, 2 * omega, 2.000001 * omega, 2.3 * omega,
                       95.0 + 0.01 * omega * omega})
        if (tau * std::max(omega, c) < 40) cases.push_back({omega, c, tau});
  ASSERT_GT(cases.size(), 60u);
  for (const Case& cs : cases) {
    const double wt = cs.omega * cs.tau, ct = cs.c * cs.tau;
    Eigen::Matrix<double, 8, 8> m = Eigen::Matrix<double, 8, 8>::Zero();
    m(0, 1) = 1;
    m(1, 0) = -wt * wt;
    m(1, 1) = -ct;
    m(1, 2) = 1;
    for (int j = 2; j < 7; ++j) m(j, j + 1) = 1;
    const Eigen::Matrix<double, 8, 8> ex = m.exp();
    modal::ModeStep st;
    const modal::ModePoles poles = pzk::pzk_fin_make_poles(cs.omega * cs.omega, cs.c);
    pzk::pzk_fin_discretise(&poles, cs.tau, &st);
    const std::string where = "omega " + std::to_string(cs.omega) + ", c " + std::to_string(cs.c) +
                              ", tau " + std::to_string(cs.tau);
    const double tol = 1e-12 * (1 + wt + ct) * (1 + wt + ct);
    EXPECT_NEAR(st.e11, ex(0, 0), tol) << where;
    EXPECT_NEAR(st.e12 / cs.tau, ex(0, 1), tol) << where;
    EXPECT_NEAR(st.e21 * cs.tau, ex(1, 0), tol * (1 + wt * wt)) << where;
    EXPECT_NEAR(st.e22, ex(1, 1), tol) << where;
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(st.d[j] / cs.tau, ex(1, 2 + j), tol) << where << ", D_" << j;
      EXPECT_NEAR(st.d[j + 1] / cs.tau, ex(0, 2 + j), tol) << where << ", D_" << j + 1;
    }
  }
}

// In the stiff regime (δ = 0.3: λ_fast ≈ −6.5e9 1/s) the step is a first-order lag: E ≈ e^{τλ_slow}
// on the slow eigenvector, and the D_j stay finite and consistent with the φ-recurrence
// D_{j−1} = τ/j! − c τ D_j − ω² τ² D_{j+1}.
TEST(ModalDiscretisation, StiffModesStayFiniteAndConsistent) {
  const ModalBasis& mb = DefaultPlant().modal();
  const double fact[8] = {1, 1, 2, 6, 24, 120, 720, 5040};
  for (double delta : {0.0, 0.3})
    for (Eigen::Index i = 0; i < mb.omega.size(); ++i)
      for (double tau : {1e-9, 1e-5, 0.01}) {
        const double w2 = mb.omega(i) * mb.omega(i), c = 95.0 + delta * w2;
        modal::ModeStep st;
        const modal::ModePoles poles = pzk::pzk_fin_make_poles(w2, c);
        pzk::pzk_fin_discretise(&poles, tau, &st);
        for (double v : {st.e11, st.e12, st.e21, st.e22}) ASSERT_TRUE(std::isfinite(v));
        for (int j = 1; j < 6; ++j) {
          ASSERT_TRUE(std::isfinite(st.d[j]));
          const double rhs = tau / fact[j] - c * tau * st.d[j] - w2 * tau * tau * st.d[j + 1];
          const double scale =
              tau / fact[j] + std::abs(c * tau * st.d[j]) + std::abs(w2 * tau * tau * st.d[j + 1]);
          EXPECT_NEAR(st.d[j - 1], rhs, 1e-12 * scale)
              << "mode " << i << " delta " << delta << " tau " << tau;
        }
        // |eigenvalues of E| ≤ 1 (no growth): trace and determinant of a contraction-like 2×2.
        const double det = st.e11 * st.e22 - st.e12 * st.e21, tr = st.e11 + st.e22;
        EXPECT_LE(det, 1.0 + 1e-12);
        EXPECT_LE(std::abs(tr), 1.0 + det + 1e-12);
      }
}

}  // namespace
}  // namespace pz::model
