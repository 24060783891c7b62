#include "complete/bw_fitness.h"

#include <cmath>

namespace pz::complete {

opt::ParamBox BwOscillatorBox() {
  opt::ParamBox box;
  box.names = model::BwIdentifiableNames();
  box.lower = {0.2, 0.1, 1e3, 1e3, 1, -1e4};
  box.upper = {20, 1e3, 1e6, 1e6, 1e5, 1e4};
  box.log_scale = {true, true, true, true, true, false};
  return box;
}

BwOscillatorFitness::BwOscillatorFitness(std::vector<BwTrainingRecord> records, double penalty)
    : records_(std::move(records)), penalty_(penalty) {
  if (records_.empty()) throw InputError("bw fitness: no records to fit");
  if (!(std::isfinite(penalty_) && penalty_ > 0))
    throw InputError(FieldError("bw fitness: penalty", penalty_, "must be finite and > 0"));
  for (const BwTrainingRecord& r : records_) {
    if (r.y.size() != r.u.size())
      throw InputError(FieldError("bw record " + r.name + ": y", std::to_string(r.y.size()) + " samples",
                                  "must have as many as u (" + std::to_string(r.u.size()) + ")"));
    if (r.first_counted >= r.u.size())
      throw InputError(FieldError("bw record " + r.name + ": first_counted", r.first_counted,
                                  "leaves no counted sample of " + std::to_string(r.u.size())));
    for (size_t i = 0; i < r.y.size(); ++i)
      if (!std::isfinite(r.y[i]))
        throw InputError(FieldError("bw record " + r.name + ": y[" + std::to_string(i) + "]", r.y[i], "must be finite"));
    model::BwRecord p;
    p.name = r.name;
    try {
      p.input = model::BwInput(r.u, r.input);
    } catch (const InputError& e) {
      throw InputError("bw record " + r.name + ": " + e.what());
    }
    p.y_measured = r.y;
    p.first_counted = r.first_counted;
    prepared_.push_back(std::move(p));
  }
}

size_t BwOscillatorFitness::counted_samples() const {
  size_t n = 0;
  for (const auto& r : records_) n += r.u.size() - r.first_counted;
  return n;
}

opt::FitnessResult BwOscillatorFitness::Evaluate(const opt::Genome& genome) const {
  if (genome.reals.size() != 6)
    return {penalty_, opt::FitnessStatus::kError,
            "genome has " + std::to_string(genome.reals.size()) + " reals, the Bouc-Wen oscillator has 6 parameters"};
  bool diverged = false;
  const double mse = model::BwOutputMse(model::BwFromIdentifiable(genome.reals), prepared_, penalty_, &diverged);
  if (diverged) return {mse, opt::FitnessStatus::kPenalized, "diverged"};
  return {mse, opt::FitnessStatus::kOk, {}};
}

}  // namespace pz::complete
