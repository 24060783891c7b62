#include "model/beam.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace pz::model {
namespace {

Status Positive(const char* field, double v) {
  if (!(std::isfinite(v) && v > 0))
    return InvalidArgument(FieldError(field, v, "must be finite and > 0"));
  return Status::Ok();
}

}  // namespace

Status BeamGeometry::Validate() const {
  for (auto [name, v] :
       {std::pair{"active_length_m", active_length_m}, std::pair{"core_width_m", core_width_m},
        std::pair{"core_thickness_m", core_thickness_m}, std::pair{"mfc_width_m", mfc_width_m},
        std::pair{"mfc_thickness_m", mfc_thickness_m},
        std::pair{"core_modulus_pa", core_modulus_pa}, std::pair{"core_density", core_density},
        std::pair{"mfc_modulus_pa", mfc_modulus_pa}, std::pair{"mfc_density", mfc_density},
        std::pair{"d33_m_per_v", d33_m_per_v},
        std::pair{"electrode_spacing_m", electrode_spacing_m}}) {
    if (auto s = Positive(name, v); !s.ok()) return s;
  }
  if (!(std::isfinite(tip_length_m) && tip_length_m >= 0))
    return InvalidArgument(FieldError("tip_length_m", tip_length_m, "must be finite and >= 0"));
  if (n_active < 1 || n_active > 200)
    return InvalidArgument(FieldError("n_active", n_active, "must be in [1, 200]"));
  if (n_tip < 0 || n_tip > 200)
    return InvalidArgument(FieldError("n_tip", n_tip, "must be in [0, 200]"));
  if ((n_tip == 0) != (tip_length_m == 0))
    return InvalidArgument(FieldError("n_tip", n_tip, "must be 0 exactly when tip_length_m is 0"));
  return Status::Ok();
}

double BeamGeometry::EiActive() const {
  const double d = 0.5 * (core_thickness_m + mfc_thickness_m);
  const double hp = mfc_thickness_m;
  return core_modulus_pa * core_width_m * std::pow(core_thickness_m, 3) / 12.0 +
         2.0 * mfc_modulus_pa * mfc_width_m * (hp * hp * hp / 12.0 + hp * d * d);
}
double BeamGeometry::EiTip() const {
  return core_modulus_pa * core_width_m * std::pow(core_thickness_m, 3) / 12.0;
}
double BeamGeometry::RhoAActive() const {
  return core_density * core_width_m * core_thickness_m +
         2.0 * mfc_density * mfc_width_m * mfc_thickness_m;
}
double BeamGeometry::RhoATip() const { return core_density * core_width_m * core_thickness_m; }
double BeamGeometry::PiezoMomentPerVolt() const {
  return mfc_modulus_pa * (d33_m_per_v / electrode_spacing_m) * mfc_width_m * mfc_thickness_m *
         (core_thickness_m + mfc_thickness_m);
}

FeModel AssembleBeam(const BeamGeometry& g) {
  ThrowIfError(g.Validate());
  const int ne = g.num_elements();
  const int nfull = 2 * (ne + 1);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nfull, nfull);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(nfull, nfull);
  for (int e = 0; e < ne; ++e) {
    const bool active = e < g.n_active;
    const double l = active ? g.active_length_m / g.n_active : g.tip_length_m / g.n_tip;
    const double ei = active ? g.EiActive() : g.EiTip();
    const double ra = active ? g.RhoAActive() : g.RhoATip();
    Eigen::Matrix4d ke, me;
    ke << 12, 6 * l, -12, 6 * l,              //
        6 * l, 4 * l * l, -6 * l, 2 * l * l,  //
        -12, -6 * l, 12, -6 * l,              //
        6 * l, 2 * l * l, -6 * l, 4 * l * l;
    ke *= ei / (l * l * l);
    me << 156, 22 * l, 54, -13 * l,             //
        22 * l, 4 * l * l, 13 * l, -3 * l * l,  //
        54, 13 * l, 156, -22 * l,               //
        -13 * l, -3 * l * l, -22 * l, 4 * l * l;
    me *= ra * l / 420.0;
    K.block<4, 4>(2 * e, 2 * e) += ke;
    M.block<4, 4>(2 * e, 2 * e) += me;
  }
  const int n = nfull - 2;  // clamp node 1: drop w_1, φ_1
  FeModel fe;
  fe.K = K.bottomRightCorner(n, n);
  fe.M = M.bottomRightCorner(n, n);
  fe.b_u = Eigen::VectorXd::Zero(n);
  fe.b_u(g.moment_dof()) = g.PiezoMomentPerVolt();
  fe.e_tip = Eigen::VectorXd::Zero(n);
  fe.e_tip(g.tip_dof()) = 1.0;
  return fe;
}

ModalBasis ComputeModalBasis(const FeModel& fe) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(fe.K, fe.M);
  PZ_CHECK_MSG(es.info() == Eigen::Success, "generalised eigenproblem of the beam failed");
  ModalBasis mb;
  mb.omega = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  mb.phi = es.eigenvectors();  // normalised so that Φᵀ M Φ = I
  mb.gain_u = mb.phi.transpose() * fe.b_u;
  mb.gain_z = mb.phi.transpose() * fe.e_tip;
  const int tip = static_cast<int>(fe.e_tip.size()) - 2;
  mb.tip = mb.phi.row(tip).transpose();
  return mb;
}

}  // namespace pz::model
