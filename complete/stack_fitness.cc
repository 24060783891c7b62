#include "complete/stack_fitness.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "io/csv.h"
#include "model/criteria.h"

namespace pz::complete {

using opt::FitnessResult;
using opt::FitnessStatus;

const char* FitCriterionName(FitCriterion c) {
  switch (c) {
    case FitCriterion::kIae:
      return "iae";
    case FitCriterion::kSse:
      return "sse";
    case FitCriterion::kRmse:
      return "rmse";
    case FitCriterion::kMax:
      return "max";
  }
  return "unknown";
}

FitCriterion ParseFitCriterion(const std::string& name) {
  for (FitCriterion c : {FitCriterion::kIae, FitCriterion::kSse, FitCriterion::kRmse, FitCriterion::kMax})
    if (name == FitCriterionName(c)) return c;
  throw InputError("criterion '" + name + "': expected iae, sse, rmse or max");
}

double WindowEnd(const io::StackRecord& r, double t1) {
  return std::min(t1, static_cast<double>(r.t.size() - 1) * r.dt());
}

StackFitness::StackFitness(model::StackFamily family, std::vector<const io::StackRecord*> records,
                           FitCriterion criterion, double t0_s, double t1_s,
                           model::StackSimOptions sim, double error_cost)
    : family_(family),
      records_(std::move(records)),
      criterion_(criterion),
      t0_(t0_s),
      t1_(t1_s),
      sim_(sim),
      error_cost_(error_cost) {
  ThrowIfError(sim_.Validate());
  if (records_.empty()) throw InputError("stack fitness: no records to fit");
  if (!(std::isfinite(t0_) && t0_ >= 0))
    throw InputError(FieldError("window t0_s", t0_, "must be finite and >= 0"));
  if (!(std::isfinite(t1_) && t1_ > t0_))
    throw InputError(FieldError("window t1_s", t1_, "must be finite and > t0_s"));
  for (const io::StackRecord* r : records_) {
    PZ_CHECK(r != nullptr);
    if (!(WindowEnd(*r, t1_) > t0_))
      throw InputError(r->Label() + " ends at " +
                       io::FormatNumber(static_cast<double>(r->t.size() - 1) * r->dt()) +
                       " s, before the window start t0_s = " + io::FormatNumber(t0_) + " s");
  }
}

double StackFitness::Cost(std::span<const double> params) const {
  thread_local std::vector<double> yhat;
  double total = 0;
  for (const io::StackRecord* r : records_) {
    yhat.resize(r->u.size());
    const std::span<double> out(yhat.data(), r->u.size());
    model::SimulateStack(family_, params, r->u, r->dt(), out, sim_);
    for (double v : out)
      if (!std::isfinite(v)) return std::numeric_limits<double>::infinity();
    const double end = WindowEnd(*r, t1_);
    switch (criterion_) {
      case FitCriterion::kIae:
        total += model::Iae(r->y, out, r->dt(), t0_, end);
        break;
      case FitCriterion::kSse:
        total += model::Sse(r->y, out, r->dt(), t0_, end);
        break;
      case FitCriterion::kRmse:
        total += model::Rmse(r->y, out, r->dt(), t0_, end);
        break;
      case FitCriterion::kMax:
        total = std::max(total, model::MaxAbsError(r->y, out, r->dt(), t0_, end));
        break;
    }
  }
  return total;
}

FitnessResult StackFitness::Evaluate(const opt::Genome& genome) const {
  const size_t want = model::StackParamNames(family_).size();
  if (genome.reals.size() != want)
    return {error_cost_, FitnessStatus::kError,
            "genome has " + std::to_string(genome.reals.size()) + " reals, " +
                model::StackFamilyName(family_) + " has " + std::to_string(want) + " parameters"};
  double cost;
  try {
    cost = Cost(genome.reals);
  } catch (const InputError& e) {
    return {error_cost_, FitnessStatus::kPenalized, std::string("invalid parameters: ") + e.what()};
  }
  if (!std::isfinite(cost) || cost >= error_cost_)
    return {error_cost_, FitnessStatus::kPenalized, "simulation diverged (non-finite output)"};
  return {cost, FitnessStatus::kOk, ""};
}

}  // namespace pz::complete
