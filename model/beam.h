// Finite-element model of the bimorph cantilever (docs: spec "bimorph-fin model", section 1).
//
// Euler–Bernoulli beam clamped at x = 0 with an active segment (fiberglass core + two MFC layers)
// and a passive tip (core only), Hermite cubic elements, nodal DOFs (w, φ). After clamping node 1
// the reduced coordinates are q = [w_2, φ_2, …, w_{n+1}, φ_{n+1}] (2n DOFs).
#pragma once

#include <Eigen/Dense>

#include "model/status.h"

namespace pz::model {

/// Geometry and materials of the bimorph beam. SI units.
struct BeamGeometry {
  double active_length_m = 0.085;       ///< L_p [m], > 0
  double tip_length_m = 0.017;          ///< L_e [m], ≥ 0 (0 with n_tip = 0)
  double core_width_m = 0.075;          ///< b_f [m], > 0
  double core_thickness_m = 0.5e-3;     ///< h_f [m], > 0
  double mfc_width_m = 0.056;           ///< b_p [m], > 0
  double mfc_thickness_m = 0.3e-3;      ///< h_p [m], > 0
  double core_modulus_pa = 20e9;        ///< E_f [Pa], > 0
  double core_density = 1850.0;         ///< ρ_f [kg/m³], > 0
  double mfc_modulus_pa = 30.3e9;       ///< E_p [Pa], > 0
  double mfc_density = 5440.0;          ///< ρ_p [kg/m³], > 0
  double d33_m_per_v = 4.275e-10;       ///< strain constant d33 [m/V], > 0
  double electrode_spacing_m = 0.5e-3;  ///< e_s [m], > 0
  int n_active = 5;                     ///< elements over the active segment, 1 … 200
  int n_tip = 1;                        ///< elements over the passive tip, 0 … 200

  Status Validate() const;

  double EiActive() const;                                               ///< [N m²]
  double EiTip() const;                                                  ///< [N m²]
  double RhoAActive() const;                                             ///< [kg/m]
  double RhoATip() const;                                                ///< [kg/m]
  double PiezoMomentPerVolt() const;                                     ///< c_p [N m / V]
  double TotalLength() const { return active_length_m + tip_length_m; }  ///< L [m]
  int num_elements() const { return n_active + n_tip; }
  int num_dofs() const { return 2 * num_elements(); }
  /// 0-based index of the tip deflection w_{n+1} in q (the spec's DOF 2n−1, counted from 1).
  int tip_dof() const { return 2 * num_elements() - 2; }
  /// 0-based index of φ at the last active node (the spec's DOF 2·n_active, counted from 1).
  int moment_dof() const { return 2 * n_active - 1; }
};

/// Assembled, clamped FE matrices.
struct FeModel {
  Eigen::MatrixXd K;      ///< stiffness [N/m, N, N m]
  Eigen::MatrixXd M;      ///< mass
  Eigen::VectorXd b_u;    ///< input vector: c_p on the moment DOF [N m / V]
  Eigen::VectorXd e_tip;  ///< unit vector of the tip deflection DOF
};

/// Mass-normalised modal basis: K Φ = M Φ diag(ω²), Φᵀ M Φ = I; ω ascending.
struct ModalBasis {
  Eigen::VectorXd omega;   ///< natural circular frequencies [rad/s]
  Eigen::MatrixXd phi;     ///< mode shapes (columns), mass-normalised
  Eigen::VectorXd gain_u;  ///< Φᵀ b_u: modal input gain per volt
  Eigen::VectorXd gain_z;  ///< Φᵀ e_tip: modal gain of the tip force z
  Eigen::VectorXd tip;     ///< row of Φ at the tip DOF: w_tip = Σ_i tip_i η_i
};

/// Assembles the clamped K, M, b_u, e_tip. Throws InputError on an invalid geometry.
FeModel AssembleBeam(const BeamGeometry& g);

/// Solves the generalised eigenproblem of an assembled beam.
ModalBasis ComputeModalBasis(const FeModel& fe);

}  // namespace pz::model
