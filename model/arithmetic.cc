#include "model/arithmetic.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include <Eigen/Dense>

#if defined(__GLIBC__)
#include <gnu/libc-version.h>
#endif

#include "model/bimorph.h"
#include "model/dense_kernels.h"
#include "model/ffnet.h"
#include "pz_build_id.h"  // PIEZOID_BUILD_ID (cmake/build_id.cmake)

namespace pz::model {

namespace {

// FNV-1a over the bits of the doubles a probe computes.
class Hash {
 public:
  void Add(double v) {
    uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    for (int i = 0; i < 8; ++i) h_ = (h_ ^ ((b >> (8 * i)) & 0xff)) * 1099511628211ull;
  }
  void Add(const double* p, size_t n) {
    for (size_t i = 0; i < n; ++i) Add(p[i]);
  }
  void Add(const Eigen::MatrixXd& m) { Add(m.data(), static_cast<size_t>(m.size())); }
  void Add(const std::vector<double>& v) { Add(v.data(), v.size()); }
  uint64_t value() const { return h_; }

 private:
  uint64_t h_ = 1469598103934665603ull;
};

std::string Hex16(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

// A deterministic, well-scaled tall matrix (no random generator: the same on every machine).
Eigen::MatrixXd Tall(int rows, int cols) {
  Eigen::MatrixXd j(rows, cols);
  for (int c = 0; c < cols; ++c)
    for (int r = 0; r < rows; ++r)
      j(r, c) = std::sin(0.37 * r + 1.3 * c) + 0.1 * std::cos(0.011 * r * (c + 1)) + 0.01 * c;
  return j;
}

// The C library's maths: the functions the plants, the networks and the fits call, over wide
// ranges (their FMA and non-FMA variants differ in the last bit on some of these inputs).
uint64_t ProbeLibm() {
  Hash h;
  for (int i = 1; i <= 2048; ++i) {
    const double x = i * 0.00731 - 3.0, p = i * 0.0117;
    h.Add(std::exp(x));
    h.Add(std::expm1(x * 1e-3));
    h.Add(std::log(p));
    h.Add(std::log1p(p));
    h.Add(std::pow(p, 1.37));
    h.Add(std::pow(p, -0.61));
    h.Add(std::sin(x * 3.1));
    h.Add(std::cos(x * 3.1));
    h.Add(std::tan(x * 0.49));
    h.Add(std::atan(x));
    h.Add(std::atan2(x, p));
    h.Add(std::tanh(x));
    h.Add(std::sinh(x));
    h.Add(std::cosh(x));
    h.Add(std::cbrt(x));
  }
  return h.value();
}

// Eigen's own kernels (compiled for the baseline instruction set): a deep product Jᵀ J (the
// records' Levenberg–Marquardt normal equations), an SVD (uncertainty tables), QR, LDLT and a
// generalised eigenproblem (the beam's modes).
uint64_t ProbeEigen() {
  Hash h;
  const Eigen::MatrixXd j = Tall(4000, 7);
  const Eigen::MatrixXd a = j.transpose() * j;
  h.Add(a);
  const Eigen::MatrixXd small = Tall(400, 7);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(small, Eigen::ComputeThinV);
  h.Add(svd.singularValues()(0));
  h.Add(svd.singularValues()(6));
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(small);
  h.Add(Eigen::MatrixXd(qr.matrixR().topRows(7)));
  const Eigen::VectorXd g = j.transpose() * Eigen::VectorXd::Ones(4000);
  const Eigen::VectorXd x = a.ldlt().solve(g);
  h.Add(x.data(), static_cast<size_t>(x.size()));
  const Eigen::MatrixXd m = a + 7.0 * Eigen::MatrixXd::Identity(7, 7);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(a, m);
  h.Add(es.eigenvalues().data(), 7);
  return h.value();
}

// The dense backend (model/dense_kernels.h: OpenBLAS when the build found it, Eigen otherwise).
uint64_t ProbeDense() {
  Hash h;
  const Eigen::MatrixXd j = Tall(3000, 12);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(12, 12);
  SyrkTnLower(j, 1.0, 0.0, c);
  h.Add(c);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(12, 3);
  GemmTn(j, j.leftCols(3), 1.0, 0.0, g);
  h.Add(g);
  for (int i = 0; i < 12; ++i) c(i, i) += 1.0;
  double rcond = 0;
  if (CholeskyLower(c, &rcond)) {
    Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(12, 1.0, 2.0);
    CholeskySolve(c, b);
    h.Add(b.data(), 12);
    h.Add(rcond);
    h.Add(CholeskyInverseTrace(c));
  }
  return h.value();
}

// The bimorph fin on its fast path (the HGANN's hot path: the cloned kernels) and on CVODE.
uint64_t ProbeFin(Solver solver) {
  static const BimorphPlant plant;
  BimorphParams p;
  Sinusoid drive;
  drive.amplitude_v = 500;
  drive.frequency_hz = 1.0;
  drive.cycles = solver == Solver::kModal ? 2.0 : 0.5;
  drive.sample_rate_hz = 100;
  SimulateOptions o;
  o.solver = solver;
  o.rtol = 1e-8;
  const BimorphTrace t = Simulate(plant, p, drive, o);
  Hash h;
  h.Add(t.angle_deg);
  h.Add(t.z);
  return h.value();
}

// The networks' vectorised tansig (a cloned kernel).
uint64_t ProbeTansig() {
  Eigen::MatrixXd n(64, 16);
  for (int i = 0; i < n.size(); ++i) n.data()[i] = std::sin(0.7 * i) * (1.0 + 0.01 * i);
  TansigInPlace(n);
  Hash h;
  h.Add(n);
  return h.value();
}

std::vector<ArithmeticPart> Measure() {
  std::vector<ArithmeticPart> parts = {
      {"libm", "the C library's exp, log, pow, sin, cos, tan, atan, tanh, … (ifunc variants)",
       ProbeLibm()},
      {"eigen", "Eigen: a deep Jᵀ J, SVD, QR, LDLT, generalised eigenvalues", ProbeEigen()},
      {"dense", std::string("the dense backend (") + DenseBackendName() + "): syrk, gemm, Cholesky",
       ProbeDense()},
      {"fin", "the bimorph fin's modal fast path (the HGANN fitness)", ProbeFin(Solver::kModal)},
      {"cvode", "the bimorph fin on SUNDIALS CVODE", ProbeFin(Solver::kCvode)},
      {"tansig", "the networks' vectorised tansig", ProbeTansig()},
  };
  const std::string& skew = ArithmeticSkew();
  for (ArithmeticPart& part : parts)
    if (part.name == skew) part.digest ^= 1;
  return parts;
}

std::string BuildName() {
  return std::string("piezoid ") + PIEZOID_VERSION + " (" + PIEZOID_BUILD_ID + ")";
}

// "name=hex" tokens after the build's "; ".
std::vector<std::pair<std::string, std::string>> Tokens(const std::string& profile) {
  std::vector<std::pair<std::string, std::string>> out;
  const size_t semi = profile.find("; ");
  if (semi == std::string::npos) return out;
  std::istringstream in(profile.substr(semi + 2));
  std::string tok;
  while (in >> tok) {
    const size_t eq = tok.find('=');
    if (eq != std::string::npos) out.emplace_back(tok.substr(0, eq), tok.substr(eq + 1));
  }
  return out;
}

}  // namespace

const std::string& ArithmeticSkew() {
  static const std::string skew = [] {
    const char* s = std::getenv("PIEZOID_ARITHMETIC_SKEW");
    return std::string(s == nullptr ? "" : s);
  }();
  return skew;
}

const std::vector<ArithmeticPart>& MeasuredArithmetic() {
  static const std::vector<ArithmeticPart> parts = Measure();
  return parts;
}

std::string ArithmeticFingerprint() {
  std::string s;
  for (const ArithmeticPart& p : MeasuredArithmetic())
    s += (s.empty() ? "" : " ") + p.name + "=" + Hex16(p.digest);
  return s;
}

std::string ArithmeticDigest() {
  Hash h;
  for (const ArithmeticPart& p : MeasuredArithmetic()) h.Add(static_cast<double>(p.digest));
  return Hex16(h.value());
}

std::string ArithmeticProfile() { return BuildName() + "; " + ArithmeticFingerprint(); }

std::string ArithmeticDifference(const std::string& ours, const std::string& theirs) {
  if (ours == theirs) return "";
  const size_t a = ours.find("; "), b = theirs.find("; ");
  const std::string build_a = ours.substr(0, a), build_b = theirs.substr(0, b);
  if (build_a != build_b) return "the build ('" + build_a + "' here, '" + build_b + "' there)";
  const auto ta = Tokens(ours), tb = Tokens(theirs);
  std::string diff;
  for (const auto& [name, value] : ta) {
    std::string other = "(not measured)";
    for (const auto& [n, v] : tb)
      if (n == name) other = v;
    if (other != value)
      diff += (diff.empty() ? "" : ", ") + name + " (" + value + " here, " + other + " there)";
  }
  return diff.empty() ? "the profile ('" + ours + "' here, '" + theirs + "' there)" : diff;
}

std::string InstructionSetLevel() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("x86-64-v3")) return "x86-64-v3";
  if (__builtin_cpu_supports("fma") && __builtin_cpu_supports("avx2")) return "x86-64+fma";
  return "x86-64";
#elif defined(__x86_64__)
  return "x86-64";
#elif defined(__aarch64__)
  return "aarch64";
#else
  return "unknown-architecture";
#endif
}

std::vector<std::pair<std::string, std::string>> ArithmeticReport() {
  std::vector<std::pair<std::string, std::string>> r;
  r.emplace_back("build", BuildName());
  r.emplace_back("isa", InstructionSetLevel() + " (the cloned kernels' copy, libm's variants)");
#if defined(__GLIBC__)
  r.emplace_back("libc", std::string("glibc ") + gnu_get_libc_version());
#else
  r.emplace_back("libc", "unknown");
#endif
  r.emplace_back("dense", DenseBackendName());
  std::ptrdiff_t l1 = 0, l2 = 0, l3 = 0;
  Eigen::internal::manage_caching_sizes(Eigen::GetAction, &l1, &l2, &l3);
  r.emplace_back("eigen", std::to_string(EIGEN_WORLD_VERSION) + "." +
                              std::to_string(EIGEN_MAJOR_VERSION) + "." +
                              std::to_string(EIGEN_MINOR_VERSION) + " (" +
                              Eigen::SimdInstructionSetsInUse() + "; product blocks for caches " +
                              std::to_string(l1 / 1024) + "/" + std::to_string(l2 / 1024) + "/" +
                              std::to_string(l3 / 1024) + " KiB, fixed by the build)");
  for (const ArithmeticPart& p : MeasuredArithmetic())
    r.emplace_back("fingerprint." + p.name, Hex16(p.digest) + "  " + p.what);
  r.emplace_back("digest", ArithmeticDigest());
  if (!ArithmeticSkew().empty())
    r.emplace_back("skew", "PIEZOID_ARITHMETIC_SKEW=" + ArithmeticSkew() + " (a test hook)");
  return r;
}

}  // namespace pz::model
