#include "model/bimorph_ode.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pz::model {

// ---- DriveInput
// ----------------------------------------------------------------------------------

DriveInput::DriveInput(const DriveSignal& signal)
    : sinusoid_(std::get_if<Sinusoid>(&signal)), sampled_(std::get_if<SampledSignal>(&signal)) {}

double DriveInput::Value(double t) const {
  if (sinusoid_) return sinusoid_->Value(t);
  const size_t k = piece_;
  return sampled_->u[k] + Rate(t) * (t - sampled_->t[k]);
}

double DriveInput::Rate(double t) const {
  if (sinusoid_) return sinusoid_->Derivative(t);
  const size_t k = piece_;
  return (sampled_->u[k + 1] - sampled_->u[k]) / (sampled_->t[k + 1] - sampled_->t[k]);
}

std::vector<double> DriveInput::Breakpoints() const {
  std::vector<double> b;
  if (sampled_) {
    if (sampled_->t.size() > 2) b.assign(sampled_->t.begin() + 1, sampled_->t.end() - 1);
    return b;
  }
  // u̇ = V ω cos(ω t) vanishes at t = (2m + 1) / (4 f); the last sample is at (N − 1) / fs.
  const double t_last =
      static_cast<double>(sinusoid_->NumSamples() - 1) / sinusoid_->sample_rate_hz;
  for (long m = 0;; ++m) {
    const double tb = (2.0 * m + 1.0) / (4.0 * sinusoid_->frequency_hz);
    if (tb >= t_last) break;
    b.push_back(tb);
  }
  return b;
}

void DriveInput::SelectPieceAt(double t) {
  if (!sampled_) return;
  const auto& ts = sampled_->t;
  const auto it = std::upper_bound(ts.begin(), ts.end(), t);
  const size_t k = it == ts.begin() ? 0 : static_cast<size_t>(it - ts.begin()) - 1;
  piece_ = std::min(k, ts.size() - 2);
}

// ---- BimorphExtension
// ----------------------------------------------------------------------------

void BimorphExtension::InitialState(std::span<double> x) const {
  std::fill(x.begin(), x.end(), 0.0);
}

// ---- BeamOdeMatrices
// -----------------------------------------------------------------------------

BeamOdeMatrices::BeamOdeMatrices(const FeModel& fe) : mass_llt(fe.M) {
  PZ_CHECK_MSG(mass_llt.info() == Eigen::Success, "mass matrix not positive definite");
  minv_k = mass_llt.solve(fe.K);
  minv_bu = mass_llt.solve(fe.b_u);
  minv_e = mass_llt.solve(fe.e_tip);
}

// ---- BimorphOde
// ----------------------------------------------------------------------------------

BimorphOde::BimorphOde(const BimorphPlant& plant, const BimorphParams& params,
                       const DriveSignal& drive, std::vector<const BimorphExtension*> extensions)
    : plant_(plant),
      params_(params),
      drive_(drive),
      extensions_(std::move(extensions)),
      mats_(plant.fe()),
      nd_(plant.geometry().num_dofs()),
      tip_dof_(plant.geometry().tip_dof()) {
  size_ = 2 * nd_ + 1;
  for (const BimorphExtension* e : extensions_) {
    PZ_CHECK(e != nullptr && e->num_states() >= 0);
    ext_offset_.push_back(size_);
    size_ += e->num_states();
  }
  work_.setZero(nd_);
}

std::vector<double> BimorphOde::InitialState() const {
  std::vector<double> y(size_, 0.0);
  for (size_t i = 0; i < extensions_.size(); ++i)
    extensions_[i]->InitialState(
        std::span<double>(y.data() + ext_offset_[i], extensions_[i]->num_states()));
  return y;
}

BimorphPoint BimorphOde::Point(double t, const double* y, size_t ext, double u,
                               double u_dot) const {
  BimorphPoint p;
  p.t = t;
  p.y = {y, static_cast<size_t>(size_)};
  p.q = {y, static_cast<size_t>(nd_)};
  p.q_dot = {y + nd_, static_cast<size_t>(nd_)};
  p.z = y[2 * nd_];
  if (ext < extensions_.size())
    p.x = {y + ext_offset_[ext], static_cast<size_t>(extensions_[ext]->num_states())};
  p.u = u;
  p.u_dot = u_dot;
  p.tip_dof = tip_dof_;
  return p;
}

int BimorphOde::Rhs(double t, const double* y, double* ydot) const {
  const int nd = nd_;
  const double* q = y;
  const double* v = y + nd;
  const double z = y[2 * nd];
  double u = drive_.Value(t), u_dot = drive_.Rate(t);

  // Extensions first, in list order: each sees the drive after the stages before it.
  bool any_force = false;
  if (!extensions_.empty()) {
    work_.setZero();
    std::span<double> force(work_.data(), static_cast<size_t>(nd));
    for (size_t i = 0; i < extensions_.size(); ++i) {
      const BimorphExtension& e = *extensions_[i];
      const BimorphPoint p = Point(t, y, i, u, u_dot);
      std::span<double> x_dot(ydot + ext_offset_[i], static_cast<size_t>(e.num_states()));
      if (const int r = e.Rhs(p, x_dot, force); r != 0) return r;
      if (e.shapes_drive()) {
        if (const int r = e.ShapeDrive(p, u, u_dot); r != 0) return r;
      }
    }
    for (int i = 0; i < nd; ++i) any_force = any_force || work_[i] != 0.0;
  }

  // q̇ = v;  v̇ = M⁻¹B_u u − M⁻¹e* z − M⁻¹K (q + δ v) − μ v   (C = μM + δK).
  const double mu = params_.mu, delta = params_.delta;
  const Eigen::MatrixXd& mk = mats_.minv_k;
  for (int i = 0; i < nd; ++i) ydot[i] = v[i];
  for (int i = 0; i < nd; ++i)
    ydot[nd + i] = mats_.minv_bu[i] * u - mats_.minv_e[i] * z - mu * v[i];
  for (int j = 0; j < nd; ++j) {
    const double qj = q[j] + delta * v[j];
    const double* col = mk.data() + static_cast<long>(j) * nd;
    for (int i = 0; i < nd; ++i) ydot[nd + i] -= col[i] * qj;
  }
  if (any_force) {
    const Eigen::VectorXd a = mats_.mass_llt.solve(work_);
    for (int i = 0; i < nd; ++i) ydot[nd + i] += a[i];
  }
  // Bouc–Wen, exponent 1.
  ydot[2 * nd] = params_.alpha * u_dot - params_.beta * std::abs(u_dot) * z -
                 params_.gamma * u_dot * std::abs(z);
  return 0;
}

int BimorphOde::Jacobian(double t, const double* y, const double*, JacobianView& jac) const {
  const int nd = nd_, n = size_, iz = 2 * nd;
  const double z = y[iz];
  const double mu = params_.mu, delta = params_.delta;
  const Eigen::MatrixXd& mk = mats_.minv_k;

  // Drive through the stages, with its gradient ∂(u, u̇)/∂y (zero for the raw drive).
  double u = drive_.Value(t), u_dot = drive_.Rate(t);
  std::vector<double> du, dud;
  Eigen::MatrixXd force, state;  // Σ ∂f_i/∂y (before M⁻¹) and the extension state rows
  if (!extensions_.empty()) {
    du.assign(n, 0.0);
    dud.assign(n, 0.0);
    force.setZero(nd, n);
    state.setZero(n - iz - 1, n);
    for (size_t i = 0; i < extensions_.size(); ++i) {
      const BimorphExtension& e = *extensions_[i];
      BimorphPoint p = Point(t, y, i, u, u_dot);
      const std::vector<double> du_in = du,
                                dud_in = dud;  // p's gradient, stable while du, dud change
      p.du_dy = du_in;
      p.du_dot_dy = dud_in;
      ExtensionJacobian ej(force, state.middleRows(ext_offset_[i] - iz - 1, e.num_states()));
      e.Jacobian(p, ej);
      if (e.shapes_drive()) {
        e.ShapeDriveJacobian(p, du, dud);
        if (const int r = e.ShapeDrive(p, u, u_dot); r != 0) return r;
      }
    }
  }

  // Beam rows: ∂q̇/∂v = I;  ∂v̇/∂q = −M⁻¹K, ∂v̇/∂v = −μI − δM⁻¹K, ∂v̇/∂z = −M⁻¹e*.
  for (int i = 0; i < nd; ++i) jac.Set(i, nd + i, 1.0);
  for (int j = 0; j < nd; ++j) {
    for (int i = 0; i < nd; ++i) {
      jac.Set(nd + i, j, -mk(i, j));
      jac.Set(nd + i, nd + j, -delta * mk(i, j) - (i == j ? mu : 0.0));
    }
  }
  for (int i = 0; i < nd; ++i) jac.Set(nd + i, iz, -mats_.minv_e[i]);
  // Bouc–Wen row: ∂ż/∂z with sgn(0) = 0.
  const double sgn_z = (z > 0) - (z < 0), sgn_ud = (u_dot > 0) - (u_dot < 0);
  jac.Set(iz, iz, -params_.beta * std::abs(u_dot) - params_.gamma * u_dot * sgn_z);
  if (extensions_.empty()) return 0;

  // Extension blocks, and the chain rule through the final drive: v̇ gets M⁻¹B_u ∂u/∂y, ż gets
  // ∂ż/∂u̇ · ∂u̇/∂y with ∂ż/∂u̇ = α − β sgn(u̇) z − γ|z|.
  const double dzdot_dudot =
      params_.alpha - params_.beta * sgn_ud * z - params_.gamma * std::abs(z);
  const Eigen::MatrixXd minv_force = mats_.mass_llt.solve(force);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < nd; ++i) jac.Add(nd + i, j, minv_force(i, j) + mats_.minv_bu[i] * du[j]);
    jac.Add(iz, j, dzdot_dudot * dud[j]);
    for (int r = 0; r < state.rows(); ++r) jac.Add(iz + 1 + r, j, state(r, j));
  }
  return 0;
}

}  // namespace pz::model
