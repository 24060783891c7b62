#include "diagnose/fin_check.h"

#include <chrono>
#include <cmath>
#include <memory>

namespace pz::diagnose {

int CheckRows() { return static_cast<int>(model::EffectLibrary().size()) + 1; }

std::string CheckColumnName(int c) {
  if (c == UnexplainedColumn()) return "unexplained";
  return c == 0 ? "none" : model::EffectLibrary().at(static_cast<size_t>(c - 1)).name;
}

bool CheckTrial::correct() const {
  if (truth.none()) return verdict_kind == "none";
  return (verdict_kind == "effect" || verdict_kind == "inseparable") && named == truth;
}

int CheckColumn(const CheckTrial& t) {
  if (t.verdict_kind == "unexplained") return UnexplainedColumn();
  if (t.verdict_kind == "effect" || t.verdict_kind == "inseparable")
    return model::FinIndex(t.named);
  return 0;
}

void Tally(CheckSummary& s, const CheckTrial& t) {
  s.confusion[static_cast<size_t>(model::FinIndex(t.truth))][static_cast<size_t>(CheckColumn(t))] +=
      1;
  s.Add(t.truth.none(), t.significant, t.verdict_kind, !t.truth.none() && t.named == t.truth,
        t.confidence);
  if (!t.truth.none() && t.correct() && std::isfinite(t.closed)) s.closed.push_back(t.closed);
  s.trials.push_back(t);
}

CheckSummary RunCheck(int trials, uint64_t seed, const DiagnoseOptions& o,
                      const SyntheticOptions& so,
                      const std::function<void(const CheckTrial&, int)>& on_trial) {
  if (trials < 1) throw InputError(FieldError("trials", trials, "must be >= 1"));
  ThrowIfError(o.Validate());
  const auto start = std::chrono::steady_clock::now();
  auto plant = std::make_shared<const model::BimorphPlant>();
  CheckSummary summary;
  for (int i = 0; i < trials; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    SyntheticTrial st = MakeSyntheticTrial(*plant, seed + static_cast<uint64_t>(i), so);
    CheckTrial t;
    t.seed = st.seed;
    t.truth = st.truth;
    t.truth_description = st.Describe();
    t.magnitude = st.magnitude;
    const DiagnosisModel m(plant, std::move(st.cases), o.sim);
    DiagnoseOptions od = o;
    od.seed = o.seed + static_cast<uint64_t>(i);
    const records::RecordDiagnosis d = DiagnoseBench(m, od).records;
    t.verdict_kind = d.verdict_kind;
    t.named = d.named_effects.empty() ? model::EffectKind() : d.named_effects.front();
    t.confidence = d.confidence;
    t.significant = d.significant;
    t.rms_ratio = d.rms_ratio;
    t.closed = d.closed_total;
    t.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    Tally(summary, t);
    if (on_trial) on_trial(t, i);
  }
  summary.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace pz::diagnose
