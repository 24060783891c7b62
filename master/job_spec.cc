#include "master/job_spec.h"

#include <cmath>
#include <set>

#include "model/status.h"

namespace pz::master {
namespace {

class Checker {
 public:
  explicit Checker(std::vector<FieldViolation>* out) : out_(out) {}
  template <typename T>
  void Require(bool ok, const std::string& field, const T& value, const std::string& rule) {
    if (!ok) out_->push_back({field, FieldError(field, value, rule)});
  }
  template <typename T>
  void Range(const std::string& field, T value, T lo, T hi) {
    Require(value >= lo && value <= hi, field, value,
            "must be in [" + Num(lo) + ", " + Num(hi) + "]");
  }
  void Finite(const std::string& field, double value) {
    Require(std::isfinite(value), field, value, "must be finite");
  }

 private:
  template <typename T>
  static std::string Num(T v) {
    std::ostringstream os;
    os << v;
    return os.str();
  }
  std::vector<FieldViolation>* out_;
};

void ValidateHgann(const HgannProblem& h, Checker& c) {
  c.Require(!h.plant_model.empty(), "hgann.plant.model", "\"\"", "must name a plant");
  for (const auto& [k, v] : h.plant_options) c.Finite("hgann.plant.options." + k, v);
  c.Require(!h.cases.empty(), "hgann.cases", 0, "needs at least one bench case");
  for (size_t i = 0; i < h.cases.size(); ++i) {
    const BenchCase& b = h.cases[i];
    const std::string f = "hgann.cases[" + std::to_string(i) + "]";
    c.Require(b.sample_time_s > 0 && std::isfinite(b.sample_time_s), f + ".sample_time_s",
              b.sample_time_s, "must be > 0");
    c.Require(b.input_v.size() >= 2, f + ".input_v", b.input_v.size(), "needs ≥ 2 samples");
    c.Require(b.output_m.size() == b.input_v.size(), f + ".output_m", b.output_m.size(),
              "must have as many samples as input_v (" + std::to_string(b.input_v.size()) + ")");
    c.Require(b.weight > 0 && std::isfinite(b.weight), f + ".weight", b.weight, "must be > 0");
    bool finite = true;
    for (double v : b.input_v) finite = finite && std::isfinite(v);
    for (double v : b.output_m) finite = finite && std::isfinite(v);
    c.Require(finite, f, b.name, "samples must be finite");
  }
  c.Require(!h.ranges.empty(), "hgann.ranges", 0, "needs at least one parameter range");
  std::set<std::string> names;
  for (size_t i = 0; i < h.ranges.size(); ++i) {
    const ParameterRange& r = h.ranges[i];
    const std::string f = "hgann.ranges[" + std::to_string(i) + "]";
    c.Require(!r.name.empty(), f + ".name", "\"\"", "must be set");
    c.Require(names.insert(r.name).second, f + ".name", r.name, "duplicate parameter name");
    c.Require(std::isfinite(r.min) && std::isfinite(r.max) && r.min < r.max, f + ".max", r.max,
              "must be finite and > min (" + std::to_string(r.min) + ")");
    c.Range(f + ".bits", r.bits, 1, 32);
  }
  for (size_t i = 0; i < h.hidden.size(); ++i)
    c.Range("hgann.hidden[" + std::to_string(i) + "]", h.hidden[i], 1, 1024);
}

}  // namespace

int GaSettings::offspring() const {
  return population - static_cast<int>(std::lround(population * elite_fraction));
}

std::string JobSpec::kind() const {
  if (std::holds_alternative<HgannProblem>(problem)) return "hgann";
  if (std::holds_alternative<SyntheticProblem>(problem)) return "synthetic";
  return "";
}

std::vector<FieldViolation> JobSpec::Validate() const {
  std::vector<FieldViolation> out;
  Checker c(&out);
  c.Require(version == kJobSpecVersion, "version", version,
            "unsupported job spec version (this master reads " + std::to_string(kJobSpecVersion) +
                ")");
  c.Require(name.size() <= 200, "name", name.size(), "must be ≤ 200 characters");
  c.Range("limits.task_timeout_s", limits.task_timeout_s, 0.001, 86400.0);
  c.Range("limits.quarantine_after", limits.quarantine_after, 1, 100);
  c.Finite("limits.penalty_cost", limits.penalty_cost);
  if (limits.target_cost) c.Finite("limits.target_cost", *limits.target_cost);

  if (const auto* h = std::get_if<HgannProblem>(&problem)) {
    ValidateHgann(*h, c);
  } else if (const auto* s = std::get_if<SyntheticProblem>(&problem)) {
    c.Range("synthetic.genome_bits", s->genome_bits, 1, 65536);
    c.Range("synthetic.sleep_ms", s->sleep_ms, 0.0, 60000.0);
    bool bits01 = s->crash_prefix.find_first_not_of("01") == std::string::npos;
    c.Require(bits01 && static_cast<int>(s->crash_prefix.size()) <= s->genome_bits,
              "synthetic.crash_prefix", s->crash_prefix, "must be a 0/1 string ≤ genome_bits");
  } else {
    out.push_back({"problem", "problem: one of hgann, synthetic must be set"});
  }

  if (!ga) {
    out.push_back({"algorithm", "algorithm: ga must be set"});
  } else {
    c.Range("ga.population", ga->population, 2, 1000000);
    c.Require(ga->elite_fraction > 0 && ga->elite_fraction < 1, "ga.elite_fraction",
              ga->elite_fraction, "must be in (0, 1)");
    const int elite = static_cast<int>(std::lround(ga->population * ga->elite_fraction));
    c.Require(elite >= 1 && elite <= ga->population - 1, "ga.elite_fraction", ga->elite_fraction,
              "round(population · elite_fraction) = " + std::to_string(elite) +
                  " must be in [1, population − 1]");
    c.Range("ga.tournament", ga->tournament, 1, 1000000);
    c.Range("ga.crossover_probability", ga->crossover_probability, 0.0, 1.0);
    c.Range("ga.mutation_probability", ga->mutation_probability, 0.0, 1.0);
    c.Range("ga.generations", ga->generations, 0, 100000000);
    c.Range("ga.stall_generations", ga->stall_generations, 0, 100000000);
  }
  return out;
}

}  // namespace pz::master
