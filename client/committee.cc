#include "client/committee.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "client/plots.h"
#include "io/csv.h"
#include "opt/inline_evaluator.h"
#include "opt/thread_pool_evaluator.h"
#include "model/criteria.h"

namespace pz::client {
namespace {

using model::StackFamily;

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Samples k with t0 ≤ k dt ≤ t1 (as model/criteria.h counts them).
size_t WindowCount(size_t n, double dt, double t0, double t1) {
  double f = std::ceil(t0 / dt);
  if (f * dt < t0) f += 1;
  double l = std::floor(t1 / dt);
  if (l * dt > t1) l -= 1;
  l = std::min(l, static_cast<double>(n - 1));
  return l >= f ? static_cast<size_t>(l - f + 1) : 0;
}

// Accumulates RoleMetrics with the pooled squared error.
struct Pool {
  RoleMetrics m;
  double sse = 0;
  void Add(const RoleMetrics& one, double one_sse) {
    m.records += one.records;
    m.samples += one.samples;
    m.iae += one.iae;
    m.max_abs = std::max(m.max_abs, one.max_abs);
    sse += one_sse;
  }
  RoleMetrics Done() const {
    RoleMetrics r = m;
    r.rmse = r.samples ? std::sqrt(sse / static_cast<double>(r.samples)) : 0;
    return r;
  }
};

struct RecordError {
  RoleMetrics m;
  double sse = 0;
};

RecordError Errors(const io::StackRecord& r, std::span<const double> yhat, double t0, double t1) {
  const double end = complete::WindowEnd(r, t1), dt = r.dt();
  RecordError e;
  e.m.records = 1;
  e.m.samples = WindowCount(r.t.size(), dt, t0, end);
  e.m.iae = model::Iae(r.y, yhat, dt, t0, end);
  e.sse = model::Sse(r.y, yhat, dt, t0, end);
  e.m.rmse = std::sqrt(e.sse / static_cast<double>(std::max<size_t>(e.m.samples, 1)));
  e.m.max_abs = model::MaxAbsError(r.y, yhat, dt, t0, end);
  return e;
}

std::string Fmt(double x, int precision = 3) {
  if (!std::isfinite(x)) return "—";
  std::ostringstream os;
  const double a = std::abs(x);
  if (a != 0 && (a < 1e-3 || a >= 1e5))
    os << std::scientific << std::setprecision(precision - 1) << x;
  else
    os << std::setprecision(precision) << x;
  return os.str();
}

std::string Pct(double x) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(2) << 100 * x << " %";
  return os.str();
}

// Triangular memberships over the band centres (a partition of unity).
std::vector<double> Memberships(const FrequencyBands& bands, double f) {
  const int nb = bands.size();
  std::vector<double> mu(nb, 0.0);
  std::vector<double> c(nb);
  for (int b = 0; b < nb; ++b) c[b] = 0.5 * (bands.edges[b] + bands.edges[b + 1]);
  if (f <= c[0]) {
    mu[0] = 1;
  } else if (f >= c[nb - 1]) {
    mu[nb - 1] = 1;
  } else {
    for (int b = 0; b + 1 < nb; ++b)
      if (f >= c[b] && f <= c[b + 1]) {
        const double w = (f - c[b]) / (c[b + 1] - c[b]);
        mu[b] = 1 - w;
        mu[b + 1] = w;
        break;
      }
  }
  return mu;
}

}  // namespace

// ---- Bands ---------------------------------------------------------------------------------

int FrequencyBands::BandOf(double f) const {
  for (int b = 0; b < size(); ++b) {
    const bool last = b + 1 == size();
    if (f >= edges[b] && (f < edges[b + 1] || (last && f == edges[b + 1]))) return b;
  }
  return -1;
}

std::string FrequencyBands::Label(int band) const {
  return io::FormatNumber(edges[band]) + "–" + io::FormatNumber(edges[band + 1]) + " Hz";
}

Status FrequencyBands::Validate() const {
  if (edges.size() < 2)
    return InvalidArgument(FieldError("bands", edges.size(), "need at least 2 edges (one band)"));
  for (size_t i = 0; i < edges.size(); ++i) {
    if (!(std::isfinite(edges[i]) && edges[i] >= 0))
      return InvalidArgument(FieldError("bands edge " + std::to_string(i + 1), edges[i],
                                        "must be finite and >= 0"));
    if (i > 0 && !(edges[i] > edges[i - 1]))
      return InvalidArgument(FieldError("bands edge " + std::to_string(i + 1), edges[i],
                                        "must be > the previous edge " +
                                            io::FormatNumber(edges[i - 1])));
  }
  return Status::Ok();
}

FrequencyBands FrequencyBands::Parse(const std::string& text) {
  // Either edges "0,50,150" or ranges "0-50,50-150" (contiguous).
  FrequencyBands b;
  b.edges.clear();
  std::stringstream ss(text);
  std::string item;
  int index = 0;
  while (std::getline(ss, item, ',')) {
    ++index;
    const size_t dash = item.find('-', 1);
    auto num = [&](const std::string& s) {
      const auto v = io::ParseDouble(s);
      if (!v)
        throw InputError("--bands '" + text + "': item " + std::to_string(index) + " '" + item +
                         "' is not a number or a lo-hi range");
      return *v;
    };
    if (dash == std::string::npos) {
      b.edges.push_back(num(item));
    } else {
      const double lo = num(item.substr(0, dash)), hi = num(item.substr(dash + 1));
      if (b.edges.empty()) {
        b.edges.push_back(lo);
      } else if (lo != b.edges.back()) {
        throw InputError("--bands '" + text + "': range " + std::to_string(index) + " '" + item +
                         "' does not start where the previous one ends (" +
                         io::FormatNumber(b.edges.back()) + ")");
      }
      b.edges.push_back(hi);
    }
  }
  const Status s = b.Validate();
  if (!s.ok()) throw InputError("--bands '" + text + "': " + s.message());
  return b;
}

opt::ParamBox DefaultStackBox(StackFamily family) {
  opt::ParamBox box;
  box.names = model::StackParamNames(family);
  if (family == StackFamily::kBoucWen) {
    box.lower = {0.01, 1e-5, -0.05, 0.02, 100};
    box.upper = {3.0, 0.1, 0.05, 0.08, 20000};
    box.log_scale = {true, true, false, false, true};
  } else {
    box.lower = {1e-4, 0.02, -0.05};
    box.upper = {1.0, 0.08, 0.1};
    box.log_scale = {true, false, false};
  }
  return box;
}

Status CommitteeOptions::Validate() const {
  if (Status s = bands.Validate(); !s.ok()) return s;
  if (families.empty()) return InvalidArgument("families: at least one model family is needed");
  if (algorithms.empty()) return InvalidArgument("optimisers: at least one optimiser is needed");
  for (size_t i = 0; i < families.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (families[i] == families[j])
        return InvalidArgument(std::string("families: ") + model::StackFamilyName(families[i]) +
                               " given twice");
  for (size_t i = 0; i < algorithms.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (algorithms[i] == algorithms[j])
        return InvalidArgument(std::string("optimisers: ") +
                               opt::SearchAlgorithmName(algorithms[i]) + " given twice");
  if (!(std::isfinite(t0_s) && t0_s >= 0))
    return InvalidArgument(FieldError("window t0_s", t0_s, "must be finite and >= 0"));
  if (!(std::isfinite(t1_s) && t1_s > t0_s))
    return InvalidArgument(FieldError("window t1_s", t1_s, "must be finite and > t0_s"));
  if (Status s = sim.Validate(); !s.ok()) return s;
  for (StackFamily f : families) {
    opt::SearchOptions so = search;
    for (opt::SearchAlgorithm a : algorithms) {
      so.algorithm = a;
      if (Status s = so.Validate(DefaultStackBox(f)); !s.ok()) return s;
    }
  }
  return Status::Ok();
}

EvaluatorFactory LocalEvaluatorFactory(int threads) {
  if (threads < 0) throw InputError(FieldError("threads", threads, "must be >= 0"));
  return [threads](const opt::FitnessFunction& f) -> std::unique_ptr<opt::BatchEvaluator> {
    if (threads == 1) return std::make_unique<opt::InlineEvaluator>(f);
    return std::make_unique<opt::ThreadPoolEvaluator>(f, threads);
  };
}

std::string IdentifiedModel::Name() const {
  return std::string(model::StackFamilyName(family)) + "/" + opt::SearchAlgorithmName(algorithm);
}

std::vector<double> PredictModel(const IdentifiedModel& m, const io::StackRecord& record,
                                 const model::StackSimOptions& sim) {
  std::vector<double> y(record.u.size());
  model::SimulateStack(m.family, m.params, record.u, record.dt(), y, sim);
  return y;
}

std::vector<double> PredictCommittee(const CommitteeResult& r, const io::StackRecord& record) {
  const FrequencyBands& bands = r.options.bands;
  if (!r.options.averaging) {
    const int b = bands.BandOf(record.frequency_hz);
    if (b < 0) throw InputError(record.Label() + " is outside every band");
    return PredictModel(r.band_models[b][r.selected[b]], record, r.options.sim);
  }
  const std::vector<double> mu = Memberships(bands, record.frequency_hz);
  std::vector<double> y(record.u.size(), 0.0);
  for (int b = 0; b < bands.size(); ++b) {
    if (mu[b] == 0) continue;
    const auto yb = PredictModel(r.band_models[b][r.selected[b]], record, r.options.sim);
    for (size_t k = 0; k < y.size(); ++k) y[k] += mu[b] * yb[k];
  }
  return y;
}

RoleMetrics RecordMetrics(const io::StackRecord& record, std::span<const double> yhat, double t0_s,
                          double t1_s) {
  return Errors(record, yhat, t0_s, t1_s).m;
}

// ---- The study -----------------------------------------------------------------------------

namespace {

// Errors of a predictor on every band's records, per role, and on all test / train records.
template <typename Predict>
void Score(const io::StackRecordSet& set, const CommitteeOptions& o, Predict predict,
           std::vector<BandMetrics>* per_band, RoleMetrics* all_test, RoleMetrics* all_train) {
  const int nb = o.bands.size();
  std::vector<Pool> train(nb), test(nb);
  Pool at, atr;
  for (const io::StackRecord& r : set.records) {
    const int b = o.bands.BandOf(r.frequency_hz);
    const std::vector<double> y = predict(r);
    const RecordError e = Errors(r, y, o.t0_s, o.t1_s);
    if (r.role == io::CaseRole::kTrain) {
      train[b].Add(e.m, e.sse);
      atr.Add(e.m, e.sse);
    } else {
      test[b].Add(e.m, e.sse);
      at.Add(e.m, e.sse);
    }
  }
  per_band->assign(nb, {});
  for (int b = 0; b < nb; ++b) (*per_band)[b] = {train[b].Done(), test[b].Done()};
  if (all_test) *all_test = at.Done();
  if (all_train) *all_train = atr.Done();
}

}  // namespace

CommitteeResult RunCommittee(const io::StackRecordSet& set, const CommitteeOptions& options,
                             const EvaluatorFactory& factory, const CommitteeLog& log) {
  ThrowIfError(options.Validate());
  const double start = Now();
  const int nb = options.bands.size();
  std::vector<std::vector<const io::StackRecord*>> band_train(nb);
  std::vector<int> band_tests(nb, 0);
  std::vector<const io::StackRecord*> all_train;
  for (const io::StackRecord& r : set.records) {
    const int b = options.bands.BandOf(r.frequency_hz);
    if (b < 0)
      throw InputError(r.Label() + " is outside every band (edges " +
                       [&] {
                         std::string s;
                         for (double e : options.bands.edges)
                           s += (s.empty() ? "" : ",") + io::FormatNumber(e);
                         return s;
                       }() +
                       " Hz)");
    if (r.role == io::CaseRole::kTrain) {
      band_train[b].push_back(&r);
      all_train.push_back(&r);
    } else {
      ++band_tests[b];
    }
  }
  for (int b = 0; b < nb; ++b) {
    if (band_train[b].empty())
      throw InputError("band " + options.bands.Label(b) + " has no training record");
    if (band_tests[b] == 0)
      throw InputError("band " + options.bands.Label(b) + " has no test record");
  }

  CommitteeResult res;
  res.options = options;

  bool first_search = true;
  auto identify = [&](StackFamily family, opt::SearchAlgorithm algo,
                      const std::vector<const io::StackRecord*>& records, int band) {
    IdentifiedModel m;
    m.family = family;
    m.algorithm = algo;
    m.band = band;
    const StackFitness fitness(family, records, options.criterion, options.t0_s, options.t1_s,
                               options.sim, options.search.error_cost);
    auto evaluator = factory(fitness);
    if (first_search) res.threads = evaluator->concurrency();  // as the first search runs
    first_search = false;
    opt::SearchOptions so = options.search;
    so.algorithm = algo;
    m.search = opt::Search(DefaultStackBox(family), so, *evaluator);
    m.params = m.search.best;
    res.evaluations += m.search.evaluations;
    Score(set, options, [&](const io::StackRecord& r) { return PredictModel(m, r, options.sim); },
          &m.per_band, &m.all_test, nullptr);
    if (log) {
      std::ostringstream os;
      os << (band < 0 ? std::string("complete") : options.bands.Label(band)) << " " << m.Name()
         << ": " << FitCriterionName(options.criterion) << " " << Fmt(m.search.best_cost, 5)
         << " after " << m.search.evaluations << " evaluations in " << Fmt(m.search.wall_time_s)
         << " s (" << Fmt(m.search.evaluations / std::max(m.search.wall_time_s, 1e-9))
         << " evaluations/s), best of " << m.search.repetition_costs.size()
         << " repetitions: #" << m.search.best_repetition;
      log(os.str());
    }
    return m;
  };

  if (options.complete) {
    const double t = Now();
    for (StackFamily f : options.families)
      for (opt::SearchAlgorithm a : options.algorithms)
        res.complete.push_back(identify(f, a, all_train, -1));
    res.complete_wall_s = Now() - t;
  }
  res.band_models.resize(nb);
  res.band_wall_s.assign(nb, 0.0);
  res.selected.assign(nb, 0);
  res.aggregate.assign(nb, 0.0);
  for (int b = 0; b < nb; ++b) {
    const double t = Now();
    for (StackFamily f : options.families)
      for (opt::SearchAlgorithm a : options.algorithms)
        res.band_models[b].push_back(identify(f, a, band_train[b], b));
    res.band_wall_s[b] = Now() - t;
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < res.band_models[b].size(); ++i) {
      const BandMetrics& bm = res.band_models[b][i].per_band[b];
      const double agg = 0.5 * (bm.train.rmse + bm.test.rmse);
      if (agg < best) {
        best = agg;
        res.selected[b] = static_cast<int>(i);
      }
    }
    res.aggregate[b] = best;
    if (log)
      log("band " + options.bands.Label(b) + ": selected " +
          res.band_models[b][res.selected[b]].Name() + " (A = " + Fmt(best, 4) + " µm)");
  }
  Score(set, options, [&](const io::StackRecord& r) { return PredictCommittee(res, r); },
        &res.committee_per_band, &res.committee_test, &res.committee_train);
  if (!res.complete.empty()) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < res.complete.size(); ++i)
      if (res.complete[i].all_test.rmse < best) {
        best = res.complete[i].all_test.rmse;
        res.best_complete = static_cast<int>(i);
      }
    const RoleMetrics& c = res.complete[res.best_complete].all_test;
    res.rmse_reduction = 1 - res.committee_test.rmse / c.rmse;
    res.max_reduction = 1 - res.committee_test.max_abs / c.max_abs;
  }
  res.wall_s = Now() - start;
  return res;
}

// ---- Report --------------------------------------------------------------------------------

namespace {

// A markdown table: one row per model, one column per band.
template <typename Value>
void BandTable(std::ostream& o, const std::string& title, const FrequencyBands& bands,
               const std::vector<const IdentifiedModel*>& rows, Value value,
               const std::vector<int>& mark = {}) {
  o << "**" << title << "**\n\n| model / optimiser |";
  for (int b = 0; b < bands.size(); ++b) o << " " << bands.Label(b) << " |";
  o << "\n|---|";
  for (int b = 0; b < bands.size(); ++b) o << "---:|";
  o << "\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    o << "| " << rows[i]->Name() << " |";
    for (int b = 0; b < bands.size(); ++b) {
      const bool m = !mark.empty() && mark[b] == static_cast<int>(i);
      o << " " << (m ? "**" : "") << value(*rows[i], b) << (m ? "**" : "") << " |";
    }
    o << "\n";
  }
  o << "\n";
}

void ParamTable(std::ostream& o, const std::vector<const IdentifiedModel*>& models,
                const FrequencyBands& bands, StackFamily family) {
  const auto names = model::StackParamNames(family);
  o << "| scope | optimiser |";
  for (const auto& n : names) o << " " << n << " |";
  o << " best cost | evaluations | wall [s] | evaluations/s | stop (best repetition) |\n|---|---|";
  for (size_t i = 0; i < names.size(); ++i) o << "---:|";
  o << "---:|---:|---:|---:|---|\n";
  for (const IdentifiedModel* m : models) {
    if (m->family != family) continue;
    o << "| " << (m->band < 0 ? std::string("complete") : bands.Label(m->band)) << " | "
      << opt::SearchAlgorithmName(m->algorithm) << " |";
    for (double p : m->params) o << " " << Fmt(p, 4) << " |";
    o << " " << Fmt(m->search.best_cost, 4) << " | " << m->search.evaluations << " | "
      << Fmt(m->search.wall_time_s) << " | "
      << Fmt(m->search.evaluations / std::max(m->search.wall_time_s, 1e-9)) << " | "
      << m->search.stop_reason << " |\n";
  }
  o << "\n";
}

void MetricTables(std::ostream& o, const std::string& prefix, const FrequencyBands& bands,
                  const std::vector<const IdentifiedModel*>& rows, bool own_band_only,
                  const std::vector<int>& mark) {
  auto at = [&](const IdentifiedModel& m, int b) -> const BandMetrics* {
    if (own_band_only) return m.band == b ? &m.per_band[b] : nullptr;
    return &m.per_band[b];
  };
  auto cell = [&](auto get) {
    return [&, get](const IdentifiedModel& m, int b) -> std::string {
      const BandMetrics* bm = at(m, b);
      return bm ? Fmt(get(*bm)) : "";
    };
  };
  BandTable(o, prefix + ": IAE, training [µm·s]", bands, rows,
            cell([](const BandMetrics& x) { return x.train.iae; }), mark);
  BandTable(o, prefix + ": max error, training [µm]", bands, rows,
            cell([](const BandMetrics& x) { return x.train.max_abs; }), mark);
  BandTable(o, prefix + ": RMSE, training [µm]", bands, rows,
            cell([](const BandMetrics& x) { return x.train.rmse; }), mark);
  BandTable(o, prefix + ": RMSE, testing [µm]", bands, rows,
            cell([](const BandMetrics& x) { return x.test.rmse; }), mark);
  BandTable(o, prefix + ": max error, testing [µm]", bands, rows,
            cell([](const BandMetrics& x) { return x.test.max_abs; }), mark);
  BandTable(o, prefix + ": test/train ratio of the max error", bands, rows,
            cell([](const BandMetrics& x) { return x.test.max_abs / x.train.max_abs; }), mark);
  BandTable(o, prefix + ": test/train ratio of the RMSE", bands, rows,
            cell([](const BandMetrics& x) { return x.test.rmse / x.train.rmse; }), mark);
}

}  // namespace

void WriteCommitteeReport(std::ostream& o, const CommitteeResult& r,
                          const io::StackRecordSet& set) {
  const CommitteeOptions& opt = r.options;
  const FrequencyBands& bands = opt.bands;
  const int nb = bands.size();
  o << "# Committee machine on " << set.dir.filename().string() << "\n\n";
  o << "Records: " << set.records.size() << " (" << set.WithRole(io::CaseRole::kTrain).size()
    << " training, " << set.WithRole(io::CaseRole::kTest).size() << " testing). Bands:";
  for (int b = 0; b < nb; ++b) o << " " << bands.Label(b) << (b + 1 < nb ? "," : ".");
  o << " Criterion " << FitCriterionName(opt.criterion) << " over t ∈ [" << opt.t0_s << ", "
    << opt.t1_s << "] s (clipped to each record's last sample), summed over the training records. "
    << opt.search.repetitions << " repetitions per search (seeds " << opt.search.pso.seed
    << ", … for PSO; " << opt.search.ga_real.seed << ", … for the real GA), best kept. PSO "
    << opt.search.pso.particles << " particles × " << opt.search.pso.iterations
    << " iterations (stall " << opt.search.pso.stall_iterations << "); real GA "
    << opt.search.ga_real.population << " × " << opt.search.ga_real.generations
    << " generations (stall " << opt.search.ga_real.stall_generations << "); binary GA "
    << opt.search.ga_binary.ga.population_size << " × " << opt.search.ga_binary.ga.max_generations
    << ", " << opt.search.ga_binary.bits_per_parameter << " bits/parameter. Bouc–Wen filter "
    << opt.sim.substeps << " sub-step(s) per sample. " << r.threads << " evaluation thread(s).\n\n";
  o << "Selection per band: A = ½ (RMSE_train + RMSE_test) over the window, pooled over the band's "
       "records of each role; lowest A. Committee output: "
    << (opt.averaging ? "averaging (triangular memberships over the band centres)"
                      : "hard switch on the record's excitation frequency")
    << ".\n\n";

  std::vector<const IdentifiedModel*> complete;
  for (const auto& m : r.complete) complete.push_back(&m);
  if (!complete.empty()) {
    o << "## Complete models (one parameter set over all bands; cf. the paper's Tables 1–10)\n\n";
    for (StackFamily f : opt.families) ParamTable(o, complete, bands, f);
    MetricTables(o, "Complete", bands, complete, false, {});
    o << "| complete model | test RMSE, all test records [µm] | test max error [µm] |\n"
         "|---|---:|---:|\n";
    for (const auto* m : complete)
      o << "| " << m->Name() << (m == complete[r.best_complete] ? " (best)" : "") << " | "
        << Fmt(m->all_test.rmse) << " | " << Fmt(m->all_test.max_abs) << " |\n";
    o << "\n";
  }

  o << "## Committee sub-models (one parameter set per band; cf. the paper's Tables 11–16)\n\n";
  std::vector<const IdentifiedModel*> all_band;
  for (const auto& v : r.band_models)
    for (const auto& m : v) all_band.push_back(&m);
  for (StackFamily f : opt.families) ParamTable(o, all_band, bands, f);
  // One row per family/optimiser, the cell of band b from band b's sub-model.
  const size_t per = r.band_models.empty() ? 0 : r.band_models[0].size();
  std::vector<const IdentifiedModel*> rows;
  std::vector<std::vector<const IdentifiedModel*>> cells(per);
  for (size_t i = 0; i < per; ++i) {
    rows.push_back(&r.band_models[0][i]);
    for (int b = 0; b < nb; ++b) cells[i].push_back(&r.band_models[b][i]);
  }
  auto sub = [&](auto get) {
    return [&, get](const IdentifiedModel& m, int b) -> std::string {
      const size_t i = static_cast<size_t>(&m - &r.band_models[0][0]);
      return Fmt(get(cells[i][b]->per_band[b]));
    };
  };
  const std::vector<int>& mark = r.selected;
  BandTable(o, "Committee: IAE, training [µm·s]", bands, rows,
            sub([](const BandMetrics& x) { return x.train.iae; }), mark);
  BandTable(o, "Committee: max error, training [µm]", bands, rows,
            sub([](const BandMetrics& x) { return x.train.max_abs; }), mark);
  BandTable(o, "Committee: RMSE, training [µm]", bands, rows,
            sub([](const BandMetrics& x) { return x.train.rmse; }), mark);
  BandTable(o, "Committee: RMSE, testing [µm]", bands, rows,
            sub([](const BandMetrics& x) { return x.test.rmse; }), mark);
  BandTable(o, "Committee: max error, testing [µm]", bands, rows,
            sub([](const BandMetrics& x) { return x.test.max_abs; }), mark);
  BandTable(o, "Committee: test/train ratio of the max error", bands, rows,
            sub([](const BandMetrics& x) { return x.test.max_abs / x.train.max_abs; }), mark);
  BandTable(o, "Committee: test/train ratio of the RMSE", bands, rows,
            sub([](const BandMetrics& x) { return x.test.rmse / x.train.rmse; }), mark);
  BandTable(o, "Committee: selection aggregate A = ½ (RMSE_train + RMSE_test) [µm] (selected in bold)",
            bands, rows,
            sub([](const BandMetrics& x) { return 0.5 * (x.train.rmse + x.test.rmse); }), mark);

  o << "## Selection and the committee against the complete model\n\n";
  o << "| band | selected | A [µm] | committee test RMSE [µm] | committee test max [µm] |";
  if (r.best_complete >= 0) o << " best complete test RMSE [µm] | best complete test max [µm] | RMSE reduction |";
  o << "\n|---|---|---:|---:|---:|";
  if (r.best_complete >= 0) o << "---:|---:|---:|";
  o << "\n";
  for (int b = 0; b < nb; ++b) {
    const BandMetrics& c = r.committee_per_band[b];
    o << "| " << bands.Label(b) << " | " << r.band_models[b][r.selected[b]].Name() << " | "
      << Fmt(r.aggregate[b]) << " | " << Fmt(c.test.rmse) << " | " << Fmt(c.test.max_abs) << " |";
    if (r.best_complete >= 0) {
      const BandMetrics& x = r.complete[r.best_complete].per_band[b];
      o << " " << Fmt(x.test.rmse) << " | " << Fmt(x.test.max_abs) << " | "
        << Pct(1 - c.test.rmse / x.test.rmse) << " |";
    }
    o << "\n";
  }
  o << "\nAll test records: committee RMSE " << Fmt(r.committee_test.rmse) << " µm, max error "
    << Fmt(r.committee_test.max_abs) << " µm";
  if (r.best_complete >= 0) {
    const RoleMetrics& c = r.complete[r.best_complete].all_test;
    o << "; best complete model (" << r.complete[r.best_complete].Name() << ") RMSE "
      << Fmt(c.rmse) << " µm, max error " << Fmt(c.max_abs) << " µm. **Error reduction of the "
      << "committee: " << Pct(r.rmse_reduction) << " in RMSE, " << Pct(r.max_reduction)
      << " in max error.**";
  }
  o << "\n\n## Timing\n\n| scope | wall [s] | evaluations | evaluations/s |\n|---|---:|---:|---:|\n";
  auto evals = [](const std::vector<IdentifiedModel>& v) {
    int64_t e = 0;
    for (const auto& m : v) e += m.search.evaluations;
    return e;
  };
  if (!r.complete.empty()) {
    const int64_t e = evals(r.complete);
    o << "| complete | " << Fmt(r.complete_wall_s) << " | " << e << " | "
      << Fmt(e / std::max(r.complete_wall_s, 1e-9)) << " |\n";
  }
  for (int b = 0; b < nb; ++b) {
    const int64_t e = evals(r.band_models[b]);
    o << "| " << bands.Label(b) << " | " << Fmt(r.band_wall_s[b]) << " | " << e << " | "
      << Fmt(e / std::max(r.band_wall_s[b], 1e-9)) << " |\n";
  }
  o << "| total | " << Fmt(r.wall_s) << " | " << r.evaluations << " | "
    << Fmt(r.evaluations / std::max(r.wall_s, 1e-9)) << " |\n";
}

// ---- JSON ----------------------------------------------------------------------------------

namespace {

using google::protobuf::ListValue;
using google::protobuf::Struct;
using google::protobuf::Value;

Value Num(double x) {
  Value v;
  if (std::isfinite(x))
    v.set_number_value(x);
  else
    v.set_null_value(google::protobuf::NULL_VALUE);
  return v;
}
Value Text(const std::string& s) {
  Value v;
  v.set_string_value(s);
  return v;
}
Value Obj(const Struct& s) {
  Value v;
  *v.mutable_struct_value() = s;
  return v;
}
Value List(const std::vector<Value>& items) {
  Value v;
  for (const auto& i : items) *v.mutable_list_value()->add_values() = i;
  return v;
}

Value RoleJson(const RoleMetrics& m) {
  Struct s;
  auto& f = *s.mutable_fields();
  f["records"] = Num(m.records);
  f["samples"] = Num(static_cast<double>(m.samples));
  f["iae_um_s"] = Num(m.iae);
  f["rmse_um"] = Num(m.rmse);
  f["max_abs_um"] = Num(m.max_abs);
  return Obj(s);
}

Value ModelJson(const IdentifiedModel& m, const FrequencyBands& bands) {
  Struct s;
  auto& f = *s.mutable_fields();
  f["family"] = Text(model::StackFamilyName(m.family));
  f["optimiser"] = Text(opt::SearchAlgorithmName(m.algorithm));
  f["scope"] = Text(m.band < 0 ? "complete" : bands.Label(m.band));
  Struct p;
  const auto names = model::StackParamNames(m.family);
  for (size_t i = 0; i < names.size(); ++i) (*p.mutable_fields())[names[i]] = Num(m.params[i]);
  f["parameters"] = Obj(p);
  f["best_cost"] = Num(m.search.best_cost);
  f["evaluations"] = Num(static_cast<double>(m.search.evaluations));
  f["wall_time_s"] = Num(m.search.wall_time_s);
  f["stop_reason"] = Text(m.search.stop_reason);
  f["best_repetition"] = Num(m.search.best_repetition);
  std::vector<Value> reps;
  for (double c : m.search.repetition_costs) reps.push_back(Num(c));
  f["repetition_costs"] = List(reps);
  std::vector<Value> per;
  for (int b = 0; b < bands.size(); ++b) {
    if (m.band >= 0 && m.band != b) continue;
    Struct x;
    (*x.mutable_fields())["band"] = Text(bands.Label(b));
    (*x.mutable_fields())["train"] = RoleJson(m.per_band[b].train);
    (*x.mutable_fields())["test"] = RoleJson(m.per_band[b].test);
    per.push_back(Obj(x));
  }
  f["per_band"] = List(per);
  f["all_test"] = RoleJson(m.all_test);
  return Obj(s);
}

}  // namespace

std::string CommitteeJson(const CommitteeResult& r, const io::StackRecordSet& set) {
  const CommitteeOptions& opt = r.options;
  Struct root;
  auto& f = *root.mutable_fields();
  f["records_dir"] = Text(set.dir.filename().string());
  std::vector<Value> edges;
  for (double e : opt.bands.edges) edges.push_back(Num(e));
  f["band_edges_hz"] = List(edges);
  f["criterion"] = Text(FitCriterionName(opt.criterion));
  f["window_s"] = List({Num(opt.t0_s), Num(opt.t1_s)});
  f["repetitions"] = Num(opt.search.repetitions);
  f["committee"] = Text(opt.averaging ? "averaging" : "hard switch");
  f["selection_aggregate"] = Text("0.5 * (rmse_train + rmse_test)");
  std::vector<Value> complete;
  for (const auto& m : r.complete) complete.push_back(ModelJson(m, opt.bands));
  f["complete_models"] = List(complete);
  std::vector<Value> bands;
  for (int b = 0; b < opt.bands.size(); ++b) {
    Struct s;
    auto& g = *s.mutable_fields();
    g["band"] = Text(opt.bands.Label(b));
    std::vector<Value> models;
    for (const auto& m : r.band_models[b]) models.push_back(ModelJson(m, opt.bands));
    g["models"] = List(models);
    g["selected"] = Text(r.band_models[b][r.selected[b]].Name());
    g["aggregate_um"] = Num(r.aggregate[b]);
    g["committee_train"] = RoleJson(r.committee_per_band[b].train);
    g["committee_test"] = RoleJson(r.committee_per_band[b].test);
    g["wall_time_s"] = Num(r.band_wall_s[b]);
    bands.push_back(Obj(s));
  }
  f["bands"] = List(bands);
  f["committee_test"] = RoleJson(r.committee_test);
  f["committee_train"] = RoleJson(r.committee_train);
  if (r.best_complete >= 0) {
    f["best_complete"] = Text(r.complete[r.best_complete].Name());
    f["best_complete_test"] = RoleJson(r.complete[r.best_complete].all_test);
    f["rmse_reduction"] = Num(r.rmse_reduction);
    f["max_error_reduction"] = Num(r.max_reduction);
  }
  f["evaluations"] = Num(static_cast<double>(r.evaluations));
  f["wall_time_s"] = Num(r.wall_s);
  f["threads"] = Num(r.threads);
  std::string json;
  google::protobuf::util::JsonPrintOptions jo;
  jo.add_whitespace = true;
  jo.preserve_proto_field_names = true;
  if (!google::protobuf::util::MessageToJsonString(root, &json, jo).ok())
    throw std::runtime_error("cannot format committee.json");
  return json;
}

// ---- Figures -------------------------------------------------------------------------------

std::vector<std::string> WriteCommitteeFigures(const std::string& dir, const CommitteeResult& r,
                                               const io::StackRecordSet& set,
                                               std::vector<std::string>* warnings) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  std::vector<fs::path> scripts;
  const IdentifiedModel* complete = r.best_complete >= 0 ? &r.complete[r.best_complete] : nullptr;
  for (const io::StackRecord& rec : set.records) {
    if (rec.role != io::CaseRole::kTest) continue;
    const int b = r.options.bands.BandOf(rec.frequency_hz);
    const auto cm = PredictCommittee(r, rec);
    std::vector<double> full;
    if (complete) full = PredictModel(*complete, rec, r.options.sim);
    // The last whole drive cycle of the record.
    const size_t n = rec.t.size();
    const size_t per = std::max<size_t>(
        2, static_cast<size_t>(std::lround(rec.sample_rate_hz / rec.frequency_hz)));
    const size_t first = n > per + 1 ? n - per - 1 : 0;
    const std::string stem =
        "loop_band" + std::to_string(b + 1) + "_f" + io::FormatNumber(rec.frequency_hz);
    io::WriteFileWith(fs::path(dir) / (stem + ".csv"), [&](std::ostream& os) {
      os << "voltage_V,measured_um,committee_um" << (complete ? ",complete_um" : "") << "\n";
      for (size_t k = first; k < n; ++k) {
        os << io::FormatNumber(rec.u[k]) << "," << io::FormatNumber(rec.y[k]) << ","
           << io::FormatNumber(cm[k]);
        if (complete) os << "," << io::FormatNumber(full[k]);
        os << "\n";
      }
    });
    Plot p;
    p.name = stem;
    p.title = "Band " + r.options.bands.Label(b) + ": " + rec.Label() + ", last cycle";
    p.xlabel = "voltage [V]";
    p.ylabel = "displacement [µm]";
    p.series.push_back({stem + ".csv", 1, 2, "measured", "points pt 7 ps 0.4"});
    p.series.push_back(
        {stem + ".csv", 1, 3, "committee (" + r.band_models[b][r.selected[b]].Name() + ")", "lines"});
    if (complete)
      p.series.push_back({stem + ".csv", 1, 4, "complete (" + complete->Name() + ")", "lines"});
    scripts.push_back(WritePlotScript(dir, p));
  }
  if (GnuplotAvailable()) {
    RenderPlots(dir, scripts, warnings);
  } else if (warnings) {
    warnings->push_back("gnuplot not found: render the figures with `gnuplot <name>.gp` in " + dir);
  }
  std::vector<std::string> out;
  for (const auto& s : scripts) out.push_back(s.string());
  return out;
}

}  // namespace pz::client
