// Dahl networks (LM / BR): where an epoch's time goes for the default 1-100-1 network on the case-1
// data set (7,001 training samples, P = 301 weights), against this machine's BLAS-level speed.
//
//   BM_Dsyrk / BM_DgemmJtJ / BM_Dgemm1000   this build's dense backend (model/dense_kernels.h)
//   BM_EigenRankUpdate / BM_EigenGemmJtJ      Eigen's own kernels at the build's ISA, for
//   comparison BM_Jacobian                               J (7,001 × 301) alone: the tansig layer
//   and its derivatives BM_NormalEquations/<block_rows>           J, JᵀJ and Jᵀe as the trainers
//   form them, by row block BM_Predict                                one forward pass over the
//   training samples (a trial step) BM_DampedSolve                            Cholesky + rcond +
//   solve of the 301 × 301 damped system BM_LmEpochs / BM_BrEpochs                 whole trainer
//   epochs (TrainLm / TrainBr, 20 epochs per run)
//
// Flop counts: SYRK n p (p + 1) (= 636 Mflop for 7,001 × 301), GEMM 2 n p². GFLOP/s counters are on
// the benchmark's CPU time (single thread), so they hold when other processes share the cores.
// Figures: docs/performance.md, "Studies against published figures".
#include <benchmark/benchmark.h>

#include <Eigen/Dense>

#include "client/dahl_nets.h"
#include "model/dense_kernels.h"
#include "model/lm_train.h"

namespace {

using namespace pz;

constexpr int kRows = 7001;   // training samples of a 10,001-point case (70 %)
constexpr int kParams = 301;  // 1-100-1 network

struct Case1 {
  client::DahlDataset ds;
  model::FitSetup fit;
  Eigen::MatrixXd xn_train;
  Eigen::VectorXd t_train;
  Case1()
      : ds(client::MakeDahlDataset(client::PaperDahlCase(1))),
        fit(model::SetUpFit(ds.data, 100, model::SplitRatios{}, 1)) {
    const Eigen::MatrixXd xn = fit.net.input_map().Apply(ds.data.x);
    xn_train.resize(static_cast<Eigen::Index>(fit.split.train.size()), 1);
    t_train.resize(xn_train.rows());
    for (size_t i = 0; i < fit.split.train.size(); ++i) {
      xn_train(static_cast<Eigen::Index>(i), 0) = xn(fit.split.train[i], 0);
      t_train(static_cast<Eigen::Index>(i)) = ds.data.t(fit.split.train[i]);
    }
  }
};
const Case1& Data() {
  static const Case1 c;
  return c;
}

void SetFlops(benchmark::State& state, double flops_per_iter) {
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops_per_iter * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(model::DenseBackendName());
}

void BM_Dsyrk(benchmark::State& state) {
  const Eigen::MatrixXd J = Eigen::MatrixXd::Random(kRows, kParams);
  Eigen::MatrixXd C(kParams, kParams);
  for (auto _ : state) {
    model::SyrkTnLower(J, 1.0, 0.0, C);
    benchmark::DoNotOptimize(C.data());
  }
  SetFlops(state, double(kRows) * kParams * (kParams + 1));
}
BENCHMARK(BM_Dsyrk)->Unit(benchmark::kMillisecond);

void BM_DgemmJtJ(benchmark::State& state) {
  const Eigen::MatrixXd J = Eigen::MatrixXd::Random(kRows, kParams);
  Eigen::MatrixXd C(kParams, kParams);
  for (auto _ : state) {
    model::GemmTn(J, J, 1.0, 0.0, C);
    benchmark::DoNotOptimize(C.data());
  }
  SetFlops(state, 2.0 * kRows * kParams * kParams);
}
BENCHMARK(BM_DgemmJtJ)->Unit(benchmark::kMillisecond);

void BM_Dgemm1000(benchmark::State& state) {
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(1000, 1000),
                        B = Eigen::MatrixXd::Random(1000, 1000);
  Eigen::MatrixXd C(1000, 1000);
  for (auto _ : state) {
    model::GemmTn(A, B, 1.0, 0.0, C);
    benchmark::DoNotOptimize(C.data());
  }
  SetFlops(state, 2e9);
}
BENCHMARK(BM_Dgemm1000)->Unit(benchmark::kMillisecond);

void BM_EigenRankUpdate(benchmark::State& state) {
  const Eigen::MatrixXd J = Eigen::MatrixXd::Random(kRows, kParams);
  Eigen::MatrixXd C(kParams, kParams);
  for (auto _ : state) {
    C.setZero();
    C.selfadjointView<Eigen::Lower>().rankUpdate(J.transpose());
    benchmark::DoNotOptimize(C.data());
  }
  SetFlops(state, double(kRows) * kParams * (kParams + 1));
  state.SetLabel(std::string("Eigen ") + Eigen::SimdInstructionSetsInUse());
}
BENCHMARK(BM_EigenRankUpdate)->Unit(benchmark::kMillisecond);

void BM_EigenGemmJtJ(benchmark::State& state) {
  const Eigen::MatrixXd J = Eigen::MatrixXd::Random(kRows, kParams);
  Eigen::MatrixXd C(kParams, kParams);
  for (auto _ : state) {
    C.noalias() = J.transpose() * J;
    benchmark::DoNotOptimize(C.data());
  }
  SetFlops(state, 2.0 * kRows * kParams * kParams);
  state.SetLabel(std::string("Eigen ") + Eigen::SimdInstructionSetsInUse());
}
BENCHMARK(BM_EigenGemmJtJ)->Unit(benchmark::kMillisecond);

void BM_Jacobian(benchmark::State& state) {
  const Case1& c = Data();
  Eigen::MatrixXd J(c.xn_train.rows(), kParams);
  Eigen::VectorXd y(c.xn_train.rows());
  for (auto _ : state) {
    c.fit.net.JacobianNormalised(c.xn_train, y, J);
    benchmark::DoNotOptimize(J.data());
  }
}
BENCHMARK(BM_Jacobian)->Unit(benchmark::kMillisecond);

void BM_NormalEquations(benchmark::State& state) {
  const Case1& c = Data();
  model::NormalEquations ne(static_cast<int>(state.range(0)), kParams);
  Eigen::MatrixXd JJ(kParams, kParams);
  Eigen::VectorXd JE(kParams);
  double mse = 0;
  for (auto _ : state) {
    ne.Form(c.fit.net, c.xn_train, c.t_train, JJ, JE, mse);
    benchmark::DoNotOptimize(JJ.data());
  }
  SetFlops(state, double(c.xn_train.rows()) * kParams * (kParams + 1));
}
BENCHMARK(BM_NormalEquations)
    ->Arg(64)
    ->Arg(128)
    ->Arg(256)
    ->Arg(512)
    ->Arg(1024)
    ->Arg(kRows)
    ->Unit(benchmark::kMillisecond);

void BM_Predict(benchmark::State& state) {
  const Case1& c = Data();
  for (auto _ : state) benchmark::DoNotOptimize(c.fit.net.PredictNormalised(c.xn_train).data());
}
BENCHMARK(BM_Predict)->Unit(benchmark::kMillisecond);

void BM_DampedSolve(benchmark::State& state) {
  const Eigen::MatrixXd J = Eigen::MatrixXd::Random(kRows, kParams);
  Eigen::MatrixXd JJ(kParams, kParams);
  model::SyrkTnLower(J, 1.0 / kRows, 0.0, JJ);
  const Eigen::VectorXd rhs = Eigen::VectorXd::Random(kParams);
  Eigen::MatrixXd work(kParams, kParams);
  for (auto _ : state) {
    work.triangularView<Eigen::Lower>() = JJ;
    work.diagonal().array() += 1e-3;
    double rcond = 0;
    model::CholeskyLower(work, &rcond);
    Eigen::VectorXd x = -rhs;
    model::CholeskySolve(work, x);
    benchmark::DoNotOptimize(x.data());
  }
}
BENCHMARK(BM_DampedSolve)->Unit(benchmark::kMillisecond);

// Whole epochs from the seed-1 initial network: 20 epochs per iteration (plus the initial JᵀJ).
void RunEpochs(benchmark::State& state, bool br) {
  const Case1& c = Data();
  constexpr int kEpochs = 20;
  double jtj = 0, wall = 0;
  long forms = 0, solves = 0;
  for (auto _ : state) {
    model::FeedForwardNet net = c.fit.net;
    model::TrainSummary s;
    if (br) {
      model::BrOptions o;
      o.epochs = kEpochs;
      s = model::TrainBr(net, c.ds.data, c.fit.split, o);
    } else {
      model::LmOptions o;
      o.epochs = kEpochs;
      o.max_fail = 0;
      s = model::TrainLm(net, c.ds.data, c.fit.split, o);
    }
    jtj += s.jtj_time_s;
    wall += s.wall_time_s;
    forms += s.jacobians;
    solves += s.solves;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["ms_per_epoch_wall"] = 1e3 * wall / (n * kEpochs);
  state.counters["ms_per_JtJ_wall"] = 1e3 * jtj / static_cast<double>(forms);
  state.counters["solves_per_epoch"] = static_cast<double>(solves) / (n * kEpochs);
  state.counters["ms_per_epoch_cpu"] = benchmark::Counter(
      kEpochs * 1e-3, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.SetLabel(model::DenseBackendName());
}
void BM_LmEpochs(benchmark::State& state) { RunEpochs(state, false); }
void BM_BrEpochs(benchmark::State& state) { RunEpochs(state, true); }
BENCHMARK(BM_LmEpochs)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_BrEpochs)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
