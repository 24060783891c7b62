#include "complete/job_kind.h"

#include <climits>
#include <cmath>
#include <sstream>

#include "model/saturation.h"
#include "opt/inline_evaluator.h"
#include "records/criterion.h"
#include "records/registry.h"
#include "records/spectrum_solve.h"

namespace pz::complete {
namespace {

using job::CompleteModelProblem;
using job::CompleteModelRecord;
using job::FieldViolation;
using Family = CompleteModelProblem::Family;
using SpecInterpolation = CompleteModelProblem::Interpolation;
using SpecCriterion = CompleteModelProblem::Criterion;

std::string Num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

bool IsStack(Family f) { return f == Family::kStackBoucWen || f == Family::kStackBacklashLike; }

int Substeps(const CompleteModelProblem& p) {
  return p.substeps > 0 ? p.substeps : p.family == Family::kBwOscillator ? 4 : 2;
}

records::DataScale ScaleOf(const CompleteModelProblem& p) {
  records::DataScale s;
  if (p.scale.size() != 9) throw InputError("complete_model.scale: 9 values expected");
  s.u_min = p.scale[0];
  s.u_max = p.scale[1];
  s.u_half = p.scale[2];
  s.y_half = p.scale[3];
  s.gain = p.scale[4];
  s.polarity = p.scale[5] < 0 ? -1 : 1;
  s.f_dom = p.scale[6];
  s.fs = p.scale[7];
  s.duration = p.scale[8];
  return s;
}

records::EffectSimOptions FinSimOf(const CompleteModelProblem& p) {
  records::EffectSimOptions o;
  if (!p.fin_sim) return o;
  o.oversample = p.fin_sim->oversample;
  o.rtol = p.fin_sim->rtol;
  o.atol = p.fin_sim->atol;
  o.max_steps = static_cast<long>(p.fin_sim->max_steps);
  o.force_cvode = p.fin_sim->force_cvode;
  return o;
}

std::shared_ptr<records::RecordModel> RecordModelOf(const CompleteModelProblem& p) {
  const records::DataScale scale = ScaleOf(p);
  records::FamilyOptions fo;
  fo.substeps = Substeps(p);
  fo.pi_operators = p.pi_operators;
  if (!p.initial_state.empty())
    fo.initial_state = model::ParseInitialState(p.initial_state, "complete_model.initial_state");
  fo.bench_form = p.bench_form;
  fo.fin_sim = FinSimOf(p);
  std::shared_ptr<const records::Family> fam = records::MakeFamily(p.record_family, scale, fo);
  std::vector<records::EffectKind> effects;
  for (const std::string& e : p.effects) {
    // The bench form takes the fin's effects, beam ones included, in the order given (its
    // EffectBox names one it does not take); the records families their drive and output ones.
    const model::EffectDef* d = p.bench_form ? model::FindEffect(e) : nullptr;
    effects.push_back(d ? records::EffectKind(*d) : records::ParseEffect(e));
  }
  return std::make_shared<records::RecordModel>(fam, effects, scale);
}

std::vector<std::string> ParameterNames(const CompleteModelProblem& p) {
  const Family f = p.family;
  if (f == Family::kBwOscillator) return model::BwIdentifiableNames();
  if (f == Family::kRecords) {
    try {
      const auto model = RecordModelOf(p);  // alive through the loop (a temporary would not be)
      std::vector<std::string>
          names;  // the searched ones (a creep spectrum on a linear family is solved)
      for (size_t i : records::SearchedParams(*model)) names.push_back(model->params()[i].name);
      return names;
    } catch (const InputError&) {
      return {};
    }
  }
  return {};
}

records::Criterion CriterionOf(SpecCriterion c) {
  switch (c) {
    case SpecCriterion::kIae:
      return records::Criterion::kIae;
    case SpecCriterion::kSse:
      return records::Criterion::kSse;
    case SpecCriterion::kRmse:
      return records::Criterion::kRmse;
    case SpecCriterion::kMax:
      return records::Criterion::kMax;
  }
  return records::Criterion::kIae;
}

SpecCriterion SpecOf(records::Criterion c) {
  switch (c) {
    case records::Criterion::kSse:
      return SpecCriterion::kSse;
    case records::Criterion::kRmse:
      return SpecCriterion::kRmse;
    case records::Criterion::kMax:
      return SpecCriterion::kMax;
    default:
      return SpecCriterion::kIae;
  }
}

// A records spec with a window is scored by its criterion over it (records/criterion.h); without
// one, by the MSE over the records' scored samples.
bool Windowed(const CompleteModelProblem& p) { return p.t0_s != 0 || p.t1_s != 0; }

// Owns the records and the model its fitness points to.
class OwningRecordFitness final : public opt::FitnessFunction {
 public:
  explicit OwningRecordFitness(const CompleteModelProblem& p) : model_(RecordModelOf(p)) {
    for (const CompleteModelRecord& c : p.records) {
      io::Record r;
      r.name = c.name;
      r.u = c.input;
      r.y = c.output;
      r.dt = c.dt_s;
      r.t.resize(r.u.size());
      for (size_t k = 0; k < r.t.size(); ++k) r.t[k] = static_cast<double>(k) * r.dt;
      r.first_scored = c.first_counted;
      r.end_scored = c.end_counted;
      r.rest_samples = c.rest_samples;
      r.offset_mode = static_cast<io::OffsetMode>(c.offset_mode);
      r.offset = c.offset;
      if (c.sinusoid)
        r.sinusoid = {static_cast<int>(c.sinusoid->case_number), c.sinusoid->amplitude_v,
                      c.sinusoid->frequency_hz, c.sinusoid->cycles, c.sinusoid->sample_rate_hz};
      records_.push_back(std::move(r));
    }
    std::vector<const io::Record*> ptrs;
    for (const auto& r : records_) ptrs.push_back(&r);
    if (Windowed(p)) {
      fitness_ = std::make_unique<records::CriterionFitness>(
          *model_, ptrs,
          records::CriterionOptions{CriterionOf(p.criterion), p.t0_s, p.t1_s, p.error_cost});
    } else {
      auto f = std::make_unique<records::RecordFitness>(*model_, ptrs);
      // The polish's residual vectors over the records fitness (kept alive beside them).
      if (p.residuals) residuals_ = std::make_unique<records::RecordResidualFitness>(*f);
      fitness_ = std::move(f);
    }
    if (residuals_)
      evaluated_ = residuals_.get();
    else
      evaluated_ = fitness_.get();
  }
  opt::FitnessResult Evaluate(const opt::Genome& g) const override {
    return evaluated_->Evaluate(g);
  }
  // The records fitness's lanes (a family that runs parameter sets side by side): a worker's
  // compute thread takes that many genomes of a lease at a time.
  int lanes() const override { return evaluated_->lanes(); }
  void EvaluateMany(std::span<const opt::Genome* const> genomes,
                    std::span<opt::FitnessResult> out) const override {
    evaluated_->EvaluateMany(genomes, out);
  }

 private:
  std::shared_ptr<records::RecordModel> model_;
  std::vector<io::Record> records_;
  std::unique_ptr<opt::FitnessFunction> fitness_;
  std::unique_ptr<records::RecordResidualFitness> residuals_;  ///< `residuals` only
  const opt::FitnessFunction* evaluated_ = nullptr;            ///< residuals_ or fitness_
};

model::InputInterpolation InterpolationOf(SpecInterpolation i) {
  switch (i) {
    case SpecInterpolation::kZoh:
      return model::InputInterpolation::kZeroOrderHold;
    case SpecInterpolation::kLinear:
      return model::InputInterpolation::kLinear;
    case SpecInterpolation::kSpline:
      return model::InputInterpolation::kCubicSpline;
    case SpecInterpolation::kFourier:
      return model::InputInterpolation::kPeriodicFourier;
  }
  return model::InputInterpolation::kCubicSpline;
}

SpecInterpolation SpecOf(model::InputInterpolation i) {
  switch (i) {
    case model::InputInterpolation::kZeroOrderHold:
      return SpecInterpolation::kZoh;
    case model::InputInterpolation::kLinear:
      return SpecInterpolation::kLinear;
    case model::InputInterpolation::kCubicSpline:
      return SpecInterpolation::kSpline;
    case model::InputInterpolation::kPeriodicFourier:
      return SpecInterpolation::kFourier;
  }
  return SpecInterpolation::kSpline;
}

// The benchmark's identification a BW_OSCILLATOR spec describes (the records as the client's).
std::unique_ptr<BwTraining> BwTrainingOf(const CompleteModelProblem& p) {
  std::vector<io::Record> records;
  for (const CompleteModelRecord& r : p.records)
    records.push_back(MakeBwRecord(r.name, model::CaseRole::kTrain, r.input, r.output,
                                   r.first_counted, r.sample_rate_hz));
  return std::make_unique<BwTraining>(
      std::move(records),
      BwProtocol(Substeps(p), InterpolationOf(p.interpolation), p.period_samples), p.error_cost);
}

Status Build(const CompleteModelProblem& p, std::unique_ptr<opt::FitnessFunction>* out) {
  try {
    if (p.family == Family::kBwOscillator)
      *out = BwTrainingOf(p);
    else if (p.family == Family::kRecords)
      *out = std::make_unique<OwningRecordFitness>(p);
    else
      return InvalidArgument(
          "complete_model.family = COMPLETE_MODEL_FAMILY_UNSPECIFIED: must be set");
  } catch (const InputError& e) {
    return InvalidArgument(std::string("complete_model: ") + e.what());
  }
  return Status::Ok();
}

// The largest prime factor of n (n ≥ 1).
uint64_t LargestPrimeFactor(uint64_t n) {
  uint64_t largest = 1;
  for (uint64_t f = 2; f * f <= n; ++f)
    while (n % f == 0) {
      largest = f;
      n /= f;
    }
  return std::max(largest, n);
}

// The FFT of the Fourier interpolation costs O(period · largest prime factor): a period with a
// large prime factor would keep a worker busy for hours.
constexpr uint64_t kMaxPeriodPrimeFactor = 1000;

// bimorph-fin's bench form: its family, no window, its simulator's options; its fields nowhere
// else.
template <typename Add>
void CheckBenchForm(const CompleteModelProblem& p, Add&& add) {
  if (!p.bench_form) {
    if (p.fin_sim)
      add("complete_model.fin_sim", "set",
          "only bimorph-fin's bench form (bench_form) runs the fin's simulator: leave unset");
    return;
  }
  if (p.record_family != "bimorph-fin")
    add("complete_model.bench_form", "true",
        "only bimorph-fin has a bench form (record_family = '" + p.record_family + "')");
  if (Windowed(p))
    add("complete_model.t0_s", Num(p.t0_s) + ", t1_s = " + Num(p.t1_s),
        "the bench form's cost is the sum of squared errors over the records: leave both unset");
  if (const Status s = FinSimOf(p).Validate(); !s.ok())
    add("complete_model.fin_sim", "{...}", s.message());
}

// A bench-form record: its stated sinusoid, which has the record's samples, and saturations b1, b2
// from its measured extremes; no sinusoid elsewhere.
template <typename Add>
void CheckSinusoid(const CompleteModelProblem& p, const CompleteModelRecord& r,
                   const std::string& f, Add&& add) {
  if (!p.bench_form) {
    if (r.sinusoid)
      add(f + ".sinusoid", "set",
          "only bimorph-fin's bench form (bench_form) simulates a stated sinusoid: leave unset");
    return;
  }
  if (!r.sinusoid) {
    add(f + ".sinusoid", "unset",
        "bimorph-fin's bench form simulates each record's stated sinusoid: required");
    return;
  }
  const CompleteModelRecord::Sinusoid& st = *r.sinusoid;
  const model::Sinusoid d{st.amplitude_v, st.frequency_hz, st.cycles, st.sample_rate_hz};
  const std::string g = f + ".sinusoid";
  if (st.case_number < 0 || st.case_number > INT_MAX)
    add(g + ".case_number", std::to_string(st.case_number), "must be <= 2147483647");
  else if (const Status s = d.Validate(); !s.ok())
    add(g, "{V, f, cycles, fs}", s.message());
  else if (static_cast<size_t>(d.NumSamples()) != r.input.size())
    add(g,
        Num(st.cycles) + " cycles at " + Num(st.frequency_hz) + " Hz, fs " +
            Num(st.sample_rate_hz) + " Hz",
        "has " + std::to_string(d.NumSamples()) + " samples, the record " +
            std::to_string(r.input.size()) + " (the bench form's records are sent whole)");
  try {  // the form's saturations (NaN outputs are named by the record's checks)
    bool finite = true;
    for (double y : r.output) finite = finite && std::isfinite(y);
    if (finite) model::SaturationFromExtremes(r.output);
  } catch (const InputError& e) {
    add(f + ".output", std::to_string(r.output.size()) + " samples",
        std::string("no saturations b1, b2 from its extremes: ") + e.what());
  }
}

// The RECORDS family: the family, effects and scale build a model; every record's window, rest and
// offset are in range.
template <typename Add>
void CheckRecordFields(const CompleteModelProblem& p, Add&& add) {
  CheckBenchForm(p, add);
  if (Windowed(p) && p.residuals)
    add("complete_model.residuals", "true",
        "only the MSE over the records' scored samples has residual vectors (no window: leave "
        "t0_s, t1_s unset, or residuals false)");
  if (Windowed(p)) {
    if (!(std::isfinite(p.t0_s) && p.t0_s >= 0))
      add("complete_model.t0_s", Num(p.t0_s), "must be finite and >= 0");
    if (!(std::isfinite(p.t1_s) && p.t1_s > p.t0_s))
      add("complete_model.t1_s", Num(p.t1_s), "must be finite and > t0_s = " + Num(p.t0_s));
  } else if (p.criterion != SpecCriterion::kIae) {
    add("complete_model.criterion", records::CriterionName(CriterionOf(p.criterion)),
        "without a window (t0_s, t1_s) records are scored by the MSE: leave unset");
  }
  if (p.interpolation != SpecInterpolation::kSpline)
    add("complete_model.interpolation",
        model::InputInterpolationName(InterpolationOf(p.interpolation)),
        "only the oscillator's input is interpolated (the records families take it as sampled): "
        "leave unset");
  if (p.period_samples != 0)
    add("complete_model.period_samples", std::to_string(p.period_samples),
        "only the oscillator's FOURIER input has periods: must be 0");
  if (p.pi_operators < 1 || p.pi_operators > 10000)
    add("complete_model.pi_operators", std::to_string(p.pi_operators), "must be in [1, 10000]");
  if (p.scale.size() != 9) {
    add("complete_model.scale", std::to_string(p.scale.size()) + " values",
        "must hold 9 (u_min … duration)");
  } else {
    for (size_t i = 0; i < 9; ++i)
      if (!std::isfinite(p.scale[i]))
        add("complete_model.scale[" + std::to_string(i) + "]", Num(p.scale[i]), "must be finite");
  }
  if (Substeps(p) < 1 || Substeps(p) > 512)
    add("complete_model.substeps", std::to_string(p.substeps), "must be in [1, 512] (0 = 2)");
  if (p.scale.size() == 9 && p.pi_operators >= 1 && p.pi_operators <= 10000) {
    try {
      RecordModelOf(p);
    } catch (const InputError& e) {
      add("complete_model.record_family", "'" + p.record_family + "'", e.what());
    }
  }
  for (size_t i = 0; i < p.records.size(); ++i) {
    const CompleteModelRecord& r = p.records[i];
    const std::string f = "complete_model.records[" + std::to_string(i) + "]";
    const size_t n = r.input.size();
    if (r.name.size() > 200)
      add(f + ".name", std::to_string(r.name.size()) + " characters", "must be <= 200");
    if (!(std::isfinite(r.dt_s) && r.dt_s > 0))
      add(f + ".dt_s", Num(r.dt_s), "must be finite and > 0");
    if (n < 2) add(f + ".input", std::to_string(n) + " samples", "needs >= 2");
    if (r.output.size() != n)
      add(f + ".output", std::to_string(r.output.size()) + " samples",
          "must have as many as input (" + std::to_string(n) + ")");
    for (size_t k = 0; k < n; ++k)
      if (!std::isfinite(r.input[k])) {
        add(f + ".input[" + std::to_string(k) + "]", Num(r.input[k]), "must be finite");
        break;
      }
    for (size_t k = 0; k < r.output.size(); ++k)
      if (!std::isfinite(r.output[k])) {
        add(f + ".output[" + std::to_string(k) + "]", Num(r.output[k]), "must be finite");
        break;
      }
    if (!(r.first_counted < r.end_counted && r.end_counted <= n))
      add(f + ".end_counted", std::to_string(r.end_counted),
          "must be > first_counted = " + std::to_string(r.first_counted) +
              " and <= " + std::to_string(n) + " samples");
    if (r.rest_samples < 1 || r.rest_samples > n)
      add(f + ".rest_samples", std::to_string(r.rest_samples),
          "must be in [1, " + std::to_string(n) + "]");
    if (r.offset_mode < 0 || r.offset_mode > 2)
      add(f + ".offset_mode", std::to_string(r.offset_mode), "must be 0, 1 or 2");
    if (!std::isfinite(r.offset)) add(f + ".offset", Num(r.offset), "must be finite");
    CheckSinusoid(p, r, f, add);
    if (Windowed(p) && std::isfinite(p.t0_s) && std::isfinite(p.t1_s) && std::isfinite(r.dt_s) &&
        r.dt_s > 0 && r.end_counted >= 1 && r.end_counted <= n) {
      const double end = static_cast<double>(r.end_counted - 1) * r.dt_s;
      if (!(std::min(p.t1_s, end) > p.t0_s))
        add(f, "ends at " + Num(end) + " s",
            "before the window start t0_s = " + Num(p.t0_s) + " s");
    }
  }
}

// Every rule of the spec, checked without building the models (the master never runs them):
// each violation named with its value.
std::vector<FieldViolation> CheckFields(const CompleteModelProblem& p) {
  std::vector<FieldViolation> v;
  auto add = [&](const std::string& field, const std::string& value, const std::string& rule) {
    v.push_back({field, field + " = " + value + ": " + rule});
  };
  if (p.family == Family::kUnspecified) return v;  // named by the generic validation
  if (p.family == Family::kRecords) {
    CheckRecordFields(p, add);
    return v;
  }
  if (IsStack(p.family)) {
    add("complete_model.family",
        p.family == Family::kStackBoucWen ? "STACK_BOUC_WEN" : "STACK_BACKLASH_LIKE",
        "the stack models are records families: family RECORDS with record_family 'stack-bouc-wen' "
        "or "
        "'backlash-like' (and the criterion's window)");
    return v;
  }
  // The Bouc–Wen oscillator of the benchmark protocol.
  if (p.residuals)
    add("complete_model.residuals", "true",
        "only the RECORDS family's fitness has residual vectors: leave unset");
  const int sub = Substeps(p);
  if (sub < 1 || sub > 1000)
    add("complete_model.substeps", std::to_string(p.substeps), "must be in [1, 1000] (0 = 4)");
  if (p.t0_s != 0 || p.t1_s != 0)
    add("complete_model.t0_s", Num(p.t0_s) + ", t1_s = " + Num(p.t1_s),
        "the oscillator has no window (its cost is the MSE over the counted samples): leave both "
        "unset");
  if (p.criterion != SpecCriterion::kIae)
    add("complete_model.criterion", records::CriterionName(CriterionOf(p.criterion)),
        "the oscillator's cost is the output-error MSE: leave criterion unset");
  if (p.interpolation != SpecInterpolation::kFourier && p.period_samples != 0)
    add("complete_model.period_samples", std::to_string(p.period_samples),
        "only the FOURIER input has periods");
  const size_t min_samples = p.interpolation == SpecInterpolation::kSpline ? 4 : 2;
  for (size_t i = 0; i < p.records.size(); ++i) {
    const CompleteModelRecord& r = p.records[i];
    const std::string f = "complete_model.records[" + std::to_string(i) + "]";
    const size_t n = r.input.size();
    if (r.name.size() > 200)
      add(f + ".name", std::to_string(r.name.size()) + " characters", "must be <= 200");
    const bool fs_ok = std::isfinite(r.sample_rate_hz) && r.sample_rate_hz > 0;
    if (!fs_ok) add(f + ".sample_rate_hz", Num(r.sample_rate_hz), "must be finite and > 0");
    if (n < min_samples)
      add(f + ".input", std::to_string(n) + " samples",
          "needs >= " + std::to_string(min_samples) +
              (min_samples == 4 ? " (the cubic-spline input)" : ""));
    if (r.output.size() != n)
      add(f + ".output", std::to_string(r.output.size()) + " samples",
          "must have as many as input (" + std::to_string(n) + ")");
    for (size_t k = 0; k < n; ++k)
      if (!std::isfinite(r.input[k])) {
        add(f + ".input[" + std::to_string(k) + "]", Num(r.input[k]), "must be finite");
        break;
      }
    for (size_t k = 0; k < r.output.size(); ++k)
      if (!std::isfinite(r.output[k])) {
        add(f + ".output[" + std::to_string(k) + "]", Num(r.output[k]), "must be finite");
        break;
      }
    if (n > 0 && r.first_counted >= n)
      add(f + ".first_counted", std::to_string(r.first_counted),
          "leaves no counted sample of " + std::to_string(n));
    const uint64_t period = p.period_samples > 0 ? p.period_samples : n;
    if (p.interpolation == SpecInterpolation::kFourier && n >= 2) {
      if (n % period != 0) {
        add(f + ".input", std::to_string(n) + " samples",
            "must be a whole number of periods (period_samples = " + std::to_string(period) + ")");
      } else if (LargestPrimeFactor(period) > kMaxPeriodPrimeFactor) {
        add(f + ".input", std::to_string(period) + " samples per period",
            "has the prime factor " + std::to_string(LargestPrimeFactor(period)) +
                " > 1000: the FOURIER input's FFT would be too slow (use SPLINE or a smoother "
                "period)");
      } else {
        // Every period equal to the first (model/bw_oscillator.h's rule, 1e-9 of the largest |u|).
        double scale = 0;
        for (double u : r.input) scale = std::max(scale, std::abs(u));
        for (size_t k = period; k < n; ++k)
          if (std::abs(r.input[k] - r.input[k % period]) > 1e-9 * scale) {
            add(f + ".input[" + std::to_string(k) + "]", Num(r.input[k]),
                "differs from input[" + std::to_string(k % period) +
                    "] = " + Num(r.input[k % period]) +
                    ": not periodic with period_samples = " + std::to_string(period));
            break;
          }
      }
    }
  }
  return v;
}

}  // namespace

job::CompleteModelProblem CompleteModelProblemOf(const BwTraining& training) {
  CompleteModelProblem p;
  p.family = Family::kBwOscillator;
  for (const io::Record& r : training.records())
    p.records.push_back({r.name, r.sample_rate_hz(), r.u, r.y, r.first_scored});
  const records::OscillatorOptions& o = training.options();
  p.substeps = static_cast<uint32_t>(o.rk4_steps);
  p.interpolation = SpecOf(o.interpolation);
  p.period_samples = o.period_samples;
  p.error_cost = training.penalty();
  return p;
}

namespace {

// A records problem; `cut`: without the part of each record's leading rest that is not scored.
CompleteModelProblem RecordsProblem(const records::RecordFitness& fitness, int pi_operators,
                                    bool cut) {
  CompleteModelProblem p;
  p.family = Family::kRecords;
  const records::RecordModel& m = fitness.model();
  p.record_family = m.family().name();
  for (records::EffectKind e : m.effects()) p.effects.push_back(records::EffectName(e));
  p.pi_operators = pi_operators;
  // The state the family was made with, so the workers' family starts where the client's does.
  p.initial_state = model::InitialStateName(m.family().initial_state());
  const records::DataScale& s = m.scale();
  p.scale = {s.u_min, s.u_max, s.u_half,  s.y_half, s.gain, static_cast<double>(s.polarity),
             s.f_dom, s.fs,    s.duration};
  // bimorph-fin's bench form simulates each record's stated sinusoid on all its samples, its
  // saturations from the whole output: its records are sent whole, with their sinusoid.
  const bool bench = m.family().simulates_records();
  p.bench_form = bench;
  for (const io::Record* r : fitness.records()) {
    const size_t from =
        cut && !bench ? std::min(std::max<size_t>(r->rest_samples, 1) - 1, r->first_scored) : 0;
    const size_t to = bench ? r->size() : r->end_scored;
    CompleteModelRecord c;
    c.name = r->name.substr(0, 200);
    c.sample_rate_hz = r->sample_rate_hz();
    c.input.assign(r->u.begin() + static_cast<std::ptrdiff_t>(from),
                   r->u.begin() + static_cast<std::ptrdiff_t>(to));
    c.output.assign(r->y.begin() + static_cast<std::ptrdiff_t>(from),
                    r->y.begin() + static_cast<std::ptrdiff_t>(to));
    if (bench) {
      const io::Record::StatedSinusoid& st = r->sinusoid;
      c.sinusoid = CompleteModelRecord::Sinusoid{st.case_number, st.amplitude_v, st.frequency_hz,
                                                 st.cycles, st.sample_rate_hz};
    }
    c.first_counted = r->first_scored - from;
    c.end_counted = r->end_scored - from;
    c.rest_samples = r->rest_samples - from;
    c.dt_s = r->dt;
    c.offset_mode = static_cast<int>(r->offset_mode);
    c.offset = r->offset;
    p.records.push_back(std::move(c));
  }
  return p;
}

}  // namespace

job::CompleteModelProblem CompleteModelProblemOf(const records::RecordFitness& fitness,
                                                 const records::FamilyOptions& options,
                                                 bool residuals) {
  CompleteModelProblem p = RecordsProblem(fitness, options.pi_operators, true);
  p.residuals = residuals;
  p.substeps = options.substeps;  // the workers' family integrates as the local one
  if (p.bench_form) {             // and simulates as the local one
    if (!options.bench_form)
      throw InputError(fitness.model().Describe() +
                       ": a bench-form model's evaluation needs the family options it was made "
                       "with (bench_form and its simulator's options), not another family's");
    const records::EffectSimOptions& o = options.fin_sim;
    p.fin_sim = CompleteModelProblem::FinSim{o.oversample, o.rtol, o.atol,
                                             static_cast<int64_t>(o.max_steps), o.force_cvode};
  }
  return p;
}

job::CompleteModelProblem CompleteModelProblemOf(const records::CriterionFitness& fitness,
                                                 const records::FamilyOptions& options) {
  const records::CriterionOptions& c = fitness.criterion();
  // A window is in each record's time from its first sample: windowed records are sent whole.
  CompleteModelProblem p = RecordsProblem(fitness.outputs(), options.pi_operators, !c.windowed());
  p.substeps = options.substeps;
  p.error_cost = c.error_cost;
  if (c.windowed()) {
    p.criterion = SpecOf(c.kind);
    p.t0_s = c.t0_s;
    p.t1_s = c.t1_s;
  }
  return p;
}

job::JobSpec CompleteModelJobSpec(job::CompleteModelProblem problem, const std::string& name) {
  job::JobSpec spec;
  spec.name = name.substr(0, 200);
  spec.seed = 0;
  spec.problem = std::move(problem);
  spec.limits.penalty_cost = opt::kDefaultErrorCost;
  return spec;
}

Status MakeCompleteModelFitness(const job::JobSpec& spec,
                                std::unique_ptr<opt::FitnessFunction>* out) {
  const auto* p = std::get_if<CompleteModelProblem>(&spec.problem);
  if (!p) return InvalidArgument("problem: not a complete_model spec");
  const std::vector<FieldViolation> v = CheckFields(*p);
  if (!v.empty()) return InvalidArgument(v.front().description);
  return Build(*p, out);
}

job::JobKind CompleteModelJobKind() {
  job::JobKind k;
  k.name = "complete_model";
  k.validate = [](const job::JobSpec& s) {
    std::vector<FieldViolation> v = CheckFields(std::get<CompleteModelProblem>(s.problem));
    if (s.ga)
      v.push_back(
          {"ga",
           "ga: the project GA searches binary genomes; a complete_model genome is the family's "
           "real "
           "parameters: drive it as an evaluation session (external; piezoid boucwen / committee "
           "--master)"});
    return v;
  };
  k.layout = [](const job::JobSpec& s, job::GenomeLayout* l) {
    const auto& p = std::get<CompleteModelProblem>(s.problem);
    const auto names = ParameterNames(p);
    if (names.empty()) {
      return InvalidArgument(
          p.family == Family::kRecords
              ? "complete_model: the records model '" + p.record_family +
                    "' has no searched parameter"
              : std::string(
                    "complete_model.family = COMPLETE_MODEL_FAMILY_UNSPECIFIED: must be set"));
    }
    l->bits = 0;
    l->reals = static_cast<int>(names.size());
    return Status::Ok();
  };
  k.make_fitness = [](const job::JobSpec& s, std::unique_ptr<opt::FitnessFunction>* f) {
    return MakeCompleteModelFitness(s, f);
  };
  k.describe = [](const job::JobSpec& s, const opt::Genome& g) {
    const auto names = ParameterNames(std::get<CompleteModelProblem>(s.problem));
    if (g.reals.size() != names.size()) return std::string();
    std::ostringstream os;
    os.precision(6);
    for (size_t i = 0; i < names.size(); ++i) os << (i ? " " : "") << names[i] << "=" << g.reals[i];
    return os.str();
  };
  return k;
}

}  // namespace pz::complete
