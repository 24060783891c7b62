#include "model/dense_kernels.h"

#include <cstddef>
#include <mutex>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include "model/status.h"

#ifdef PZ_HAVE_BLAS
// Fortran BLAS / LAPACK interface (any BLAS; the build links OpenBLAS when found). The trailing
// size_t arguments are gfortran's hidden lengths of the character arguments.
extern "C" {
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha,
            const double* a, const int* lda, const double* beta, double* c, const int* ldc, size_t,
            size_t);
void dgemm_(const char* ta, const char* tb, const int* m, const int* n, const int* k,
            const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
            const double* beta, double* c, const int* ldc, size_t, size_t);
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info, size_t);
void dpotrs_(const char* uplo, const int* n, const int* nrhs, const double* a, const int* lda,
             double* b, const int* ldb, int* info, size_t);
void dpocon_(const char* uplo, const int* n, const double* a, const int* lda, const double* anorm,
             double* rcond, double* work, int* iwork, int* info, size_t);
double dlansy_(const char* norm, const char* uplo, const int* n, const double* a, const int* lda,
               double* work, size_t, size_t);
void dtrtri_(const char* uplo, const char* diag, const int* n, double* a, const int* lda, int* info,
             size_t, size_t);
// OpenBLAS only; null with another BLAS.
char* openblas_get_config() __attribute__((weak));
char* openblas_get_corename() __attribute__((weak));
}
#endif

namespace pz::model {

namespace {
int AsInt(Eigen::Index i) {
  PZ_CHECK(i >= 0 && i <= 0x7fffffff);
  return static_cast<int>(i);
}
#ifdef PZ_HAVE_BLAS
// Debian's serial OpenBLAS shares its work buffers between callers without locking: two threads in
// dsyrk at once give wrong sums (seen here). Every BLAS / LAPACK call holds this lock, so callers
// on several threads stay correct (they do not run their BLAS parts in parallel).
std::mutex blas_mutex;
#endif
}  // namespace

const char* DenseBackendName() {
#ifdef PZ_HAVE_BLAS
  static const std::string name = [] {
    if (openblas_get_config == nullptr) return std::string("BLAS/LAPACK");
    std::string s = openblas_get_config();
    if (openblas_get_corename != nullptr) s += std::string(" core=") + openblas_get_corename();
    return s;
  }();
  return name.c_str();
#else
  static const std::string name =
      "Eigen " + std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) +
      "." + std::to_string(EIGEN_MINOR_VERSION) + " (" + Eigen::SimdInstructionSetsInUse() + ")";
  return name.c_str();
#endif
}

void SyrkTnLower(const Eigen::Ref<const Eigen::MatrixXd>& J, double alpha, double beta,
                 Eigen::Ref<Eigen::MatrixXd> C) {
  PZ_CHECK(C.rows() == J.cols() && C.cols() == J.cols());
  if (J.cols() == 0) return;
#ifdef PZ_HAVE_BLAS
  const int n = AsInt(J.cols()), k = AsInt(J.rows());
  const int lda = AsInt(std::max<Eigen::Index>(1, J.outerStride()));
  const int ldc = AsInt(C.outerStride());
  std::lock_guard<std::mutex> lock(blas_mutex);
  dsyrk_("L", "T", &n, &k, &alpha, J.data(), &lda, &beta, C.data(), &ldc, 1, 1);
#else
  if (beta != 1.0) C.triangularView<Eigen::Lower>() = beta * C;
  C.selfadjointView<Eigen::Lower>().rankUpdate(J.transpose(), alpha);
#endif
}

void GemmTn(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::MatrixXd>& B,
            double alpha, double beta, Eigen::Ref<Eigen::MatrixXd> C) {
  PZ_CHECK(A.rows() == B.rows() && C.rows() == A.cols() && C.cols() == B.cols());
#ifdef PZ_HAVE_BLAS
  const int m = AsInt(A.cols()), n = AsInt(B.cols()), k = AsInt(A.rows());
  const int lda = AsInt(std::max<Eigen::Index>(1, A.outerStride()));
  const int ldb = AsInt(std::max<Eigen::Index>(1, B.outerStride()));
  const int ldc = AsInt(std::max<Eigen::Index>(1, C.outerStride()));
  std::lock_guard<std::mutex> lock(blas_mutex);
  dgemm_("T", "N", &m, &n, &k, &alpha, A.data(), &lda, B.data(), &ldb, &beta, C.data(), &ldc, 1, 1);
#else
  if (beta == 0.0)
    C.noalias() = alpha * A.transpose() * B;
  else {
    C *= beta;
    C.noalias() += alpha * A.transpose() * B;
  }
#endif
}

bool CholeskyLower(Eigen::Ref<Eigen::MatrixXd> A, double* rcond) {
  PZ_CHECK(A.rows() == A.cols());
  if (rcond != nullptr) *rcond = 0;
#ifdef PZ_HAVE_BLAS
  const int n = AsInt(A.rows()), lda = AsInt(std::max<Eigen::Index>(1, A.outerStride()));
  std::vector<double> work(3 * static_cast<size_t>(n) + 1);
  std::vector<int> iwork(static_cast<size_t>(n) + 1);
  std::lock_guard<std::mutex> lock(blas_mutex);
  const double anorm =
      rcond != nullptr ? dlansy_("1", "L", &n, A.data(), &lda, work.data(), 1, 1) : 0;
  int info = 0;
  dpotrf_("L", &n, A.data(), &lda, &info, 1);
  if (info != 0) return false;
  if (rcond != nullptr) {
    dpocon_("L", &n, A.data(), &lda, &anorm, rcond, work.data(), iwork.data(), &info, 1);
    if (info != 0) *rcond = 0;
  }
  return true;
#else
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(A);
  if (llt.info() != Eigen::Success) return false;
  if (rcond != nullptr) *rcond = llt.rcond();
  return true;
#endif
}

void CholeskySolve(const Eigen::Ref<const Eigen::MatrixXd>& L, Eigen::Ref<Eigen::VectorXd> b) {
  PZ_CHECK(L.rows() == L.cols() && b.size() == L.rows());
#ifdef PZ_HAVE_BLAS
  const int n = AsInt(L.rows()), lda = AsInt(std::max<Eigen::Index>(1, L.outerStride()));
  const int one = 1, ldb = std::max(1, n);
  int info = 0;
  std::lock_guard<std::mutex> lock(blas_mutex);
  dpotrs_("L", &n, &one, L.data(), &lda, b.data(), &ldb, &info, 1);
  PZ_CHECK(info == 0);
#else
  L.triangularView<Eigen::Lower>().solveInPlace(b);
  L.triangularView<Eigen::Lower>().transpose().solveInPlace(b);
#endif
}

double CholeskyInverseTrace(const Eigen::Ref<const Eigen::MatrixXd>& L) {
  PZ_CHECK(L.rows() == L.cols());
  Eigen::MatrixXd Linv = L.triangularView<Eigen::Lower>();
#ifdef PZ_HAVE_BLAS
  const int n = AsInt(L.rows()), lda = std::max(1, n);
  int info = 0;
  std::lock_guard<std::mutex> lock(blas_mutex);
  dtrtri_("L", "N", &n, Linv.data(), &lda, &info, 1, 1);
  PZ_CHECK(info == 0);
  return Linv.triangularView<Eigen::Lower>().toDenseMatrix().squaredNorm();
#else
  L.triangularView<Eigen::Lower>().solveInPlace(Linv.setIdentity());
  return Linv.triangularView<Eigen::Lower>().toDenseMatrix().squaredNorm();
#endif
}

}  // namespace pz::model
