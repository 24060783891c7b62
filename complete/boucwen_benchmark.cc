#include "complete/boucwen_benchmark.h"

#include <cmath>
#include <stdexcept>

#include "io/csv.h"
#include "records/criterion.h"
#include "records/registry.h"

namespace pz::complete {
namespace {

// The records of one role: (record name, file).
std::vector<std::pair<std::string, std::string>> FilesOf(model::CaseRole role) {
  if (role == model::CaseRole::kTrain)
    return {{"train_A", "train_A_multisine.csv"}, {"train_B", "train_B_multisine.csv"}};
  if (role == model::CaseRole::kTest)
    return {{"test_multisine", "test_multisine.csv"}, {"test_sinesweep", "test_sinesweep.csv"}};
  throw InputError(std::string("the Bouc-Wen benchmark has no ") + model::CaseRoleName(role) +
                   " records (train: train_A, train_B; test: test_multisine, test_sinesweep)");
}

// θ's output on [0, n) of a test record of the benchmark's protocol with 20 RK4 sub-steps.
std::vector<double> SimulateTest(std::span<const double> theta, const io::Record& r,
                                 model::InputInterpolation interpolation, size_t period,
                                 const char* what) {
  const auto model = MakeBwModel(BwProtocol(20, interpolation, period));
  std::vector<double> y(r.size());
  model->Simulate(r, theta, {}, r.size(), y);
  for (size_t k = 0; k < y.size(); ++k)
    if (!std::isfinite(y[k]))
      throw std::runtime_error(std::string(what) + ": the simulation diverged before sample " +
                               std::to_string(k));
  return y;
}

}  // namespace

io::Record MakeBwRecord(std::string name, model::CaseRole role, std::vector<double> u,
                        std::vector<double> y, size_t first_scored, double sample_rate_hz) {
  const std::string what = "bw record " + name;
  if (!(std::isfinite(sample_rate_hz) && sample_rate_hz > 0))
    throw InputError(
        FieldError(what + ": sample_rate_hz", sample_rate_hz, "must be finite and > 0"));
  if (y.size() != u.size())
    throw InputError(FieldError(what + ": y", std::to_string(y.size()) + " samples",
                                "must have as many as u (" + std::to_string(u.size()) + ")"));
  if (u.size() < 2)
    throw InputError(FieldError(what + ": u", std::to_string(u.size()) + " samples", "needs >= 2"));
  if (first_scored >= u.size())
    throw InputError(FieldError(what + ": first_counted", first_scored,
                                "leaves no counted sample of " + std::to_string(u.size())));
  for (size_t i = 0; i < u.size(); ++i) {
    if (!std::isfinite(u[i]))
      throw InputError(FieldError(what + ": u[" + std::to_string(i) + "]", u[i], "must be finite"));
    if (!std::isfinite(y[i]))
      throw InputError(FieldError(what + ": y[" + std::to_string(i) + "]", y[i], "must be finite"));
  }
  io::Record r;
  r.name = std::move(name);
  r.role = role;
  r.dt = 1.0 / sample_rate_hz;
  r.t.resize(u.size());
  for (size_t k = 0; k < r.t.size(); ++k) r.t[k] = static_cast<double>(k) / sample_rate_hz;
  r.u = std::move(u);
  r.y = std::move(y);
  r.first_scored = first_scored;
  r.end_scored = r.u.size();
  r.rest_samples = 1;
  r.offset_mode = io::OffsetMode::kFixed;
  r.offset = 0;
  return r;
}

io::RecordSet LoadBwBenchmark(const std::filesystem::path& dir, model::CaseRole role) {
  io::RecordSet set;
  set.source = dir;
  set.format = "boucwen-benchmark";
  set.drive_unit = "N";
  set.response_unit = "m";
  for (const auto& [name, file] : FilesOf(role)) {
    const io::CsvTable t = io::ReadCsvFile(dir / file);
    t.RequireColumns({"u_N", "y_m"});
    t.RequireRows();
    const int cu = t.RequireColumn("u_N"), cy = t.RequireColumn("y_m");
    std::vector<double> u, y;
    u.reserve(t.rows.size());
    y.reserve(t.rows.size());
    for (size_t i = 0; i < t.rows.size(); ++i) {
      u.push_back(t.Number(i, cu));
      y.push_back(t.Number(i, cy));
    }
    set.records.push_back(MakeBwRecord(name, role, std::move(u), std::move(y), 0));
    set.records.back().file = dir / file;
  }
  return set;
}

io::Record MakeBwTrainingRecord(const io::Record& raw, size_t samples, bool steady_state) {
  if (samples % kBwPeriod != 0 || samples == 0 || samples > raw.size())
    throw InputError(
        FieldError(raw.name + ": samples", samples,
                   "must be a whole number of 8192-sample periods, at most the record's " +
                       std::to_string(raw.size())));
  const size_t warmup = steady_state ? kBwPeriod : 0;
  const auto n = static_cast<std::ptrdiff_t>(samples);
  std::vector<double> u(raw.u.begin(), raw.u.begin() + static_cast<std::ptrdiff_t>(warmup));
  u.insert(u.end(), raw.u.begin(), raw.u.begin() + n);
  std::vector<double> y(warmup, 0.0);
  y.insert(y.end(), raw.y.begin(), raw.y.begin() + n);
  io::Record r = MakeBwRecord(raw.name, model::CaseRole::kTrain, std::move(u), std::move(y), warmup,
                              raw.sample_rate_hz());
  r.file = raw.file;
  return r;
}

records::OscillatorOptions BwProtocol(int rk4_steps, model::InputInterpolation interpolation,
                                      size_t period_samples) {
  records::OscillatorOptions o;
  o.physical = true;
  o.rk4_steps = rk4_steps;
  o.interpolation = interpolation;
  o.period_samples = period_samples;
  o.from_zero_state = true;
  return o;
}

std::shared_ptr<records::RecordModel> MakeBwModel(const records::OscillatorOptions& options) {
  // The physical oscillator's box is absolute and its output the displacement itself: the scale
  // is not measured (its polarity, +1, is all the model reads of it).
  const records::DataScale scale;
  records::FamilyOptions fo;
  fo.oscillator = options;
  std::shared_ptr<const records::Family> family = records::MakeFamily("bw-oscillator", scale, fo);
  return std::make_shared<records::RecordModel>(family, std::vector<records::EffectKind>{}, scale);
}

BwTraining::BwTraining(std::vector<io::Record> records, const records::OscillatorOptions& options,
                       double penalty)
    : records_(std::move(records)), options_(options), model_(MakeBwModel(options)) {
  if (records_.empty()) throw InputError("bw fitness: no records to fit");
  std::vector<const io::Record*> ptrs;
  for (const io::Record& r : records_) ptrs.push_back(&r);
  fitness_ = std::make_unique<records::RecordFitness>(*model_, std::move(ptrs), penalty);
}

opt::FitnessResult BwTraining::Evaluate(const opt::Genome& genome) const {
  if (genome.reals.size() != 6)
    return {penalty(), opt::FitnessStatus::kError,
            "genome has " + std::to_string(genome.reals.size()) +
                " reals, the Bouc-Wen oscillator has 6 parameters"};
  return fitness_->Evaluate(genome);
}

void BwTraining::EvaluateMany(std::span<const opt::Genome* const> genomes,
                              std::span<opt::FitnessResult> out) const {
  for (const opt::Genome* g : genomes) {
    if (g->reals.size() != 6)
      return FitnessFunction::EvaluateMany(genomes, out);  // Evaluate's error each
  }
  fitness_->EvaluateMany(genomes, out);
}

opt::ParamBox BwTraining::Box() const { return records::ParamBoxOf(*model_); }

std::vector<double> SimulateBwMultisineTest(std::span<const double> theta, const io::Record& test) {
  const size_t n = test.size();
  std::vector<double> u3, y3(2 * n, 0.0);
  for (int k = 0; k < 3; ++k) u3.insert(u3.end(), test.u.begin(), test.u.end());
  y3.insert(y3.end(), test.y.begin(), test.y.end());
  const io::Record three = MakeBwRecord(test.name, test.role, std::move(u3), std::move(y3), 2 * n,
                                        test.sample_rate_hz());
  const std::vector<double> y =
      SimulateTest(theta, three, model::InputInterpolation::kPeriodicFourier, n, "multisine test");
  return std::vector<double>(y.end() - static_cast<std::ptrdiff_t>(n), y.end());
}

std::vector<double> SimulateBwSweepTest(std::span<const double> theta, const io::Record& test) {
  return SimulateTest(theta, test, model::InputInterpolation::kCubicSpline, 0, "sine-sweep test");
}

}  // namespace pz::complete
