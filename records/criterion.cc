#include "records/criterion.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "io/csv.h"
#include "model/criteria.h"

namespace pz::records {
namespace {

constexpr Criterion kCriteria[] = {Criterion::kMse, Criterion::kIae, Criterion::kSse,
                                   Criterion::kRmse, Criterion::kMax};

// Samples k with t0 ≤ k dt ≤ t1 (as model/criteria.h counts them).
size_t WindowCount(size_t n, double dt, double t0, double t1) {
  double f = std::ceil(t0 / dt);
  if (f * dt < t0) f += 1;
  double l = std::floor(t1 / dt);
  if (l * dt > t1) l -= 1;
  l = std::min(l, static_cast<double>(n - 1));
  return l >= f ? static_cast<size_t>(l - f + 1) : 0;
}

}  // namespace

const char* CriterionName(Criterion c) {
  switch (c) {
    case Criterion::kMse:
      return "mse";
    case Criterion::kIae:
      return "iae";
    case Criterion::kSse:
      return "sse";
    case Criterion::kRmse:
      return "rmse";
    case Criterion::kMax:
      return "max";
  }
  return "unknown";
}

Criterion ParseCriterion(const std::string& name) {
  for (Criterion c : kCriteria)
    if (name == CriterionName(c)) return c;
  throw InputError("criterion '" + name + "': expected mse, iae, sse, rmse or max");
}

Status CriterionOptions::Validate() const {
  if (!(std::isfinite(error_cost) && error_cost > 0))
    return InvalidArgument(FieldError("error_cost", error_cost, "must be finite and > 0"));
  if (!windowed()) return Status::Ok();
  if (!(std::isfinite(t0_s) && t0_s >= 0))
    return InvalidArgument(FieldError("window t0_s", t0_s, "must be finite and >= 0"));
  if (!(std::isfinite(t1_s) && t1_s > t0_s))
    return InvalidArgument(FieldError("window t1_s", t1_s, "must be finite and > t0_s"));
  return Status::Ok();
}

double WindowEnd(const io::Record& r, double t1) {
  return std::min(t1, static_cast<double>(r.end_scored - 1) * r.dt);
}

WindowErrors ScoreWindow(const io::Record& r, std::span<const double> yhat, double t0, double t1) {
  const double end = WindowEnd(r, t1), dt = r.dt;
  const std::span<const double> y(r.y.data(), r.end_scored);
  yhat = yhat.first(r.end_scored);
  WindowErrors e;
  e.samples = WindowCount(r.end_scored, dt, t0, end);
  e.iae = model::Iae(y, yhat, dt, t0, end);
  e.sse = model::Sse(y, yhat, dt, t0, end);
  e.max_abs = model::MaxAbsError(y, yhat, dt, t0, end);
  return e;
}

CriterionFitness::CriterionFitness(const RecordModel& model, std::vector<const io::Record*> records,
                                   CriterionOptions criterion)
    : fitness_(model, std::move(records)), criterion_(criterion) {
  ThrowIfError(criterion_.Validate());
  if (!criterion_.windowed()) return;
  for (const io::Record* r : fitness_.records()) {
    if (!(WindowEnd(*r, criterion_.t1_s) > criterion_.t0_s))
      throw InputError(r->Label() + " ends at " +
                       io::FormatNumber(static_cast<double>(r->end_scored - 1) * r->dt) +
                       " s, before the window start t0_s = " + io::FormatNumber(criterion_.t0_s) +
                       " s");
  }
}

double CriterionFitness::Cost(std::span<const double> params) const {
  if (!criterion_.windowed()) return fitness_.Run(params).mse;
  const RecordModel& m = fitness_.model();
  // The hot path of a family without effects (the committee's): the family's simulation straight
  // on the record's samples into a per-thread buffer — RecordModel::Simulate's numbers (from rest
  // at the end of the rest segment, the rest output before it, polarity and offset), without its
  // copies.
  const bool direct = m.effects().empty() && !m.family().linear();
  const RecordFitness::Output out = direct ? RecordFitness::Output{} : fitness_.Run(params);
  thread_local std::vector<double> buffer;
  const double inf = std::numeric_limits<double>::infinity();
  const auto& records = fitness_.records();
  const double t0 = criterion_.t0_s;
  const int pol = m.scale().polarity;
  double total = 0;
  for (size_t i = 0; i < records.size(); ++i) {
    const io::Record& r = *records[i];
    std::span<const double> yhat;
    if (direct) {
      if (params.size() != m.params().size())
        throw InputError(m.Describe() + ": " + std::to_string(params.size()) +
                         " parameters given, " + std::to_string(m.params().size()) + " expected");
      const size_t end = r.end_scored, from = SimulatedFrom(r, end);
      buffer.resize(end);
      const std::span<double> y(buffer.data(), end);
      m.family().Simulate(params, std::span<const double>(r.u).subspan(from, end - from), r.dt,
                          y.subspan(from));
      std::fill(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(from), y[from]);
      const double rest = pol * y[from];
      if (pol != 1)
        for (double& v : y) v *= pol;
      const double o = RecordOffset(r, y, rest);
      if (o != 0)
        for (double& v : y) v += o;
      yhat = y;
    } else {
      yhat = out.yhat[i];
    }
    for (double v : yhat)
      if (!std::isfinite(v)) return inf;
    const std::span<const double> y(r.y.data(), r.end_scored);
    const double end = WindowEnd(r, criterion_.t1_s);
    switch (criterion_.kind) {
      case Criterion::kIae:
        total += model::Iae(y, yhat, r.dt, t0, end);
        break;
      case Criterion::kSse:
        total += model::Sse(y, yhat, r.dt, t0, end);
        break;
      case Criterion::kRmse:
        total += model::Rmse(y, yhat, r.dt, t0, end);
        break;
      case Criterion::kMax:
        total = std::max(total, model::MaxAbsError(y, yhat, r.dt, t0, end));
        break;
      case Criterion::kMse:
        break;
    }
  }
  return total;
}

opt::FitnessResult CriterionFitness::Evaluate(const opt::Genome& genome) const {
  const size_t want = model().params().size();
  if (genome.reals.size() != want)
    return {criterion_.error_cost, opt::FitnessStatus::kError,
            "genome has " + std::to_string(genome.reals.size()) + " reals, " + model().Describe() +
                " has " + std::to_string(want) + " parameters"};
  double cost;
  try {
    cost = Cost(genome.reals);
  } catch (const InputError& e) {
    return {criterion_.error_cost, opt::FitnessStatus::kPenalized,
            std::string("invalid parameters: ") + e.what()};
  }
  if (!std::isfinite(cost) || cost >= criterion_.error_cost)
    return {criterion_.error_cost, opt::FitnessStatus::kPenalized,
            "simulation diverged (non-finite output)"};
  return {cost, opt::FitnessStatus::kOk, ""};
}

opt::ParamBox ParamBoxOf(const RecordModel& model) {
  opt::ParamBox box;
  for (const ParamInfo& p : model.params()) {
    box.names.push_back(p.name);
    box.lower.push_back(p.lower);
    box.upper.push_back(p.upper);
    box.log_scale.push_back(p.log_scale);
  }
  return box;
}

}  // namespace pz::records
