// Analytic checks of the FE beam: section properties and natural frequencies printed in the spec,
// static tip deflection against the closed form, convergence to Euler–Bernoulli frequencies.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "model/beam.h"

namespace pz::model {
namespace {

TEST(BeamSectionProperties, MatchSpecValues) {
  BeamGeometry g;
  EXPECT_NEAR(g.EiActive(), 0.186153, 5e-7);
  EXPECT_NEAR(g.EiTip(), 0.015625, 5e-7);
  EXPECT_NEAR(g.RhoAActive(), 0.252159, 5e-7);
  EXPECT_NEAR(g.RhoATip(), 0.069375, 5e-7);
  EXPECT_NEAR(g.PiezoMomentPerVolt(), 3.48183e-4, 5e-10);
  EXPECT_EQ(g.tip_dof(), 10);
  EXPECT_EQ(g.moment_dof(), 9);
}

TEST(BeamModes, DefaultMeshFrequenciesMatchSpec) {
  const FeModel fe = AssembleBeam(BeamGeometry{});
  const ModalBasis mb = ComputeModalBasis(fe);
  ASSERT_EQ(mb.omega.size(), 12);
  const double expected_hz[] = {58.57, 343.09, 815.69, 1359.57};
  for (int i = 0; i < 4; ++i)
    EXPECT_NEAR(mb.omega(i) / (2 * std::numbers::pi), expected_hz[i], 0.006) << i;
  // Mass normalisation: Φᵀ M Φ = I, Φᵀ K Φ = diag(ω²).
  const Eigen::MatrixXd mm = mb.phi.transpose() * fe.M * mb.phi;
  EXPECT_LT((mm - Eigen::MatrixXd::Identity(12, 12)).norm(), 1e-9);
  const Eigen::MatrixXd kk = mb.phi.transpose() * fe.K * mb.phi;
  EXPECT_LT((kk - Eigen::MatrixXd(mb.omega.array().square().matrix().asDiagonal())).norm() /
                mb.omega.array().square().maxCoeff(),
            1e-9);
}

// Static tip deflection under a tip force P on the two-segment cantilever (closed form by
// superposition: tip segment cantilevered on the deflected, rotated end of the active segment).
TEST(BeamStatic, TipForceDeflectionMatchesClosedForm) {
  BeamGeometry g;
  const FeModel fe = AssembleBeam(g);
  const double P = 1.0;
  const Eigen::VectorXd q = fe.K.ldlt().solve(P * fe.e_tip);
  const double a = g.active_length_m, b = g.tip_length_m, ei1 = g.EiActive(), ei2 = g.EiTip();
  // Active segment carries shear P and moment P (b + a − x) at x: end deflection and slope.
  const double w_a = P * a * a * a / (3 * ei1) + P * b * a * a / (2 * ei1);
  const double th_a = P * a * a / (2 * ei1) + P * b * a / ei1;
  const double w_tip = w_a + th_a * b + P * b * b * b / (3 * ei2);
  EXPECT_NEAR(q(g.tip_dof()), w_tip, 1e-12 * std::abs(w_tip) + 1e-15);
}

// Piezo end moment: static tip deflection under the moment c_p·u at the end of the active segment.
TEST(BeamStatic, PiezoMomentDeflectionMatchesClosedForm) {
  BeamGeometry g;
  const FeModel fe = AssembleBeam(g);
  const double u = 100.0;
  const Eigen::VectorXd q = fe.K.ldlt().solve(fe.b_u * u);
  const double m0 = g.PiezoMomentPerVolt() * u, a = g.active_length_m;
  const double w_tip = m0 * a * a / (2 * g.EiActive()) + m0 * a / g.EiActive() * g.tip_length_m;
  EXPECT_NEAR(q(g.tip_dof()), w_tip, 1e-12 * std::abs(w_tip));
}

// A uniform cantilever: FE frequencies converge from above to the Euler–Bernoulli values
// ω_i = (β_i L)² sqrt(EI / (ρA L⁴)), with the error decreasing as the mesh is refined.
TEST(BeamModes, UniformCantileverConvergesToEulerBernoulli) {
  const double betaL[] = {1.8751040687, 4.6940911330, 7.8547574382, 10.995540734};
  double prev_err[4] = {1e9, 1e9, 1e9, 1e9};
  for (int n : {4, 8, 16, 32}) {
    BeamGeometry g;
    g.tip_length_m = 0;
    g.n_tip = 0;
    g.n_active = n;
    const ModalBasis mb = ComputeModalBasis(AssembleBeam(g));
    const double L = g.active_length_m;
    for (int i = 0; i < 4; ++i) {
      const double exact =
          betaL[i] * betaL[i] * std::sqrt(g.EiActive() / (g.RhoAActive() * std::pow(L, 4)));
      const double err = (mb.omega(i) - exact) / exact;
      EXPECT_GE(err, -1e-10) << "FE (consistent mass) must bound from above, mode " << i << " n "
                             << n;
      // Hermite cubic elements converge as h⁴ in frequency: halving h divides the error by ~16.
      if (n >= 16) {
        EXPECT_GT(prev_err[i] / err, 12.0) << "mode " << i << " n " << n;
      }
      prev_err[i] = err;
    }
  }
  for (int i = 0; i < 4; ++i) EXPECT_LT(prev_err[i], 2e-5) << i;
}

TEST(BeamGeometryValidate, NamesTheField) {
  BeamGeometry g;
  g.n_active = 0;
  EXPECT_NE(g.Validate().message().find("n_active = 0"), std::string::npos);
  g = {};
  g.core_modulus_pa = -1;
  EXPECT_NE(g.Validate().message().find("core_modulus_pa"), std::string::npos);
  EXPECT_THROW(AssembleBeam(g), InputError);
}

}  // namespace
}  // namespace pz::model
