#include "hgann/hgann_fitness.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/chromosome.h"
#include "model/metrics.h"

namespace pz::hgann {

using opt::FitnessResult;
using opt::FitnessStatus;
using opt::Genome;

model::InputNormalization HgannFitnessConfig::FromTrainingCases() const {
  std::vector<double> v, f;
  for (const auto& c : cases) {
    if (!c.training) continue;
    v.push_back(c.drive.amplitude_v);
    f.push_back(c.drive.frequency_hz);
  }
  return model::InputNormalization::FromCases(v, f);
}

Status HgannFitnessConfig::Validate() const {
  int training = 0;
  for (size_t i = 0; i < cases.size(); ++i) {
    const auto& c = cases[i];
    const std::string f = "cases[" + std::to_string(i) + "]";
    if (c.number <= 0) return InvalidArgument(FieldError(f + ".number", c.number, "must be > 0"));
    if (auto s = c.drive.Validate(); !s.ok()) return InvalidArgument(f + ".drive." + s.message());
    if (static_cast<int>(c.measured_deg.size()) != c.drive.NumSamples())
      return InvalidArgument(FieldError(
          f + ".measured_deg.size()", c.measured_deg.size(),
          "must equal the drive's sample count " + std::to_string(c.drive.NumSamples())));
    for (size_t k = 0; k < c.measured_deg.size(); ++k)
      if (!std::isfinite(c.measured_deg[k]))
        return InvalidArgument(FieldError(f + ".measured_deg[" + std::to_string(k) + "]",
                                          c.measured_deg[k], "must be finite"));
    if (!(std::isfinite(c.b1) && c.b1 > 0))
      return InvalidArgument(FieldError(f + ".b1", c.b1, "must be finite and > 0"));
    if (!(std::isfinite(c.b2) && c.b2 < 0))
      return InvalidArgument(FieldError(f + ".b2", c.b2, "must be finite and < 0"));
    for (size_t j = 0; j < i; ++j)
      if (cases[j].number == c.number)
        return InvalidArgument(
            FieldError(f + ".number", c.number, "duplicates cases[" + std::to_string(j) + "]"));
    training += c.training;
  }
  if (training == 0) return InvalidArgument("cases: needs at least one training case");
  if (!(std::isfinite(spread_penalty) && spread_penalty >= 0))
    return InvalidArgument(
        FieldError("spread_penalty", spread_penalty, "must be finite and >= 0 [deg^2]"));
  if (auto s = ranges.Validate(); !s.ok()) return s;
  if (auto s = normalization.Validate(); !s.ok())
    return InvalidArgument("normalization." + s.message());
  if (auto s = geometry.Validate(); !s.ok()) return InvalidArgument("geometry." + s.message());
  return Status::Ok();
}

HgannFitness::HgannFitness(HgannFitnessConfig config) : config_(std::move(config)) {
  ThrowIfError(config_.Validate());
  plant_ = std::make_unique<model::BimorphPlant>(config_.geometry);
  simulator_ = std::make_unique<model::ModalSimulator>(*plant_);
  double bound = 0;
  for (const auto& c : config_.cases) {
    if (!c.training) continue;
    const double b = std::max(c.b1, -c.b2);
    for (double y : c.measured_deg) bound += (b + std::abs(y)) * (b + std::abs(y));
  }
  penalty_ = 2.0 * bound + 1.0;
  // Absurd data (e.g. samples of 1e300 deg) would make the bound, and so every cost, infinite: the
  // penalty stays the largest finite double then, and costs that overflow are penalised below.
  if (!std::isfinite(penalty_)) penalty_ = std::numeric_limits<double>::max();
}

model::Network HgannFitness::Decode(const Genome& genome) const {
  return model::DecodeChromosome(genome.bits, config_.normalization, config_.ranges);
}

model::BimorphParams HgannFitness::ParamsFor(const model::NetworkParameters& p,
                                             const HgannCase& c) const {
  model::BimorphParams bp;
  bp.mu = p.mu;
  bp.delta = p.delta;
  bp.alpha = p.alpha;
  bp.beta = p.beta;
  bp.gamma = p.gamma;
  bp.a1 = p.a1;
  bp.a2 = p.a2;
  bp.b1 = c.b1;
  bp.b2 = c.b2;
  return bp;
}

FitnessResult HgannFitness::Evaluate(const Genome& genome) const {
  if (auto s = model::ValidateChromosome(genome.bits); !s.ok())
    return {penalty_, FitnessStatus::kError, "invalid genome: " + s.message()};
  model::Network net;
  try {
    net = Decode(genome);
  } catch (const InputError& e) {
    return {penalty_, FitnessStatus::kError, std::string("decode: ") + e.what()};
  }
  return EvaluateNetwork(net);
}

FitnessResult HgannFitness::EvaluateNetwork(const model::Network& network) const {
  thread_local std::vector<double> angle;
  thread_local model::ModalWorkspace workspace;
  double cost = 0;
  for (const auto& c : config_.cases) {
    if (!c.training) continue;
    model::NetworkParameters p;
    try {
      p = network.Predict(c.drive.amplitude_v, c.drive.frequency_hz);
    } catch (const InputError& e) {
      return {penalty_, FitnessStatus::kError, std::string("predict: ") + e.what()};
    }
    angle.resize(c.measured_deg.size());
    const auto summary = simulator_->SimulateAngle(ParamsFor(p, c), c.drive, angle, workspace);
    if (!summary.ok()) {
      return {penalty_,
              summary.status == model::SimStatus::kInvalidInput ? FitnessStatus::kError
                                                                : FitnessStatus::kPenalized,
              model::SimStatusName(summary.status)};
    }
    const double pi = model::PerformanceIndex(c.measured_deg, angle);
    if (!std::isfinite(pi)) return {penalty_, FitnessStatus::kPenalized, "non_finite"};
    cost += pi;
  }
  if (config_.spread_penalty > 0) {
    // The grid of the spread penalty is the network's envelope: a network that gives an unbounded
    // loop at a point of it is penalised like one that does so on a training case.
    const Envelope e = GridOf(network);
    if (!e.bounded)
      return {penalty_, FitnessStatus::kPenalized, "unbounded_hysteresis_in_envelope"};
    cost += config_.spread_penalty * e.spread;
  }
  if (!std::isfinite(cost) || cost >= penalty_)
    return {penalty_, FitnessStatus::kPenalized,
            "cost overflow (" + std::to_string(cost) + " deg^2)"};
  return {cost, FitnessStatus::kOk, {}};
}

double HgannFitness::OutputSpread(const model::Network& network) const {
  return GridOf(network).spread;
}

bool HgannFitness::BoundedOnEnvelope(const model::Network& network) const {
  return GridOf(network).bounded;
}

std::vector<std::pair<double, double>> HgannFitness::EnvelopeGrid(
    const model::InputNormalization& n) {
  constexpr int kGrid = 5;
  std::vector<std::pair<double, double>> grid;
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j)
      grid.emplace_back(
          n.amplitude_lo_v + (n.amplitude_hi_v - n.amplitude_lo_v) * i / (kGrid - 1),
          n.frequency_lo_hz + (n.frequency_hi_hz - n.frequency_lo_hz) * j / (kGrid - 1));
  return grid;
}

HgannFitness::Envelope HgannFitness::GridOf(const model::Network& network) const {
  Envelope e;
  double sum[model::kNetworkOutputs] = {}, sum2[model::kNetworkOutputs] = {};
  const std::vector<std::pair<double, double>> grid = EnvelopeGrid(config_.normalization);
  for (const auto& [v, f] : grid) {
    const model::NetworkParameters q = network.Predict(v, f);
    if (!LoopBounded(q)) e.bounded = false;
    const auto p = q.ToArray();
    for (int k = 0; k < model::kNetworkOutputs; ++k) {
      const auto& r = config_.ranges[k];
      const double s = r.upper > r.lower ? (p[k] - r.lower) / (r.upper - r.lower) : 0.0;
      sum[k] += s;
      sum2[k] += s * s;
    }
  }
  const double count = static_cast<double>(grid.size());
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    e.spread += std::max(0.0, sum2[k] / count - (sum[k] / count) * (sum[k] / count));
  return e;
}

std::array<int, model::kNetworkOutputs> HgannFitness::ParametersAtBound(
    const model::Network& network) const {
  std::array<int, model::kNetworkOutputs> side{};
  bool first = true;
  for (const auto& c : config_.cases) {
    if (!c.training) continue;
    const auto p = network.Predict(c.drive.amplitude_v, c.drive.frequency_hz).ToArray();
    for (int k = 0; k < model::kNetworkOutputs; ++k) {
      const auto& r = config_.ranges[k];
      const double tol = kAtBoundShare * (r.upper - r.lower);
      const int here = !(r.upper > r.lower)    ? 0
                       : p[k] <= r.lower + tol ? -1
                       : p[k] >= r.upper - tol ? 1
                                               : 0;
      side[k] = first ? here : (side[k] == here ? here : 0);
    }
    first = false;
  }
  return side;
}

std::vector<HgannCaseResult> HgannFitness::EvaluateCases(const model::Network& network) const {
  std::vector<HgannCaseResult> out;
  model::ModalWorkspace ws;
  std::vector<double> angle;
  for (const auto& c : config_.cases) {
    HgannCaseResult r;
    r.number = c.number;
    r.training = c.training;
    r.params = ParamsFor(network.Predict(c.drive.amplitude_v, c.drive.frequency_hz), c);
    angle.resize(c.measured_deg.size());
    r.summary = simulator_->SimulateAngle(r.params, c.drive, angle, ws);
    r.pi = r.summary.ok() ? model::PerformanceIndex(c.measured_deg, angle) : penalty_;
    out.push_back(std::move(r));
  }
  return out;
}

bool HgannFitness::SimulateCase(const model::NetworkParameters& p, const HgannCase& c,
                                std::span<double> angle) const {
  thread_local model::ModalWorkspace workspace;
  if (angle.size() != c.measured_deg.size()) return false;
  return simulator_->SimulateAngle(ParamsFor(p, c), c.drive, angle, workspace).ok();
}

model::BimorphTrace HgannFitness::Trace(const model::Network& network, const HgannCase& c) const {
  const auto params = ParamsFor(network.Predict(c.drive.amplitude_v, c.drive.frequency_hz), c);
  return simulator_->Simulate(params, model::DriveSignal{c.drive});
}

}  // namespace pz::hgann

#include "io/bench_data.h"
#include "model/saturation.h"

namespace pz::hgann {

HgannFitnessConfig HgannConfigFromCaseSet(const io::CaseSet& set,
                                          const model::ParameterRanges& ranges,
                                          const std::vector<model::SaturationPair>& given) {
  PZ_CHECK(given.empty() || given.size() == set.cases.size());
  HgannFitnessConfig config;
  config.ranges = ranges;
  for (size_t i = 0; i < set.cases.size(); ++i)
    config.cases.push_back(
        io::MakeFinCase(set.cases[i], given.empty() ? std::nullopt : std::optional(given[i])));
  bool any_training = false;
  for (const auto& c : config.cases) any_training |= c.training;
  if (!any_training)
    throw InputError((set.dir / "cases.csv").string() + ": no case has role 'train'");
  config.normalization = config.FromTrainingCases();
  ThrowIfError(config.Validate());
  return config;
}

}  // namespace pz::hgann
