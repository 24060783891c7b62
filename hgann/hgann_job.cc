#include "hgann/hgann_job.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <numbers>
#include <set>
#include <sstream>
#include <string>

#include "hgann/identify.h"
#include "hgann/loop_repair.h"
#include "hgann/output_move.h"
#include "hgann/trend_seeds.h"
#include "model/chromosome.h"

namespace pz::hgann {

using job::CaseRole;
using job::FieldViolation;
using job::GenomeLayout;
using job::HgannCaseSpec;
using job::HgannProblem;
using job::JobKind;
using job::JobSpec;
using job::ParameterRange;
using job::Violations;
using opt::FitnessFunction;
using opt::Genome;
namespace {

constexpr size_t kMaxSamplesPerCase = 10'000'000;
constexpr size_t kMaxCases = 10'000;
constexpr size_t kMaxSourceChars = 1000;

/// The overridable fields of model::BeamGeometry, by their proto names.
struct GeometryField {
  const char* name;
  double model::BeamGeometry::*real;  ///< nullptr for the element counts
  int model::BeamGeometry::*count;
};

constexpr GeometryField kGeometryFields[] = {
    {"active_length_m", &model::BeamGeometry::active_length_m, nullptr},
    {"tip_length_m", &model::BeamGeometry::tip_length_m, nullptr},
    {"core_width_m", &model::BeamGeometry::core_width_m, nullptr},
    {"core_thickness_m", &model::BeamGeometry::core_thickness_m, nullptr},
    {"mfc_width_m", &model::BeamGeometry::mfc_width_m, nullptr},
    {"mfc_thickness_m", &model::BeamGeometry::mfc_thickness_m, nullptr},
    {"core_modulus_pa", &model::BeamGeometry::core_modulus_pa, nullptr},
    {"core_density", &model::BeamGeometry::core_density, nullptr},
    {"mfc_modulus_pa", &model::BeamGeometry::mfc_modulus_pa, nullptr},
    {"mfc_density", &model::BeamGeometry::mfc_density, nullptr},
    {"d33_m_per_v", &model::BeamGeometry::d33_m_per_v, nullptr},
    {"electrode_spacing_m", &model::BeamGeometry::electrode_spacing_m, nullptr},
    {"n_active", nullptr, &model::BeamGeometry::n_active},
    {"n_tip", nullptr, &model::BeamGeometry::n_tip},
};

const GeometryField* FindGeometryField(const std::string& name) {
  for (const auto& f : kGeometryFields)
    if (name == f.name) return &f;
  return nullptr;
}

std::string GeometryFieldNames() {
  std::string s;
  for (const auto& f : kGeometryFields) s += (s.empty() ? "" : ", ") + std::string(f.name);
  return s;
}

/// Applies the overrides; the error names "hgann.geometry.<field>".
Status ApplyGeometry(const std::map<std::string, double>& overrides, model::BeamGeometry* g) {
  for (const auto& [name, value] : overrides) {
    const std::string field = "hgann.geometry." + name;
    const GeometryField* f = FindGeometryField(name);
    if (!f)
      return InvalidArgument(
          FieldError(field, value, "unknown field (known: " + GeometryFieldNames() + ")"));
    if (f->real) {
      g->*(f->real) = value;
    } else {
      if (!(std::isfinite(value) && value >= 0 && value <= 1e6 && value == std::floor(value)))
        return InvalidArgument(FieldError(field, value, "must be a whole number"));
      g->*(f->count) = static_cast<int>(value);
    }
  }
  if (Status s = g->Validate(); !s.ok()) return InvalidArgument("hgann.geometry." + s.message());
  return Status::Ok();
}

std::string Num(double x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}

int NameIndex(const std::string& name) {
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    if (name == model::OutputName(k)) return k;
  return -1;
}

std::string OutputNames() {
  std::string s;
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    s += (k ? ", " : "") + std::string(model::OutputName(k));
  return s;
}

/// The first non-finite sample of `v`, checked as "<field>[k] = nan: must be finite".
void RequireFiniteSamples(Violations& c, const std::string& field, const std::vector<double>& v) {
  for (size_t k = 0; k < v.size(); ++k) {
    if (!std::isfinite(v[k])) {
      c.Require(false, field + "[" + std::to_string(k) + "]", v[k], "must be finite");
      return;  // one per series: a file of NaNs must not flood the answer
    }
  }
}

}  // namespace

Status HgannRanges(const HgannProblem& h, model::ParameterRanges* ranges) {
  const auto preset = RangesPreset(h.ranges_preset);
  if (!preset)
    return InvalidArgument(
        FieldError("hgann.ranges_preset", "\"" + h.ranges_preset + "\"", kRangesPresetRule));
  *ranges = *preset;
  std::set<std::string> seen;
  for (size_t i = 0; i < h.ranges.size(); ++i) {
    const ParameterRange& r = h.ranges[i];
    const std::string f = "hgann.ranges[" + std::to_string(i) + "]";
    const int k = NameIndex(r.name);
    if (k < 0)
      return InvalidArgument(
          FieldError(f + ".name", "\"" + r.name + "\"", "must be one of " + OutputNames()));
    if (!seen.insert(r.name).second)
      return InvalidArgument(FieldError(f + ".name", r.name, "is given twice"));
    if (!std::isfinite(r.min))
      return InvalidArgument(FieldError(f + ".min", r.min, "must be finite"));
    if (!(std::isfinite(r.max) && r.max >= r.min))
      return InvalidArgument(
          FieldError(f + ".max", r.max, "must be finite and >= min (" + Num(r.min) + ")"));
    (*ranges)[k] = {r.min, r.max};
  }
  return ranges->Validate();
}

/// hgann.next_candidates: at most kMaxNextCandidates points, each V and f finite and > 0.
void RequireNextCandidates(Violations& c, const HgannProblem& h) {
  c.Require(h.next_candidates.size() <= job::kMaxNextCandidates, "hgann.next_candidates",
            std::to_string(h.next_candidates.size()) + " points",
            "must be at most " + std::to_string(job::kMaxNextCandidates));
  for (size_t i = 0; i < h.next_candidates.size(); ++i) {
    const auto& [v, f] = h.next_candidates[i];
    const std::string at = "hgann.next_candidates[" + std::to_string(i) + "]";
    c.Require(std::isfinite(v) && v > 0, at + ".amplitude_v", v, "must be finite and > 0 [V]");
    c.Require(std::isfinite(f) && f > 0, at + ".frequency_hz", f, "must be finite and > 0 [Hz]");
  }
}

std::vector<FieldViolation> ValidateHgannProblem(const HgannProblem& h) {
  Violations c;
  c.Require(h.case_set_dir.empty(), "hgann.case_set_dir", "\"" + h.case_set_dir + "\"",
            "is read by the client (piezoid submit), which embeds the cases: a master never reads "
            "client paths");
  c.Require(h.source.size() <= kMaxSourceChars, "hgann.source", h.source.size(),
            "must be <= " + std::to_string(kMaxSourceChars) + " characters");
  c.Require(!h.cases.empty(), "hgann.cases", "[]",
            "needs at least one case with role CASE_ROLE_TRAIN");
  c.Require(h.cases.size() <= kMaxCases, "hgann.cases", h.cases.size(),
            "at most " + std::to_string(kMaxCases) + " cases");
  const bool given = h.saturation == HgannProblem::Saturation::kGiven;
  int training = 0;
  std::set<int> numbers;
  for (size_t i = 0; i < h.cases.size() && i < kMaxCases; ++i) {
    const HgannCaseSpec& x = h.cases[i];
    const std::string f = "hgann.cases[" + std::to_string(i) + "]";
    c.Require(x.number > 0, f + ".number", x.number, "must be > 0");
    c.Require(x.number <= 0 || numbers.insert(x.number).second, f + ".number", x.number,
              "duplicates an earlier case's number");
    c.Require(std::isfinite(x.amplitude_v) && x.amplitude_v >= 0, f + ".amplitude_v", x.amplitude_v,
              "must be finite and >= 0 [V]");
    c.Require(std::isfinite(x.frequency_hz) && x.frequency_hz > 0, f + ".frequency_hz",
              x.frequency_hz, "must be finite and > 0 [Hz]");
    c.Require(x.role != CaseRole::kUnspecified, f + ".role", "CASE_ROLE_UNSPECIFIED",
              "must be CASE_ROLE_TRAIN, CASE_ROLE_VALIDATE or CASE_ROLE_TEST");
    training += x.role == CaseRole::kTrain;
    c.Require(std::isfinite(x.sample_rate_hz) && x.sample_rate_hz > 0, f + ".sample_rate_hz",
              x.sample_rate_hz, "must be finite and > 0 [Hz]");
    c.Require(x.angle_deg.size() >= 2 && x.angle_deg.size() <= kMaxSamplesPerCase,
              f + ".angle_deg.size()", x.angle_deg.size(),
              "must be in [2, " + std::to_string(kMaxSamplesPerCase) + "]");
    RequireFiniteSamples(c, f + ".angle_deg", x.angle_deg);
    c.Require(
        x.voltage_v.empty() || x.voltage_v.size() == x.angle_deg.size(), f + ".voltage_v.size()",
        x.voltage_v.size(),
        "must be 0 or the number of angle samples (" + std::to_string(x.angle_deg.size()) + ")");
    RequireFiniteSamples(c, f + ".voltage_v", x.voltage_v);
    if (given) {
      c.Require(x.b1.has_value(), f + ".b1", "unset",
                "is required with saturation SATURATION_GIVEN");
      c.Require(x.b2.has_value(), f + ".b2", "unset",
                "is required with saturation SATURATION_GIVEN");
      if (x.b1)
        c.Require(std::isfinite(*x.b1) && *x.b1 > 0, f + ".b1", *x.b1,
                  "must be finite and > 0 [deg]");
      if (x.b2)
        c.Require(std::isfinite(*x.b2) && *x.b2 < 0, f + ".b2", *x.b2,
                  "must be finite and < 0 [deg]");
    } else {
      c.Require(!x.b1 && !x.b2, f + (x.b1 ? ".b1" : ".b2"), x.b1 ? *x.b1 : x.b2.value_or(0),
                "set only with saturation SATURATION_GIVEN (the default fits b1, b2 from the "
                "measured extremes)");
      bool finite = true;
      double lo = 0, hi = 0;
      for (double y : x.angle_deg) {
        finite = finite && std::isfinite(y);
        lo = std::min(lo, y);
        hi = std::max(hi, y);
      }
      if (finite && x.angle_deg.size() >= 2) {
        c.Require(
            hi > 0, f + ".angle_deg", "max " + std::to_string(hi),
            "never rises above 0, so b1 cannot be fitted from the extremes (use SATURATION_GIVEN)");
        c.Require(
            lo < 0, f + ".angle_deg", "min " + std::to_string(lo),
            "never falls below 0, so b2 cannot be fitted from the extremes (use SATURATION_GIVEN)");
      }
    }
  }
  if (!h.cases.empty())
    c.Require(training > 0, "hgann.cases", std::to_string(h.cases.size()) + " cases",
              "needs at least one case with role CASE_ROLE_TRAIN");
  c.Require(std::isfinite(h.spread_penalty) && h.spread_penalty >= 0, "hgann.spread_penalty",
            h.spread_penalty, "must be finite and >= 0 [deg^2]");
  c.Require(RangesPreset(h.ranges_preset).has_value(), "hgann.ranges_preset",
            "\"" + h.ranges_preset + "\"", kRangesPresetRule);
  c.Require(job::HgannSearchPreset(h.preset).has_value(), "hgann.preset", "\"" + h.preset + "\"",
            job::kHgannPresetRule);
  RequireNextCandidates(c, h);
  std::set<std::string> seen;
  for (size_t i = 0; i < h.ranges.size(); ++i) {
    const ParameterRange& r = h.ranges[i];
    const std::string f = "hgann.ranges[" + std::to_string(i) + "]";
    c.Require(NameIndex(r.name) >= 0, f + ".name", "\"" + r.name + "\"",
              "must be one of " + OutputNames());
    c.Require(NameIndex(r.name) < 0 || seen.insert(r.name).second, f + ".name", r.name,
              "is given twice");
    c.Require(std::isfinite(r.min), f + ".min", r.min, "must be finite");
    c.Require(!std::isfinite(r.min) || (std::isfinite(r.max) && r.max >= r.min), f + ".max", r.max,
              "must be finite and >= min (" + Num(r.min) + ")");
  }
  bool geometry_named = true;
  for (const auto& [name, value] : h.geometry) {
    const std::string f = "hgann.geometry." + name;
    const GeometryField* g = FindGeometryField(name);
    c.Require(g != nullptr, f, value, "unknown field (known: " + GeometryFieldNames() + ")");
    if (g && !g->real)
      c.Require(std::isfinite(value) && value >= 0 && value <= 1e6 && value == std::floor(value), f,
                value, "must be a whole number");
    geometry_named = geometry_named && g != nullptr;
  }
  model::BeamGeometry geometry;
  if (geometry_named) {
    if (Status s = ApplyGeometry(h.geometry, &geometry); !s.ok()) {
      const std::string m = s.message();
      if (m.find("whole number") == std::string::npos) c.Add(m.substr(0, m.find(" = ")), m);
    }
  }
  if (c.out.empty()) {
    // Everything the fields say is fine: what remains is the problem as a whole (e.g. a record
    // whose sample count does not match its drive).
    HgannFitnessConfig config;
    if (Status s = HgannConfigFromProblem(h, &config); !s.ok())
      c.Add("hgann", "hgann: " + s.message());
  }
  return c.out;
}

io::CaseSet HgannCaseSet(const HgannProblem& h) {
  io::CaseSet set;
  set.dir = h.source;
  io::BenchReadOptions
      options;  // the spec's samples are the measured ones: no stated length or drive to check
  options.cycles = 0;
  options.check_voltage = false;
  for (size_t i = 0; i < h.cases.size(); ++i) {
    set.cases.push_back(
        io::MakeBenchCase(io::SamplesOfSpecCase(h.cases[i]), options,
                          io::SpecCaseWhere("hgann.cases[" + std::to_string(i) + "]")));
  }
  return set;
}

Status HgannConfigFromProblem(const HgannProblem& h, HgannFitnessConfig* config) {
  try {
    model::ParameterRanges ranges;
    if (Status s = HgannRanges(h, &ranges); !s.ok()) return s;
    model::BeamGeometry geometry;
    if (Status s = ApplyGeometry(h.geometry, &geometry); !s.ok()) return s;
    const io::CaseSet set = HgannCaseSet(h);
    std::vector<model::SaturationPair> given;  // empty: from the measured extremes
    if (h.saturation == HgannProblem::Saturation::kGiven) {
      for (size_t i = 0; i < h.cases.size(); ++i) {
        if (!h.cases[i].b1 || !h.cases[i].b2)
          return InvalidArgument("hgann.cases[" + std::to_string(i) +
                                 "]: b1 and b2 are required with SATURATION_GIVEN");
        given.push_back({*h.cases[i].b1, *h.cases[i].b2});
      }
    }
    HgannFitnessConfig cfg = HgannConfigFromCaseSet(set, ranges, given);
    cfg.geometry = geometry;
    cfg.spread_penalty = h.spread_penalty;
    if (Status s = cfg.Validate(); !s.ok()) {
      // HgannFitnessConfig names its cases by position, as the spec does.
      std::string m = s.message();
      if (m.rfind("cases[", 0) == 0 || m.rfind("spread_penalty", 0) == 0) m = "hgann." + m;
      return InvalidArgument(m);
    }
    *config = std::move(cfg);
    return Status::Ok();
  } catch (const InputError& e) {
    return InvalidArgument(e.what());
  } catch (const std::exception& e) {
    return Internal(std::string("hgann: ") + e.what());
  }
}

HgannProblem HgannProblemFromCaseSet(const io::CaseSet& set) {
  HgannProblem h;
  h.source = set.dir.string();
  for (const io::BenchCase& b : set.cases) {
    HgannCaseSpec x;
    x.number = b.number;
    x.amplitude_v = b.amplitude_v;
    x.frequency_hz = b.frequency_hz;
    x.role = b.role;
    x.sample_rate_hz = b.sample_rate_hz;
    x.angle_deg = b.angle_deg;
    x.voltage_v = b.u;
    h.cases.push_back(std::move(x));
  }
  return h;
}

JobKind HgannJobKind() {
  JobKind k;
  k.name = "hgann";
  k.validate = [](const JobSpec& s) {
    return ValidateHgannProblem(std::get<HgannProblem>(s.problem));
  };
  k.layout = [](const JobSpec&, GenomeLayout* l) {
    l->bits = model::kChromosomeBits;
    l->reals = 0;
    return Status::Ok();
  };
  k.make_fitness = [](const JobSpec& s, std::unique_ptr<FitnessFunction>* f) -> Status {
    HgannFitnessConfig config;
    if (Status st = HgannConfigFromProblem(std::get<HgannProblem>(s.problem), &config); !st.ok())
      return st;
    try {
      *f = std::make_unique<HgannFitness>(std::move(config));
    } catch (const std::exception& e) {
      return InvalidArgument(std::string("hgann: ") + e.what());
    }
    return Status::Ok();
  };
  k.networks = [](const JobSpec& s, std::span<const Genome> genomes,
                  std::vector<model::Network>* out) {
    HgannFitnessConfig config;  // the normalisation and ranges the fitness decodes with
    if (Status st = HgannConfigFromProblem(std::get<HgannProblem>(s.problem), &config); !st.ok())
      return st;
    out->clear();
    for (const Genome& g : genomes) {
      if (Status st = model::ValidateChromosome(g.bits); !st.ok()) return st;
      out->push_back(model::DecodeChromosome(g.bits, config.normalization, config.ranges));
    }
    return Status::Ok();
  };
  k.move = [](const JobSpec& s, opt::GeneticAlgorithm::Move* out) -> Status {
    *out = nullptr;
    const HgannProblem& problem = std::get<HgannProblem>(s.problem);
    if (HgannOutputMoves(ToGaOptions(s, GenomeLayout{model::kChromosomeBits, 0}),
                         problem.spread_penalty) == 0)
      return Status::Ok();      // as identify: none unset without a spread penalty
    HgannFitnessConfig config;  // the normalisation and training drives the fitness uses
    if (Status st = HgannConfigFromProblem(problem, &config); !st.ok()) return st;
    *out = OutputMove(config);
    return Status::Ok();
  };
  k.repair = [](const JobSpec& s, opt::GeneticAlgorithm::Repair* out) -> Status {
    *out = nullptr;
    const HgannProblem& problem = std::get<HgannProblem>(s.problem);
    if (!HgannRepairsLoops(problem.preset)) return Status::Ok();
    HgannFitnessConfig config;  // the normalisation, ranges and points the fitness checks
    if (Status st = HgannConfigFromProblem(problem, &config); !st.ok()) return st;
    *out = LoopRepair(config);
    return Status::Ok();
  };
  k.seeds = [](const JobSpec& s, std::vector<Genome>* out) -> Status {
    out->clear();
    const HgannProblem& problem = std::get<HgannProblem>(s.problem);
    if (!problem.trend_seeds) return Status::Ok();
    HgannFitnessConfig config;
    if (Status st = HgannConfigFromProblem(problem, &config); !st.ok()) return st;
    try {
      const HgannFitness fitness(std::move(config));
      // One thread: the master's job thread (the result does not depend on it).
      *out = MakeTrendSeeds(fitness, TrendSeedOptions{}).genomes;
    } catch (const std::exception& e) {
      return InvalidArgument(std::string("hgann trend seeds: ") + e.what());
    }
    return Status::Ok();
  };
  k.committee = [](const JobSpec& s, const Genome& best, job::LawCommittee* out) -> Status {
    const HgannProblem& problem = std::get<HgannProblem>(s.problem);
    if (!problem.trend_seeds) return {StatusCode::kNotFound, "no trend seeds, no law"};
    HgannFitnessConfig config;
    if (Status st = HgannConfigFromProblem(problem, &config); !st.ok()) return st;
    try {
      const HgannFitness fitness(std::move(config));
      // As identify (hgann/identify.cc RunIdentify): the seeds' law, the best kept as a member,
      // the spec's candidates; the same whatever the thread count.
      const std::optional<TrendSeeds> seeds = MakeTrendSeeds(fitness, TrendSeedOptions{});
      const std::optional<LawCommittee> c = RunCommittee(
          fitness, seeds, fitness.Decode(best), problem.next_candidates, /*threads=*/1);
      if (!c) return {StatusCode::kNotFound, "the law could not be fitted"};
      *out = *c;
    } catch (const std::exception& e) {
      return InvalidArgument(std::string("hgann committee: ") + e.what());
    }
    return Status::Ok();
  };
  k.describe = [](const JobSpec&, const Genome& g) {
    return g.bits.size() == static_cast<size_t>(model::kChromosomeBits)
               ? model::DescribeChromosome(g.bits)
               : std::string();
  };
  return k;
}

}  // namespace pz::hgann
