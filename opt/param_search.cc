#include "opt/param_search.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <utility>

#include "opt/inline_evaluator.h"
#include "opt/random.h"

namespace pz::opt {
namespace {

std::string Num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

double NowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

Status Field(const std::string& prefix, const char* field, double value, const char* rule) {
  return InvalidArgument(FieldError(prefix + "." + field, value, rule));
}

Status CheckProbability(const std::string& prefix, const char* field, double p) {
  if (!(p >= 0 && p <= 1)) return Field(prefix, field, p, "must be in [0, 1]");
  return Status::Ok();
}

Status CheckNonNegativeFinite(const std::string& prefix, const char* field, double v) {
  if (!(std::isfinite(v) && v >= 0)) return Field(prefix, field, v, "must be finite and >= 0");
  return Status::Ok();
}

/// Reflects x into [0, 1] (any number of folds).
double Reflect(double x) {
  if (x >= 0 && x <= 1) return x;
  double r = std::fmod(std::abs(x), 2.0);
  if (r > 1) r = 2 - r;
  return std::clamp(r, 0.0, 1.0);
}

/// A standard normal draw by Box–Muller from two uniform draws (always two).
double Gaussian(Rng& rng) {
  const double u1 = 1.0 - rng.Uniform01();  // (0, 1]
  const double u2 = rng.Uniform01();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

/// Does a new best cost count as an improvement over `reference` (relative tolerance)?
bool Significant(double new_best, double reference, double tolerance) {
  return new_best < reference - tolerance * std::abs(reference);
}

// Shared bookkeeping of one search (all repetitions).
struct Run {
  Run(const ParamBox& b, const SearchOptions& o, BatchEvaluator& e)
      : box(b), options(o), evaluator(e) {}
  const ParamBox& box;
  const SearchOptions& options;
  BatchEvaluator& evaluator;
  double start_s = NowSeconds();
  uint64_t batch_counter = 0;
  int64_t evaluations = 0;
  int iterations = 0;
  double overall_best = std::numeric_limits<double>::infinity();
  SearchTrace trace;

  // Evaluates unit-box points; writes sanitised costs.
  void EvaluateUnit(const std::vector<std::vector<double>>& unit, std::vector<double>& cost) {
    const size_t n = unit.size(), d = box.size();
    std::vector<Genome> genomes(n);
    for (size_t i = 0; i < n; ++i) {
      genomes[i].reals.resize(d);
      box.ToPhysical(unit[i].data(), genomes[i].reals.data());
    }
    EvaluatePhysical(genomes, cost);
  }

  void EvaluatePhysical(std::span<const Genome> genomes, std::vector<double>& cost) {
    std::vector<int> indices(genomes.size());
    std::iota(indices.begin(), indices.end(), 0);
    std::vector<FitnessResult> out(genomes.size());
    evaluator.Evaluate(EvalBatch{batch_counter++, genomes, indices}, out);
    cost.resize(genomes.size());
    for (size_t i = 0; i < out.size(); ++i) {
      SanitizeFitness(out[i], options.error_cost);
      cost[i] = out[i].cost;
    }
    evaluations += static_cast<int64_t>(genomes.size());
  }

  void Record(int repetition, int iteration, double rep_best) {
    overall_best = std::min(overall_best, rep_best);
    trace.evaluations.push_back(evaluations);
    trace.best_cost.push_back(overall_best);
    trace.wall_time_s.push_back(NowSeconds() - start_s);
    if (options.on_progress) {
      options.on_progress(
          SearchProgress{repetition, iteration, evaluations, rep_best, overall_best});
    }
  }

  // Common stopping rules; returns the reason or "".
  std::string Stop(int iteration, int max_iterations, int stall, int max_stall, double tolerance,
                   double best, double rep_start_s, const char* unit) const {
    std::ostringstream os;
    os.precision(10);
    if (best <= options.target_cost) {
      os << "target: best cost " << best << " <= " << options.target_cost;
    } else if (max_stall > 0 && stall >= max_stall) {
      os << "stall: no relative improvement > " << tolerance << " in " << stall << " " << unit;
    } else if (iteration >= max_iterations) {
      os << "limit: " << max_iterations << " " << unit;
    } else if (options.max_wall_time_s > 0 &&
               NowSeconds() - rep_start_s >= options.max_wall_time_s) {
      os << "time: " << options.max_wall_time_s << " s";
    }
    return os.str();
  }
};

struct RepetitionResult {
  std::vector<double> best_unit;
  double best_cost = 0;
  std::string stop_reason;
};

int ArgMin(const std::vector<double>& cost) {
  int best = 0;
  for (int i = 1; i < static_cast<int>(cost.size()); ++i) {
    if (cost[i] < cost[best]) best = i;
  }
  return best;
}

RepetitionResult RunPso(Run& run, int repetition) {
  const PsoOptions& o = run.options.pso;
  const size_t d = run.box.size(), n = o.particles;
  const double rep_start = NowSeconds();
  Rng rng(o.seed + static_cast<uint64_t>(repetition));
  std::vector<std::vector<double>> x(n, std::vector<double>(d)), v = x;
  for (size_t i = 0; i < n; ++i) {
    for (size_t k = 0; k < d; ++k) x[i][k] = rng.Uniform01();
    for (size_t k = 0; k < d; ++k) v[i][k] = (2 * rng.Uniform01() - 1) * o.velocity_clamp;
  }
  std::vector<double> cost;
  run.EvaluateUnit(x, cost);
  std::vector<std::vector<double>> pbest = x;
  std::vector<double> pcost = cost;
  int g = ArgMin(pcost);
  std::vector<double> gbest = pbest[g];
  double gcost = pcost[g], reference = gcost;
  int stall = 0, iteration = 0;
  run.Record(repetition, 0, gcost);
  std::string reason;
  // The swarm's spread about its best (max-norm, unit box) after an update; +inf before the first.
  double spread = std::numeric_limits<double>::infinity();
  auto converged = [&]() -> std::string {
    if (!(o.converged_spread > 0 && spread <= o.converged_spread)) return "";
    std::ostringstream os;
    os.precision(10);
    os << "converged: every particle within " << o.converged_spread << " of the best after "
       << iteration << " iterations";
    return os.str();
  };
  while ((reason = run.Stop(iteration, o.iterations, stall, o.stall_iterations, o.tolerance, gcost,
                            rep_start, "iterations"))
             .empty() &&
         (reason = converged()).empty()) {
    ++iteration;
    const double w = o.iterations <= 1 ? o.inertia_start
                                       : o.inertia_start + (o.inertia_end - o.inertia_start) *
                                                               (iteration - 1) / (o.iterations - 1);
    for (size_t i = 0; i < n; ++i) {
      for (size_t k = 0; k < d; ++k) {
        const double r1 = rng.Uniform01(), r2 = rng.Uniform01();
        double vk = w * v[i][k] + o.cognitive * r1 * (pbest[i][k] - x[i][k]) +
                    o.social * r2 * (gbest[k] - x[i][k]);
        vk = std::clamp(vk, -o.velocity_clamp, o.velocity_clamp);
        double xk = x[i][k] + vk;
        if (xk < 0 || xk > 1) {
          xk = Reflect(xk);
          vk = -vk;
        }
        x[i][k] = xk;
        v[i][k] = vk;
      }
    }
    run.EvaluateUnit(x, cost);
    for (size_t i = 0; i < n; ++i) {
      if (cost[i] < pcost[i]) {
        pcost[i] = cost[i];
        pbest[i] = x[i];
      }
    }
    g = ArgMin(pcost);
    if (pcost[g] < gcost) {
      gcost = pcost[g];
      gbest = pbest[g];
    }
    if (Significant(gcost, reference, o.tolerance)) {
      reference = gcost;
      stall = 0;
    } else {
      ++stall;
    }
    if (o.converged_spread > 0) {
      spread = 0;
      for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < d; ++k) spread = std::max(spread, std::abs(x[i][k] - gbest[k]));
    }
    ++run.iterations;
    run.Record(repetition, iteration, gcost);
  }
  RepetitionResult r;
  r.best_unit = gbest;
  r.best_cost = gcost;
  r.stop_reason = reason;
  return r;
}

RepetitionResult RunGaReal(Run& run, int repetition) {
  const RealGaOptions& o = run.options.ga_real;
  const size_t d = run.box.size();
  const int n = o.population;
  const int elite = static_cast<int>(std::lround(n * o.elite_fraction));
  const double rep_start = NowSeconds();
  Rng rng(o.seed + static_cast<uint64_t>(repetition));
  const BernoulliThreshold cross(o.crossover_probability), mutate(o.mutation_probability);

  std::vector<std::vector<double>> pop(n, std::vector<double>(d));
  for (auto& ind : pop) {
    for (double& xk : ind) xk = rng.Uniform01();
  }
  std::vector<double> cost;
  run.EvaluateUnit(pop, cost);
  // Ranks pop/cost by (cost, index).
  auto rank = [&](std::vector<std::vector<double>>& p, std::vector<double>& c) {
    std::vector<int> order(p.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&c](int a, int b) { return c[a] < c[b]; });
    std::vector<std::vector<double>> p2(p.size());
    std::vector<double> c2(p.size());
    for (size_t r = 0; r < order.size(); ++r) {
      p2[r] = std::move(p[order[r]]);
      c2[r] = c[order[r]];
    }
    p = std::move(p2);
    c = std::move(c2);
  };
  rank(pop, cost);
  double reference = cost[0];
  int stall = 0, generation = 0;
  run.Record(repetition, 0, cost[0]);
  auto tournament = [&]() {
    uint64_t w = rng.UniformBelow(static_cast<uint64_t>(n));
    for (int k = 1; k < o.tournament; ++k)
      w = std::min(w, rng.UniformBelow(static_cast<uint64_t>(n)));
    return static_cast<int>(w);  // ranked population: the lowest index is the best
  };
  std::string reason;
  while ((reason = run.Stop(generation, o.generations, stall, o.stall_generations, o.tolerance,
                            cost[0], rep_start, "generations"))
             .empty()) {
    ++generation;
    const int n_off = n - elite;
    const double sigma = o.generations <= 1 || o.mutation_sigma_end == 0
                             ? o.mutation_sigma
                             : o.mutation_sigma * std::pow(o.mutation_sigma_end / o.mutation_sigma,
                                                           static_cast<double>(generation - 1) /
                                                               (o.generations - 1));
    std::vector<std::vector<double>> off(n_off);
    for (int c = 0; c < n_off; c += 2) {
      const std::vector<double>& pa = pop[tournament()];
      const std::vector<double>& pb = pop[tournament()];
      std::vector<double> c1 = pa, c2 = pb;
      if (rng.Bernoulli(cross)) {
        for (size_t k = 0; k < d; ++k) {
          const double a = pa[k], b = pb[k];
          if (o.crossover == RealCrossover::kSbx) {
            const double u = rng.Uniform01();
            const double e = 1.0 / (o.sbx_eta + 1.0);
            const double beta = u <= 0.5 ? std::pow(2 * u, e) : std::pow(1.0 / (2 * (1 - u)), e);
            c1[k] = 0.5 * ((1 + beta) * a + (1 - beta) * b);
            c2[k] = 0.5 * ((1 - beta) * a + (1 + beta) * b);
          } else {
            const double lo = std::min(a, b), hi = std::max(a, b), ext = o.blx_alpha * (hi - lo);
            c1[k] = lo - ext + rng.Uniform01() * (hi - lo + 2 * ext);
            c2[k] = lo - ext + rng.Uniform01() * (hi - lo + 2 * ext);
          }
        }
      }
      for (std::vector<double>* child : {&c1, &c2}) {
        for (double& xk : *child) {
          if (rng.Bernoulli(mutate)) xk += sigma * Gaussian(rng);
          xk = Reflect(xk);
        }
      }
      off[c] = std::move(c1);
      if (c + 1 < n_off) off[c + 1] = std::move(c2);  // an odd last child is dropped
    }
    std::vector<double> off_cost;
    run.EvaluateUnit(off, off_cost);
    pop.resize(elite);
    cost.resize(elite);
    for (int c = 0; c < n_off; ++c) {
      pop.push_back(std::move(off[c]));
      cost.push_back(off_cost[c]);
    }
    rank(pop, cost);
    if (Significant(cost[0], reference, o.tolerance)) {
      reference = cost[0];
      stall = 0;
    } else {
      ++stall;
    }
    ++run.iterations;
    run.Record(repetition, generation, cost[0]);
  }
  RepetitionResult r;
  r.best_unit = pop[0];
  r.best_cost = cost[0];
  r.stop_reason = reason;
  return r;
}

// The binary GA's evaluator: decodes bits to physical reals and forwards to the user's evaluator.
class DecodingEvaluator final : public BatchEvaluator {
 public:
  DecodingEvaluator(Run& run, int bits, bool gray) : run_(run), bits_(bits), gray_(gray) {}
  void Evaluate(const EvalBatch& batch, std::span<FitnessResult> out) override {
    const size_t d = run_.box.size();
    std::vector<Genome> decoded(batch.genomes.size());
    std::vector<double> unit(d);
    for (size_t i = 0; i < decoded.size(); ++i) {
      PZ_CHECK(batch.genomes[i].bits.size() == d * static_cast<size_t>(bits_));
      DecodeBits(batch.genomes[i].bits.data(), d, bits_, gray_, unit.data());
      decoded[i].reals.resize(d);
      run_.box.ToPhysical(unit.data(), decoded[i].reals.data());
    }
    std::vector<double> cost;
    run_.EvaluatePhysical(decoded, cost);
    for (size_t i = 0; i < out.size(); ++i) out[i] = FitnessResult{cost[i], FitnessStatus::kOk, {}};
  }
  int concurrency() const override { return run_.evaluator.concurrency(); }

 private:
  Run& run_;
  int bits_;
  bool gray_;
};

RepetitionResult RunGaBinary(Run& run, int repetition) {
  const BinaryGaOptions& o = run.options.ga_binary;
  const size_t d = run.box.size();
  const double rep_start = NowSeconds();
  GaOptions ga = o.ga;
  ga.genome_bits = static_cast<int>(d) * o.bits_per_parameter;
  ga.seed = o.ga.seed + static_cast<uint64_t>(repetition);
  ga.error_cost = run.options.error_cost;
  ga.target_cost = std::max(ga.target_cost, run.options.target_cost);
  DecodingEvaluator decoding(run, o.bits_per_parameter, o.gray_code);
  GeneticAlgorithm algorithm(ga, &decoding);
  algorithm.Initialize();
  run.Record(repetition, 0, algorithm.state().best_fitness.cost);
  std::string reason;
  for (;;) {
    if (std::optional<GaTermination> t = algorithm.CheckTermination()) {
      reason = algorithm.MakeSummary(*t).message;
      break;
    }
    if (run.options.max_wall_time_s > 0 &&
        NowSeconds() - rep_start >= run.options.max_wall_time_s) {
      std::ostringstream os;
      os << "time: " << run.options.max_wall_time_s << " s";
      reason = os.str();
      break;
    }
    algorithm.Step();
    ++run.iterations;
    run.Record(repetition, static_cast<int>(algorithm.state().generation),
               algorithm.state().best_fitness.cost);
  }
  RepetitionResult r;
  std::vector<double> unit(d);
  DecodeBits(algorithm.state().best.bits.data(), d, o.bits_per_parameter, o.gray_code, unit.data());
  r.best_unit = unit;
  r.best_cost = algorithm.state().best_fitness.cost;
  r.stop_reason = reason;
  return r;
}

RepetitionResult RunDe(Run& run, int repetition) {
  // DE/rand-to-best/1/bin: trial = x + F (best − x) + F (x_r1 − x_r2) on the crossed coordinates
  // (at least one), a coordinate leaving the box put between the parent and that bound; the trial
  // replaces its parent when not worse. The seeds take the first slots of the initial population.
  const DeOptions& o = run.options.de;
  const size_t d = run.box.size();
  const int np = o.population, dim = static_cast<int>(d);
  const double rep_start = NowSeconds();
  Rng rng(o.seed + static_cast<uint64_t>(repetition));
  std::vector<std::vector<double>> pop(np, std::vector<double>(d));
  const auto& seeds = run.options.seeds;
  for (int i = 0; i < np; ++i) {
    if (i < static_cast<int>(seeds.size())) {
      for (size_t k = 0; k < d; ++k) pop[i][k] = std::clamp(seeds[i][k], 0.0, 1.0);
    } else {
      for (size_t k = 0; k < d; ++k) pop[i][k] = rng.Uniform01();
    }
  }
  std::vector<double> cost, tcost;
  run.EvaluateUnit(pop, cost);
  int best = ArgMin(cost);
  double reference = cost[best];
  int stall = 0, generation = 0;
  run.Record(repetition, 0, cost[best]);
  std::vector<std::vector<double>> trial(np, std::vector<double>(d));
  std::string reason;
  while ((reason = run.Stop(generation, o.generations, stall, o.stall_generations, o.tolerance,
                            cost[best], rep_start, "generations"))
             .empty()) {
    ++generation;
    for (int i = 0; i < np; ++i) {
      int r1, r2;
      do r1 = static_cast<int>(rng.UniformBelow(np));
      while (r1 == i);
      do r2 = static_cast<int>(rng.UniformBelow(np));
      while (r2 == i || r2 == r1);
      const int jr = static_cast<int>(rng.UniformBelow(dim));
      for (int k = 0; k < dim; ++k) {
        const double xi = pop[i][k];
        const bool cross = rng.Uniform01() < o.cr || k == jr;
        double v = xi;
        if (cross) {
          v = xi + o.f * (pop[best][k] - xi) + o.f * (pop[r1][k] - pop[r2][k]);
          if (v < 0) v = xi * rng.Uniform01();
          if (v > 1) v = xi + (1 - xi) * rng.Uniform01();
        }
        trial[i][k] = v;
      }
    }
    run.EvaluateUnit(trial, tcost);
    for (int i = 0; i < np; ++i) {
      if (tcost[i] <= cost[i]) {
        pop[i] = trial[i];
        cost[i] = tcost[i];
      }
    }
    best = ArgMin(cost);
    if (reference - cost[best] >
        o.tolerance * std::abs(reference)) {  // (the rule of Significant, as
      reference = cost[best];                 // the fin's seeded fits ran it)
      stall = 0;
    } else {
      ++stall;
    }
    ++run.iterations;
    run.Record(repetition, generation, cost[best]);
  }
  RepetitionResult r;
  r.best_unit = pop[best];
  r.best_cost = cost[best];
  r.stop_reason = reason;
  return r;
}

/// Brent's minimisation of one bracket [a, b] around its lowest point x (R. P. Brent, Algorithms
/// for Minimization without Derivatives, 1973, ch. 5: the procedure `localmin`), as a state machine
/// that proposes one point at a time (Propose) and is told its cost (Tell), so that several
/// brackets can advance side by side. It starts from evaluated points: x (the grid's minimum) and
/// its two neighbours as w and v, with the first step allowed to be the parabola through them.
class BrentBracket {
 public:
  BrentBracket(double a, double b, double x, double fx, double w, double fw, double v, double fv,
               double tol)
      : a_(a),
        b_(b),
        x_(x),
        w_(w),
        v_(v),
        fx_(fx),
        fw_(fw),
        fv_(fv),
        d_(b - a),
        e_(b - a),
        tol_(tol) {}

  /// The next point to evaluate, or nothing once x is located within the tolerance.
  std::optional<double> Propose() {
    constexpr double kGolden = 0.3819660112501051;   // (3 − √5) / 2
    constexpr double kEps = 1.4901161193847656e-08;  // √(machine ε)
    const double xm = 0.5 * (a_ + b_);
    const double tol1 = kEps * std::abs(x_) + tol_ / 3, tol2 = 2 * tol1;
    if (std::abs(x_ - xm) <= tol2 - 0.5 * (b_ - a_)) return std::nullopt;
    bool golden = true;
    if (std::abs(e_) > tol1) {  // the parabola through x, w, v
      double r = (x_ - w_) * (fx_ - fv_);
      double q = (x_ - v_) * (fx_ - fw_);
      double p = (x_ - v_) * q - (x_ - w_) * r;
      q = 2 * (q - r);
      if (q > 0) p = -p;
      q = std::abs(q);
      r = e_;
      e_ = d_;
      if (std::abs(p) < std::abs(0.5 * q * r) && p > q * (a_ - x_) && p < q * (b_ - x_)) {
        d_ = p / q;
        const double u = x_ + d_;
        if (u - a_ < tol2 || b_ - u < tol2) d_ = xm >= x_ ? tol1 : -tol1;
        golden = false;
      }
    }
    if (golden) {
      e_ = x_ >= xm ? a_ - x_ : b_ - x_;
      d_ = kGolden * e_;
    }
    u_ = std::abs(d_) >= tol1 ? x_ + d_ : x_ + (d_ >= 0 ? tol1 : -tol1);
    u_ = std::clamp(u_, a_, b_);
    return u_;
  }

  void Tell(double fu) {
    if (fu <= fx_) {
      (u_ >= x_ ? a_ : b_) = x_;
      v_ = w_;
      fv_ = fw_;
      w_ = x_;
      fw_ = fx_;
      x_ = u_;
      fx_ = fu;
    } else {
      (u_ < x_ ? a_ : b_) = u_;
      if (fu <= fw_ || w_ == x_) {
        v_ = w_;
        fv_ = fw_;
        w_ = u_;
        fw_ = fu;
      } else if (fu <= fv_ || v_ == x_ || v_ == w_) {
        v_ = u_;
        fv_ = fu;
      }
    }
    ++steps_;
  }

  double x() const { return x_; }
  double fx() const { return fx_; }
  int steps() const { return steps_; }

 private:
  double a_, b_, x_, w_, v_, fx_, fw_, fv_, d_, e_, u_ = 0;
  double tol_;
  int steps_ = 0;
};

RepetitionResult RunLine(Run& run, int repetition) {
  // The grid, one batch: the unit interval's `grid` points, ends included.
  const LineOptions& o = run.options.line;
  const int g = o.grid;
  std::vector<std::vector<double>> points(static_cast<size_t>(g), std::vector<double>(1));
  for (int i = 0; i < g; ++i) points[static_cast<size_t>(i)][0] = static_cast<double>(i) / (g - 1);
  std::vector<double> cost;
  run.EvaluateUnit(points, cost);
  auto at = [&](int i) { return points[static_cast<size_t>(i)][0]; };
  auto c = [&](int i) { return cost[static_cast<size_t>(i)]; };
  int best = ArgMin(cost);
  double best_u = at(best), best_cost = c(best);
  run.Record(repetition, 0, best_cost);
  // The grid's local minima (not above the right neighbour, below the left one: a plateau counts
  // once), lowest first (ties: the lower index).
  std::vector<int> minima;
  for (int i = 0; i < g; ++i)
    if ((i == 0 || c(i) < c(i - 1)) && (i == g - 1 || c(i) <= c(i + 1))) minima.push_back(i);
  std::stable_sort(minima.begin(), minima.end(), [&](int x, int y) { return c(x) < c(y); });
  if (static_cast<int>(minima.size()) > o.brackets) minima.resize(static_cast<size_t>(o.brackets));
  std::vector<BrentBracket> brackets;
  for (int i : minima) {
    const int lo = std::max(i - 1, 0), hi = std::min(i + 1, g - 1);
    // w: the lower neighbour, v: the other (at an end of the grid, the one neighbour twice).
    int w = lo == i ? hi : hi == i ? lo : (c(hi) < c(lo) ? hi : lo);
    int v = w == lo ? hi : lo;
    if (v == i) v = w;
    brackets.emplace_back(at(lo), at(hi), at(i), c(i), at(w), c(w), at(v), c(v), o.tolerance);
  }
  // Brent's steps, the brackets side by side: one batch of the points of those still refining.
  std::vector<char> done(brackets.size(), 0), capped(brackets.size(), 0);
  std::vector<size_t> active;
  std::string reason;
  for (int step = 1;; ++step) {
    points.clear();
    active.clear();
    for (size_t k = 0; k < brackets.size(); ++k) {
      if (done[k]) continue;
      if (brackets[k].steps() >= o.max_steps) {
        done[k] = capped[k] = 1;
        continue;
      }
      const std::optional<double> u = brackets[k].Propose();
      if (!u) {
        done[k] = 1;
        continue;
      }
      points.push_back({*u});
      active.push_back(k);
    }
    if (points.empty()) break;
    run.EvaluateUnit(points, cost);
    for (size_t j = 0; j < active.size(); ++j) {
      brackets[active[j]].Tell(cost[j]);
      if (cost[j] < best_cost) {
        best_cost = cost[j];
        best_u = points[j][0];
      }
    }
    ++run.iterations;
    run.Record(repetition, step, best_cost);
    if (best_cost <= run.options.target_cost) {
      std::ostringstream os;
      os.precision(10);
      os << "target: best cost " << best_cost << " <= " << run.options.target_cost;
      reason = os.str();
      break;
    }
  }
  if (reason.empty()) {
    std::ostringstream os;
    os << "grid of " << g << ", " << brackets.size()
       << (brackets.size() == 1 ? " local minimum" : " local minima")
       << " refined by Brent's method (";
    for (size_t k = 0; k < brackets.size(); ++k) {
      os << (k > 0 ? ", " : "") << brackets[k].steps() << " steps"
         << (capped[k] ? " (the limit)" : "");
    }
    os << ") to " << o.tolerance << " of the range";
    reason = os.str();
  }
  RepetitionResult r;
  r.best_unit = {best_u};
  r.best_cost = best_cost;
  r.stop_reason = reason;
  return r;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Box and options

Status ParamBox::Validate() const {
  const size_t d = names.size();
  if (d == 0) return InvalidArgument("box.names: empty, the box needs at least one parameter");
  if (lower.size() != d) {
    return InvalidArgument(FieldError("box.lower.size()", lower.size(),
                                      "must equal box.names.size() = " + std::to_string(d)));
  }
  if (upper.size() != d) {
    return InvalidArgument(FieldError("box.upper.size()", upper.size(),
                                      "must equal box.names.size() = " + std::to_string(d)));
  }
  if (!log_scale.empty() && log_scale.size() != d) {
    return InvalidArgument(FieldError("box.log_scale.size()", log_scale.size(),
                                      "must be 0 or box.names.size() = " + std::to_string(d)));
  }
  std::set<std::string> seen;
  for (size_t i = 0; i < d; ++i) {
    const std::string at = "[" + std::to_string(i) + "] (" + names[i] + ")";
    if (names[i].empty())
      return InvalidArgument("box.names[" + std::to_string(i) + "]: empty name");
    if (!seen.insert(names[i]).second) {
      return InvalidArgument("box.names[" + std::to_string(i) + "] = " + names[i] +
                             ": duplicate name");
    }
    if (!std::isfinite(lower[i]))
      return InvalidArgument(FieldError("box.lower" + at, lower[i], "must be finite"));
    if (!std::isfinite(upper[i]) || !(upper[i] > lower[i])) {
      return InvalidArgument(
          FieldError("box.upper" + at, upper[i], "must be finite and > lower = " + Num(lower[i])));
    }
    if (!log_scale.empty() && log_scale[i] && !(lower[i] > 0)) {
      return InvalidArgument(
          FieldError("box.lower" + at, lower[i], "must be > 0 for a log-scaled parameter"));
    }
  }
  return Status::Ok();
}

void ParamBox::ToPhysical(const double* unit, double* physical) const {
  for (size_t i = 0; i < names.size(); ++i) {
    const double x = std::clamp(unit[i], 0.0, 1.0);
    double p;
    if (!log_scale.empty() && log_scale[i]) {
      const double a = std::log10(lower[i]), b = std::log10(upper[i]);
      p = std::pow(10.0, a + x * (b - a));
    } else {
      p = lower[i] + x * (upper[i] - lower[i]);
    }
    physical[i] = std::clamp(p, lower[i], upper[i]);
  }
}

void ParamBox::ToUnit(const double* physical, double* unit) const {
  for (size_t i = 0; i < names.size(); ++i) {
    double x;
    if (!log_scale.empty() && log_scale[i]) {
      const double a = std::log10(lower[i]), b = std::log10(upper[i]);
      x = physical[i] > 0 ? (std::log10(physical[i]) - a) / (b - a) : 0.0;
    } else {
      x = (physical[i] - lower[i]) / (upper[i] - lower[i]);
    }
    unit[i] = std::clamp(x, 0.0, 1.0);
  }
}

const char* SearchAlgorithmName(SearchAlgorithm a) {
  switch (a) {
    case SearchAlgorithm::kPso:
      return "pso";
    case SearchAlgorithm::kGaReal:
      return "ga-real";
    case SearchAlgorithm::kGaBinary:
      return "ga-binary";
    case SearchAlgorithm::kDe:
      return "de";
    case SearchAlgorithm::kLine:
      return "line";
  }
  return "unknown";
}

SearchAlgorithm ParseSearchAlgorithm(const std::string& name) {
  if (name == "pso") return SearchAlgorithm::kPso;
  if (name == "ga-real") return SearchAlgorithm::kGaReal;
  if (name == "ga-binary") return SearchAlgorithm::kGaBinary;
  if (name == "de") return SearchAlgorithm::kDe;
  if (name == "line") return SearchAlgorithm::kLine;
  throw InputError("algorithm = " + name + ": must be pso, ga-real, ga-binary, de or line");
}

Status DeOptions::Validate() const {
  if (population < 4)
    return InvalidArgument(FieldError("de.population", population, "must be >= 4"));
  if (generations < 0)
    return InvalidArgument(FieldError("de.generations", generations, "must be >= 0"));
  if (stall_generations < 0)
    return InvalidArgument(
        FieldError("de.stall_generations", stall_generations, "must be >= 0 (0 = never)"));
  if (!(tolerance >= 0))
    return InvalidArgument(FieldError("de.tolerance", tolerance, "must be >= 0"));
  if (!(f > 0 && f <= 2)) return InvalidArgument(FieldError("de.f", f, "must be in (0, 2]"));
  if (!(cr >= 0 && cr <= 1)) return InvalidArgument(FieldError("de.cr", cr, "must be in [0, 1]"));
  return Status::Ok();
}

Status LineOptions::Validate() const {
  if (grid < 3) return InvalidArgument(FieldError("line.grid", grid, "must be >= 3"));
  if (brackets < 1) return InvalidArgument(FieldError("line.brackets", brackets, "must be >= 1"));
  if (!(tolerance > 0 && tolerance < 0.5))
    return InvalidArgument(FieldError("line.tolerance", tolerance, "must be in (0, 0.5)"));
  if (max_steps < 1)
    return InvalidArgument(FieldError("line.max_steps", max_steps, "must be >= 1"));
  return Status::Ok();
}

std::string LineOptions::Describe() const {
  std::ostringstream os;
  os << "a grid of " << grid << " points, then the lowest ";
  if (brackets > 1) os << brackets << " ";
  os << "of its local minima refined by Brent's method to " << tolerance << " of the range";
  return os.str();
}

Status PsoOptions::Validate() const {
  const std::string p = "pso";
  if (particles < 2) return Field(p, "particles", particles, "must be >= 2");
  if (iterations < 0) return Field(p, "iterations", iterations, "must be >= 0");
  for (Status s : {CheckNonNegativeFinite(p, "inertia_start", inertia_start),
                   CheckNonNegativeFinite(p, "inertia_end", inertia_end),
                   CheckNonNegativeFinite(p, "cognitive", cognitive),
                   CheckNonNegativeFinite(p, "social", social),
                   CheckNonNegativeFinite(p, "tolerance", tolerance)}) {
    if (!s.ok()) return s;
  }
  if (!(velocity_clamp > 0 && velocity_clamp <= 1)) {
    return Field(p, "velocity_clamp", velocity_clamp,
                 "must be in (0, 1] (a fraction of the unit box)");
  }
  if (stall_iterations < 0)
    return Field(p, "stall_iterations", stall_iterations, "must be >= 0 (0 = never)");
  if (!(converged_spread >= 0 && converged_spread < 1))
    return Field(p, "converged_spread", converged_spread, "must be in [0, 1) (0 = never)");
  return Status::Ok();
}

Status RealGaOptions::Validate() const {
  const std::string p = "ga_real";
  if (population < 2) return Field(p, "population", population, "must be >= 2");
  if (generations < 0) return Field(p, "generations", generations, "must be >= 0");
  if (!(elite_fraction >= 0 && elite_fraction < 1))
    return Field(p, "elite_fraction", elite_fraction, "must be in [0, 1)");
  const long e = std::lround(population * elite_fraction);
  if (e < 1 || e > population - 1) {
    return InvalidArgument(FieldError(p + ".elite_fraction", elite_fraction,
                                      "round(population * elite_fraction) = " + std::to_string(e) +
                                          " must be 1 … population − 1"));
  }
  if (tournament < 1) return Field(p, "tournament", tournament, "must be >= 1");
  for (Status s : {CheckProbability(p, "crossover_probability", crossover_probability),
                   CheckProbability(p, "mutation_probability", mutation_probability),
                   CheckNonNegativeFinite(p, "blx_alpha", blx_alpha),
                   CheckNonNegativeFinite(p, "tolerance", tolerance)}) {
    if (!s.ok()) return s;
  }
  if (!(std::isfinite(sbx_eta) && sbx_eta > 0))
    return Field(p, "sbx_eta", sbx_eta, "must be finite and > 0");
  if (!(std::isfinite(mutation_sigma) && mutation_sigma > 0)) {
    return Field(p, "mutation_sigma", mutation_sigma, "must be finite and > 0");
  }
  if (!(std::isfinite(mutation_sigma_end) && mutation_sigma_end >= 0 &&
        mutation_sigma_end <= mutation_sigma)) {
    return InvalidArgument(FieldError(
        p + ".mutation_sigma_end", mutation_sigma_end,
        "must be 0 (constant step) or in (0, mutation_sigma = " + Num(mutation_sigma) + "]"));
  }
  if (stall_generations < 0)
    return Field(p, "stall_generations", stall_generations, "must be >= 0 (0 = never)");
  return Status::Ok();
}

Status BinaryGaOptions::Validate(size_t parameters) const {
  if (bits_per_parameter < 2 || bits_per_parameter > 52) {
    return InvalidArgument(
        FieldError("ga_binary.bits_per_parameter", bits_per_parameter, "must be in 2 … 52"));
  }
  if (parameters * static_cast<size_t>(bits_per_parameter) < 3) {
    return InvalidArgument(FieldError("ga_binary.bits_per_parameter", bits_per_parameter,
                                      "the genome (bits × parameters) needs at least 3 bits"));
  }
  GaOptions ga_checked = ga;
  ga_checked.genome_bits = static_cast<int>(parameters) * bits_per_parameter;
  Status s = ga_checked.Validate();
  if (!s.ok()) return InvalidArgument("ga_binary.ga." + s.message());
  return Status::Ok();
}

Status SearchOptions::Validate(const ParamBox& box) const {
  Status s = box.Validate();
  if (!s.ok()) return s;
  switch (algorithm) {
    case SearchAlgorithm::kPso:
      s = pso.Validate();
      break;
    case SearchAlgorithm::kGaReal:
      s = ga_real.Validate();
      break;
    case SearchAlgorithm::kGaBinary:
      s = ga_binary.Validate(box.size());
      break;
    case SearchAlgorithm::kDe:
      s = de.Validate();
      break;
    case SearchAlgorithm::kLine:
      s = line.Validate();
      if (s.ok() && box.size() != 1)
        s = InvalidArgument(
            FieldError("algorithm", "line",
                       "searches one parameter; the box has " + std::to_string(box.size())));
      if (s.ok() && repetitions != 1)
        s = InvalidArgument(FieldError("repetitions", repetitions,
                                       "must be 1 for the line search (it has no random choice)"));
      break;
  }
  if (!s.ok()) return s;
  if (!seeds.empty() && algorithm != SearchAlgorithm::kDe)
    return InvalidArgument(
        FieldError("seeds.size()", seeds.size(), "must be 0: only the de search takes seeds"));
  for (size_t i = 0; i < seeds.size(); ++i) {
    if (seeds[i].size() != box.size())
      return InvalidArgument(FieldError("seeds[" + std::to_string(i) + "].size()", seeds[i].size(),
                                        "must be " + std::to_string(box.size())));
  }
  if (repetitions < 1)
    return InvalidArgument(FieldError("repetitions", repetitions, "must be >= 1"));
  if (std::isnan(target_cost))
    return InvalidArgument(FieldError("target_cost", target_cost, "must not be NaN"));
  if (!(std::isfinite(max_wall_time_s) && max_wall_time_s >= 0)) {
    return InvalidArgument(
        FieldError("max_wall_time_s", max_wall_time_s, "must be finite and >= 0 (0 = none)"));
  }
  if (!std::isfinite(error_cost))
    return InvalidArgument(FieldError("error_cost", error_cost, "must be finite"));
  return Status::Ok();
}

void DecodeBits(const uint8_t* bits, size_t parameters, int bits_per_parameter, bool gray_code,
                double* unit) {
  const double scale = std::ldexp(1.0, bits_per_parameter) - 1.0;
  for (size_t p = 0; p < parameters; ++p) {
    uint64_t code = 0, prev = 0;
    for (int b = 0; b < bits_per_parameter; ++b) {
      uint64_t bit = bits[p * bits_per_parameter + b] & 1u;
      if (gray_code) {
        bit ^= prev;  // binary bit = gray bit XOR previous binary bit
        prev = bit;
      }
      code = (code << 1) | bit;
    }
    unit[p] = static_cast<double>(code) / scale;
  }
}

// ---------------------------------------------------------------------------------------------
// Search

SearchResult Search(const ParamBox& box, const SearchOptions& options, BatchEvaluator& evaluator) {
  ThrowIfError(options.Validate(box));
  Run run(box, options, evaluator);
  SearchResult result;
  result.best_cost = std::numeric_limits<double>::infinity();
  for (int rep = 0; rep < options.repetitions; ++rep) {
    RepetitionResult r;
    switch (options.algorithm) {
      case SearchAlgorithm::kPso:
        r = RunPso(run, rep);
        break;
      case SearchAlgorithm::kGaReal:
        r = RunGaReal(run, rep);
        break;
      case SearchAlgorithm::kGaBinary:
        r = RunGaBinary(run, rep);
        break;
      case SearchAlgorithm::kDe:
        r = RunDe(run, rep);
        break;
      case SearchAlgorithm::kLine:
        r = RunLine(run, rep);
        break;
    }
    std::vector<double> physical(box.size());
    box.ToPhysical(r.best_unit.data(), physical.data());
    result.repetition_costs.push_back(r.best_cost);
    result.repetition_best.push_back(physical);
    if (r.best_cost < result.best_cost || rep == 0) {
      result.best_cost = r.best_cost;
      result.best = physical;
      result.best_repetition = rep;
      result.stop_reason = r.stop_reason;
    }
  }
  result.evaluations = run.evaluations;
  result.iterations = run.iterations;
  result.trace = std::move(run.trace);
  result.wall_time_s = NowSeconds() - run.start_s;
  return result;
}

}  // namespace pz::opt
