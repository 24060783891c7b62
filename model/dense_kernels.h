// The dense kernels of the Levenberg–Marquardt trainers: JᵀJ (the bulk of an epoch), GEMM for the
// benchmark, and Cholesky factor / solve / trace of the inverse for (JᵀJ/N + μI) δ = −Jᵀe/N.
//
// When the build found a BLAS/LAPACK (Debian's libopenblas-serial-dev, installed by
// scripts/deps.sh) these call its dsyrk / dgemm / dpotrf / dpotrs / dpocon / dpotri, which pick
// AVX2/FMA kernels at run time; otherwise Eigen's own kernels (which this project compiles for the
// baseline ISA unless PIEZOID_NATIVE is on). Results agree to rounding; a given build and machine
// is deterministic (single-threaded BLAS). Safe to call from several threads: the BLAS calls are
// serialised by a lock, because Debian's serial OpenBLAS is not re-entrant.
#pragma once

#include <Eigen/Core>

namespace pz::model {

/// "OpenBLAS <version> <core>" / "BLAS" / "Eigen <version>": who computes the kernels below.
const char* DenseBackendName();

/// Lower triangle of C ← alpha Jᵀ J + beta C (J: m × p, C: p × p). The upper triangle is not
/// touched.
void SyrkTnLower(const Eigen::Ref<const Eigen::MatrixXd>& J, double alpha, double beta,
                 Eigen::Ref<Eigen::MatrixXd> C);

/// C ← alpha Aᵀ B + beta C (A: k × m, B: k × n, C: m × n).
void GemmTn(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::MatrixXd>& B,
            double alpha, double beta, Eigen::Ref<Eigen::MatrixXd> C);

/// In-place Cholesky of the symmetric matrix whose lower triangle is in A: A = L Lᵀ with L in the
/// lower triangle. Returns false if A is not (numerically) positive definite. If rcond is not null
/// it receives the reciprocal 1-norm condition estimate of the original A (0 on failure).
bool CholeskyLower(Eigen::Ref<Eigen::MatrixXd> A, double* rcond = nullptr);

/// Solves L Lᵀ x = b in place (b → x) with the factor from CholeskyLower.
void CholeskySolve(const Eigen::Ref<const Eigen::MatrixXd>& L, Eigen::Ref<Eigen::VectorXd> b);

/// tr((L Lᵀ)⁻¹) = ‖L⁻¹‖²_F from the factor from CholeskyLower (L is copied, not changed).
double CholeskyInverseTrace(const Eigen::Ref<const Eigen::MatrixXd>& L);

}  // namespace pz::model
