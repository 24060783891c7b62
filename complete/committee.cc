#include "complete/committee.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "io/csv.h"
#include "opt/inline_evaluator.h"
#include "opt/thread_pool_evaluator.h"
#include "records/fit.h"
#include "records/registry.h"

namespace pz::complete {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
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

RecordError Errors(const io::Record& r, std::span<const double> yhat, double t0, double t1) {
  const records::WindowErrors w = records::ScoreWindow(r, yhat, t0, t1);
  RecordError e;
  e.m.records = 1;
  e.m.samples = w.samples;
  e.m.iae = w.iae;
  e.sse = w.sse;
  e.m.rmse = std::sqrt(e.sse / static_cast<double>(std::max<size_t>(e.m.samples, 1)));
  e.m.max_abs = w.max_abs;
  return e;
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
      return InvalidArgument(
          FieldError("bands edge " + std::to_string(i + 1), edges[i], "must be finite and >= 0"));
    if (i > 0 && !(edges[i] > edges[i - 1]))
      return InvalidArgument(
          FieldError("bands edge " + std::to_string(i + 1), edges[i],
                     "must be > the previous edge " + io::FormatNumber(edges[i - 1])));
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

std::map<std::string, opt::ParamBox> Seed002Boxes() {
  std::map<std::string, opt::ParamBox> boxes;
  boxes["stack-bouc-wen"] = {{"alpha", "beta", "gamma", "d", "fc_Hz"},
                             {0.01, 1e-5, -0.05, 0.02, 100},
                             {3.0, 0.1, 0.05, 0.08, 20000},
                             {true, true, false, false, true}};
  boxes["backlash-like"] = {
      {"alpha", "c", "B1"}, {1e-4, 0.02, -0.05}, {1.0, 0.08, 0.1}, {true, false, false}};
  return boxes;
}

Status CommitteeOptions::Validate() const {
  if (Status s = bands.Validate(); !s.ok()) return s;
  if (families.empty()) return InvalidArgument("families: at least one model family is needed");
  if (algorithms.empty()) return InvalidArgument("optimisers: at least one optimiser is needed");
  const std::vector<std::string>& known = records::FamilyNames();
  for (size_t i = 0; i < families.size(); ++i) {
    if (std::find(known.begin(), known.end(), families[i]) == known.end()) {
      std::string list;
      for (const auto& n : known) list += (list.empty() ? "" : ", ") + n;
      return InvalidArgument("families: unknown family '" + families[i] + "' (families: " + list +
                             ")");
    }
    for (size_t j = 0; j < i; ++j)
      if (families[i] == families[j])
        return InvalidArgument("families: " + families[i] + " given twice");
  }
  for (size_t i = 0; i < algorithms.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (algorithms[i] == algorithms[j])
        return InvalidArgument(std::string("optimisers: ") +
                               opt::SearchAlgorithmName(algorithms[i]) + " given twice");
  if (!(std::isfinite(t0_s) && t0_s >= 0))
    return InvalidArgument(FieldError("window t0_s", t0_s, "must be finite and >= 0"));
  if (!(std::isfinite(t1_s) && t1_s > t0_s))
    return InvalidArgument(FieldError("window t1_s", t1_s, "must be finite and > t0_s"));
  if (family_options.substeps < 1 || family_options.substeps > 512)
    return InvalidArgument(FieldError("substeps", family_options.substeps, "must be 1 … 512"));
  if (Status s = records::CriterionOptions{criterion, t0_s, t1_s, search.error_cost}.Validate();
      !s.ok())
    return s;
  for (const auto& [name, box] : boxes) {
    opt::SearchOptions so = search;
    for (opt::SearchAlgorithm a : algorithms) {
      so.algorithm = a;
      if (Status s = so.Validate(box); !s.ok())
        return InvalidArgument("box of " + name + ": " + s.message());
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
  return family + "/" + opt::SearchAlgorithmName(algorithm);
}

std::vector<double> PredictModel(const IdentifiedModel& m, const io::Record& record) {
  std::vector<double> y;
  records::Evaluate(*m.model, m.params, m.weights, record, &y);
  return y;
}

std::vector<double> PredictCommittee(const CommitteeResult& r, const io::Record& record) {
  const FrequencyBands& bands = r.options.bands;
  if (!r.options.averaging) {
    const int b = bands.BandOf(record.frequency_hz);
    if (b < 0) throw InputError(record.Label() + " is outside every band");
    return PredictModel(r.band_models[b][r.selected[b]], record);
  }
  const std::vector<double> mu = Memberships(bands, record.frequency_hz);
  std::vector<double> y(record.end_scored, 0.0);
  for (int b = 0; b < bands.size(); ++b) {
    if (mu[b] == 0) continue;
    const auto yb = PredictModel(r.band_models[b][r.selected[b]], record);
    for (size_t k = 0; k < y.size(); ++k) y[k] += mu[b] * yb[k];
  }
  return y;
}

RoleMetrics RecordMetrics(const io::Record& record, std::span<const double> yhat, double t0_s,
                          double t1_s) {
  return Errors(record, yhat, t0_s, t1_s).m;
}

// ---- The study -----------------------------------------------------------------------------

namespace {

// Errors of a predictor on every band's records, per role, and on all test / train records.
template <typename Predict>
void Score(const io::RecordSet& set, const CommitteeOptions& o, Predict predict,
           std::vector<BandMetrics>* per_band, RoleMetrics* all_test, RoleMetrics* all_train) {
  const int nb = o.bands.size();
  std::vector<Pool> train(nb), test(nb);
  Pool at, atr;
  for (const io::Record& r : set.records) {
    const int b = o.bands.BandOf(r.frequency_hz);
    const std::vector<double> y = predict(r);
    const RecordError e = Errors(r, y, o.t0_s, o.t1_s);
    if (r.role == model::CaseRole::kTrain) {
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

/// The records banded by frequency, their windows set, and the training records of each band.
struct BandedRecords {
  std::vector<std::vector<const io::Record*>> band_train;
  std::vector<const io::Record*> all_train;
};

BandedRecords BandRecords(io::RecordSet& set, const CommitteeOptions& options) {
  const int nb = options.bands.size();
  BandedRecords out;
  out.band_train.resize(nb);
  std::vector<int> band_tests(nb, 0);
  for (io::Record& r : set.records) {
    if (!(r.frequency_hz > 0))
      throw InputError(r.Label() +
                       " states no excitation frequency (the committee bands the records by it: a "
                       "bench's, or a manifest's frequency_Hz column)");
    const int b = options.bands.BandOf(r.frequency_hz);
    if (b < 0)
      throw InputError(r.Label() + " (" + io::FormatNumber(r.frequency_hz) +
                       " Hz) is outside every band (edges " +
                       [&] {
                         std::string s;
                         for (double e : options.bands.edges)
                           s += (s.empty() ? "" : ",") + io::FormatNumber(e);
                         return s;
                       }() +
                       " Hz)");
    // The criterion's window in the record's own time, t1 clipped to its last sample.
    const double t_end = r.t.back() - r.t.front();
    if (!(t_end > options.t0_s))
      throw InputError(r.Label() + " ends at " + io::FormatNumber(t_end) +
                       " s, before the window start t0_s = " + io::FormatNumber(options.t0_s) +
                       " s");
    io::SetWindow(r, r.t.front() + options.t0_s, r.t.front() + std::min(options.t1_s, t_end), 1,
                  r.Label() + ": the criterion window");
    if (r.role == model::CaseRole::kTrain) {
      out.band_train[b].push_back(&r);
      out.all_train.push_back(&r);
    } else {
      ++band_tests[b];
    }
  }
  for (int b = 0; b < nb; ++b) {
    if (out.band_train[b].empty())
      throw InputError("band " + options.bands.Label(b) + " has no training record");
    if (band_tests[b] == 0)
      throw InputError("band " + options.bands.Label(b) + " has no test record");
  }
  return out;
}

/// Identifies one family with one algorithm on a band's (or every) training record, scores it on
/// every record and logs it; the first search states the result's thread count.
class Identifier {
 public:
  Identifier(const CommitteeOptions& options, const EvaluatorFactory& factory,
             const CommitteeLog& log, CommitteeResult& res)
      : options_(options), factory_(factory), log_(log), res_(res) {}

  IdentifiedModel operator()(const std::string& family, opt::SearchAlgorithm algo,
                             const std::vector<const io::Record*>& train, int band) {
    const CommitteeOptions& options = options_;
    IdentifiedModel m;
    m.family = family;
    m.algorithm = algo;
    m.band = band;
    const records::DataScale scale = records::MeasureScale(train);
    auto model = std::make_shared<records::RecordModel>(
        records::MakeFamily(family, scale, options.family_options),
        std::vector<records::EffectKind>{}, scale);
    m.model = model;
    const records::CriterionFitness fitness(
        *model, train, {options.criterion, options.t0_s, options.t1_s, options.search.error_cost});
    const auto given = options.boxes.find(family);
    const opt::ParamBox box =
        given != options.boxes.end() ? given->second : records::ParamBoxOf(*model);
    if (box.names.size() != model->params().size())
      throw InputError("box of " + family + ": " + std::to_string(box.names.size()) +
                       " parameters, the family has " + std::to_string(model->params().size()));
    if (!box.names.empty()) {
      auto evaluator = factory_(fitness);
      if (first_search_) res_.threads = evaluator->concurrency();  // as the first search runs
      first_search_ = false;
      opt::SearchOptions so = options.search;
      so.algorithm = algo;
      ThrowIfError(so.Validate(box));
      m.search = opt::Search(box, so, *evaluator);
      m.params = m.search.best;
      res_.evaluations += m.search.evaluations;
    } else {  // a linear family without searched parameters: its weights are solved
      m.search.best_cost = fitness.Cost({});
      m.search.stop_reason = "weights solved by least squares";
    }
    if (model->family().linear()) m.weights = fitness.outputs().Run(m.params).weights;
    Score(
        res_.set, options, [&](const io::Record& r) { return PredictModel(m, r); }, &m.per_band,
        &m.all_test, nullptr);
    if (log_) Log(m, band);
    return m;
  }

 private:
  void Log(const IdentifiedModel& m, int band) const {
    std::ostringstream os;
    os << (band < 0 ? std::string("complete") : options_.bands.Label(band)) << " " << m.Name()
       << ": " << records::CriterionName(options_.criterion) << " "
       << FormatFigure(m.search.best_cost, 5) << " after " << m.search.evaluations
       << " evaluations in " << FormatFigure(m.search.wall_time_s) << " s ("
       << FormatFigure(m.search.evaluations / std::max(m.search.wall_time_s, 1e-9))
       << " evaluations/s), best of " << m.search.repetition_costs.size() << " repetitions: #"
       << m.search.best_repetition;
    log_(os.str());
  }

  const CommitteeOptions& options_;
  const EvaluatorFactory& factory_;
  const CommitteeLog& log_;
  CommitteeResult& res_;
  bool first_search_ = true;
};

/// Band b's models, the one of lowest aggregate A = (train RMSE + test RMSE) / 2 selected.
void IdentifyBand(const CommitteeOptions& options, const std::vector<const io::Record*>& train,
                  int b, Identifier& identify, const CommitteeLog& log, CommitteeResult& res) {
  const double t = Now();
  for (const std::string& f : options.families)
    for (opt::SearchAlgorithm a : options.algorithms)
      res.band_models[b].push_back(identify(f, a, train, b));
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
        res.band_models[b][res.selected[b]].Name() + " (A = " + FormatFigure(best, 4) + " µm)");
}

}  // namespace

CommitteeResult RunCommittee(const io::RecordSet& records, const CommitteeOptions& options,
                             const EvaluatorFactory& factory, const CommitteeLog& log) {
  ThrowIfError(options.Validate());
  const double start = Now();
  const int nb = options.bands.size();
  CommitteeResult res;
  res.options = options;
  res.set = records;
  const BandedRecords banded = BandRecords(res.set, options);
  Identifier identify(options, factory, log, res);

  if (options.complete) {
    const double t = Now();
    for (const std::string& f : options.families)
      for (opt::SearchAlgorithm a : options.algorithms)
        res.complete.push_back(identify(f, a, banded.all_train, -1));
    res.complete_wall_s = Now() - t;
  }
  res.band_models.resize(nb);
  res.band_wall_s.assign(nb, 0.0);
  res.selected.assign(nb, 0);
  res.aggregate.assign(nb, 0.0);
  for (int b = 0; b < nb; ++b) IdentifyBand(options, banded.band_train[b], b, identify, log, res);
  Score(
      res.set, options, [&](const io::Record& r) { return PredictCommittee(res, r); },
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

std::string FormatFigure(double x, int precision) {
  if (!std::isfinite(x)) return "—";
  std::ostringstream os;
  const double a = std::abs(x);
  if (a != 0 && (a < 1e-3 || a >= 1e5))
    os << std::scientific << std::setprecision(precision - 1) << x;
  else
    os << std::setprecision(precision) << x;
  return os.str();
}

std::string FormatPercent(double x) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(2) << 100 * x << " %";
  return os.str();
}

}  // namespace pz::complete
