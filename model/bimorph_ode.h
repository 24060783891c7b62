// The bimorph plant as a first-order ODE for the general (CVODE) path, with a seam for extensions.
//
// State vector (N = 2·(2n) + 1 + Σ extension states, n = number of elements, 2n = beam DOFs):
//
//   y = [ q (2n) | q̇ (2n) | z | x_1 | x_2 | … ]
//
//   q̇ = v
//   v̇ = M⁻¹ ( B_u u_e − e* z − C v − K q + Σ_i f_i )          C = μ M + δ K
//   ż = α u̇_e − β |u̇_e| z − γ u̇_e |z|
//   ẋ_i = g_i(t, y, u_e, u̇_e)
//
// M⁻¹ is applied through a Cholesky factorisation computed once per run (M⁻¹K, M⁻¹B_u, M⁻¹e*), so
// the right-hand side is a few small matrix-vector products. The Jacobian is analytic and dense
// (M⁻¹ of the banded consistent mass matrix is full, so a banded Jacobian would only be an
// approximation); the q̇ = v rows are declared kinematic, so each Newton system is solved by
// eliminating q and factoring only the (2n + 1 + extension states)-sized rest.
//
// Extension seam. A plant extension (amplifier low-pass on u, creep, Dahl friction at the tip,
// cubic stiffening, …) is a BimorphExtension: it owns x_i (num_states() ≥ 0 states appended to y),
// and
//   * may act as a drive stage (shapes_drive()): it replaces the drive (u, u̇) seen by the piezo
//   moment,
//     the Bouc–Wen element and the extensions after it — e.g. an amplifier returns (x, (u − x)/τ);
//   * adds a generalised force f_i (2n entries, [N] on w DOFs, [N m] on φ DOFs) to the beam — e.g.
//     −k₃ w_tip³ on the tip DOF, or −F on the tip DOF for a Dahl friction state F;
//   * gives the derivatives of its own states g_i;
//   * gives its Jacobian blocks ∂g_i/∂y, ∂f_i/∂y and, for a drive stage, ∂(u_e, u̇_e)/∂y, through
//     ExtensionJacobian; BimorphOde applies M⁻¹ and the chain rule through the drive.
// Extensions run in list order; none is needed for the spec's plant. Extensions are immutable and
// shared (const methods); per-run state lives in y. A plant with extensions is simulated by
// SimulateBimorphOde(plant, params, drive, options, {&ext1, &ext2, …}); SimulateCvode() is the same
// with none. Not yet in the seam: events of an extension (a switching state needing root functions
// and a discrete update); they would go through OdeSystem::num_roots()/Roots() and the stop hook,
// as the Dahl plant (model/dahl.h) does for its sign mode.
#pragma once

#include <Eigen/Dense>
#include <span>
#include <string>
#include <vector>

#include "model/bimorph.h"
#include "model/cvode.h"
#include "model/signal.h"

namespace pz::model {

/// The drive as the right-hand side sees it: u(t) [V] and u̇(t) [V/s]. A Sinusoid is analytic. A
/// SampledSignal is linear between samples, so u̇ jumps at every sample: the integrator stops at
/// each sample (a breakpoint) and SelectPieceAt(t_k) fixes the piece [t_k, t_{k+1}] the RHS uses,
/// so both ends of a step see the slope of the same piece.
class DriveInput {
 public:
  /// Keeps a reference: signal must outlive the DriveInput.
  explicit DriveInput(const DriveSignal& signal);
  double Value(double t) const;
  double Rate(double t) const;
  /// Times in (t_first, t_last) where the right-hand side is not smooth: every inner sample of a
  /// SampledSignal, and the zeros of u̇ of a Sinusoid (|u̇| has a kink there).
  std::vector<double> Breakpoints() const;
  /// True if the right-hand side depends on the selected piece (SampledSignal).
  bool piecewise() const { return sampled_ != nullptr; }
  /// Selects the piece that starts at or before t (t at a sample selects the piece that starts
  /// there). The first piece is selected on construction.
  void SelectPieceAt(double t);

 private:
  const Sinusoid* sinusoid_ = nullptr;
  const SampledSignal* sampled_ = nullptr;
  size_t piece_ = 0;
};

/// Read-only snapshot of the plant at one instant, handed to extensions.
struct BimorphPoint {
  double t = 0;                   ///< [s]
  std::span<const double> y;      ///< full state (layout above; BimorphOde index helpers)
  std::span<const double> q;      ///< beam DOFs [m, rad]
  std::span<const double> q_dot;  ///< beam DOF rates [m/s, rad/s]
  double z = 0;                   ///< Bouc–Wen force [N]
  std::span<const double> x;      ///< this extension's own states
  double u = 0;                   ///< drive after the previous drive stages [V]
  double u_dot = 0;               ///< its rate [V/s]
  /// In Jacobian calls only (empty in Rhs): ∂u/∂y and ∂u̇/∂y of the drive above (zero without drive
  /// stages), for the chain rule of an extension whose terms depend on the drive.
  std::span<const double> du_dy, du_dot_dy;
  int tip_dof = 0;  ///< index of w_tip in q
};

/// Where an extension writes its Jacobian blocks; columns are indices into the full state y.
class ExtensionJacobian {
 public:
  ExtensionJacobian(Eigen::Ref<Eigen::MatrixXd> force_rows, Eigen::Ref<Eigen::MatrixXd> state_rows)
      : force_(force_rows), state_(state_rows) {}
  /// ∂f_i[dof]/∂y[col] += v  (dof in 0 … 2n−1).
  void AddForce(int dof, int col, double v) { force_(dof, col) += v; }
  /// ∂ẋ_i[row]/∂y[col] += v  (row in 0 … num_states()−1 of this extension).
  void AddState(int row, int col, double v) { state_(row, col) += v; }

 private:
  Eigen::Ref<Eigen::MatrixXd> force_;
  Eigen::Ref<Eigen::MatrixXd> state_;
};

/// One plant extension (see the file comment). Methods are const and must not throw; a non-zero
/// return follows the SUNDIALS convention (> 0 recoverable, < 0 fatal).
class BimorphExtension {
 public:
  virtual ~BimorphExtension() = default;
  /// Short name for messages, e.g. "amplifier".
  virtual std::string name() const = 0;
  /// Number of own states appended to y, ≥ 0.
  virtual int num_states() const { return 0; }
  /// Initial own states (default zeros).
  virtual void InitialState(std::span<double> x) const;
  /// True if ShapeDrive() replaces the drive.
  virtual bool shapes_drive() const { return false; }
  /// Drive stage: replaces (u, u̇) given the point p (p.u, p.u_dot hold the incoming drive).
  virtual int ShapeDrive(const BimorphPoint& p, double& u, double& u_dot) const { return 0; }
  /// Drive stage Jacobian: on entry du_dy, du_dot_dy hold ∂(incoming u, u̇)/∂y; on exit they must
  /// hold ∂(outgoing u, u̇)/∂y.
  virtual void ShapeDriveJacobian(const BimorphPoint& p, std::span<double> du_dy,
                                  std::span<double> du_dot_dy) const {}
  /// Own state derivatives into x_dot (num_states() entries) and the generalised force on the beam
  /// added into beam_force (2n entries, zero on entry for the first extension that writes it).
  virtual int Rhs(const BimorphPoint& p, std::span<double> x_dot,
                  std::span<double> beam_force) const = 0;
  /// ∂x_dot/∂y and ∂beam_force/∂y at p, total derivatives (through p.u, p.u_dot too: use p.du_dy,
  /// p.du_dot_dy). Entries the extension omits are taken as zero.
  virtual void Jacobian(const BimorphPoint& p, ExtensionJacobian& jac) const = 0;
};

/// Precomputed matrices of the first-order beam system for one geometry (M⁻¹ through Cholesky).
struct BeamOdeMatrices {
  Eigen::MatrixXd minv_k;                ///< M⁻¹ K
  Eigen::VectorXd minv_bu;               ///< M⁻¹ B_u [per volt]
  Eigen::VectorXd minv_e;                ///< M⁻¹ e* [per newton]
  Eigen::LLT<Eigen::MatrixXd> mass_llt;  ///< Cholesky factor of M (applies M⁻¹ to extension forces)
  explicit BeamOdeMatrices(const FeModel& fe);
};

/// The bimorph plant y' = f(t, y) of the file comment, for one run: it binds a (shared, immutable)
/// plant, the parameters, the drive and the extensions. Not to be shared between concurrent runs
/// (the drive piece of a SampledSignal and scratch vectors live in it); constructing one is cheap.
class BimorphOde final : public OdeSystem {
 public:
  BimorphOde(const BimorphPlant& plant, const BimorphParams& params, const DriveSignal& drive,
             std::vector<const BimorphExtension*> extensions = {});

  int size() const override { return size_; }
  int Rhs(double t, const double* y, double* ydot) const override;
  JacobianStructure jacobian_structure() const override {
    return {.analytic = true, .kinematic = nd_};
  }
  int Jacobian(double t, const double* y, const double* fy, JacobianView& jac) const override;

  int num_dofs() const { return nd_; }                             ///< 2n
  int q_index(int dof) const { return dof; }                       ///< index of q[dof] in y
  int q_dot_index(int dof) const { return nd_ + dof; }             ///< index of q̇[dof] in y
  int z_index() const { return 2 * nd_; }                          ///< index of z in y
  int tip_index() const { return tip_dof_; }                       ///< index of w_tip in y
  int extension_offset(size_t i) const { return ext_offset_[i]; }  ///< first state of extension i

  /// Zero beam and Bouc–Wen states, the extensions' InitialState().
  std::vector<double> InitialState() const;
  /// Breakpoints of the drive (see DriveInput::Breakpoints()).
  std::vector<double> Breakpoints() const { return drive_.Breakpoints(); }
  bool piecewise_drive() const { return drive_.piecewise(); }
  /// Selects the drive piece for the integration that continues from t (SampledSignal).
  void SelectDrivePieceAt(double t) { drive_.SelectPieceAt(t); }

 private:
  // The point extension ext sees, with the drive (u, u̇) after the stages before it.
  BimorphPoint Point(double t, const double* y, size_t ext, double u, double u_dot) const;

  const BimorphPlant& plant_;
  BimorphParams params_;
  DriveInput drive_;
  std::vector<const BimorphExtension*> extensions_;
  BeamOdeMatrices mats_;
  int nd_ = 0;
  int size_ = 0;
  int tip_dof_ = 0;
  std::vector<int> ext_offset_;
  mutable Eigen::VectorXd work_;  // 2n scratch (beam force of the extensions)
};

/// Simulates the plant (with optional extensions) on the CVODE path: BDF, Newton with the analytic
/// dense Jacobian, breakpoints at the drive's non-smooth points, outputs on the signal's sample
/// grid, then θ = atan(w_tip / L) [deg] and the backlash. Assumes params, drive and options
/// validated and the loop bounded (Simulate() checks); never throws. options.solver is ignored. If
/// the solve fails, the trace holds the samples reached before the failure and the summary says
/// why.
BimorphTrace SimulateBimorphOde(const BimorphPlant& plant, const BimorphParams& params,
                                const DriveSignal& drive, const SimulateOptions& options,
                                std::vector<const BimorphExtension*> extensions = {});

}  // namespace pz::model
