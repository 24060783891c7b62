#include "diagnose/check.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "diagnose/fin_diagnose.h"
#include "records/registry.h"

namespace pz::diagnose {

CheckSummary::CheckSummary(CheckText t, const std::vector<model::EffectKind>& effects)
    : text(std::move(t)) {
  columns.push_back("none");
  for (model::EffectKind e : effects) columns.push_back(EffectName(e));
  columns.push_back("unexplained");
  confusion.assign(columns.size() - 1, std::vector<int>(columns.size(), 0));
}

int CheckSummary::EffectColumn(const std::string& effect) const {
  const auto at = std::find(columns.begin() + 1, columns.end() - 1, effect);
  if (at == columns.end() - 1)
    throw std::logic_error("calibration check: the effect '" + effect +
                           "' is not among the check's effects");
  return static_cast<int>(at - columns.begin());
}

int CheckSummary::Column(const std::string& verdict_kind, const std::string& named) const {
  if (verdict_kind == "unexplained") return static_cast<int>(columns.size()) - 1;
  if (verdict_kind != "effect" && verdict_kind != "inseparable") return 0;
  return EffectColumn(named);
}

void CheckSummary::Tally(CheckTrial t) {
  const std::string truth = EffectName(t.truth);
  const size_t row = t.truth.none() ? 0 : static_cast<size_t>(EffectColumn(truth));
  confusion[row][static_cast<size_t>(Column(t.verdict_kind, t.named))] += 1;
  t.correct = Add(t.truth.none(), t.significant, t.verdict_kind,
                  !t.truth.none() && t.named == truth, t.confidence);
  if (!t.truth.none() && t.correct && std::isfinite(t.closed)) closed.push_back(t.closed);
  trials.push_back(std::move(t));
}

CheckForm FinCheckForm(const diagnose::DiagnoseOptions& o, const synth::FinTrialOptions& trials) {
  ThrowIfError(o.Validate());
  CheckForm f;
  f.text = {.noun = "benches", .description_width = 70, .closed_per_trial = true};
  for (const auto& e : records::FinEffects()) f.effects.push_back(e.kind);
  f.draw = FinTrialDraw(trials);
  f.options = [o](int index) {
    diagnose::DiagnoseOptions od = o;
    od.seed = o.seed + static_cast<uint64_t>(index);
    return diagnose::RecordOptionsOf(od);
  };
  return f;
}

CheckForm RecordsCheckForm(const RecordsCheckOptions& o) {
  CheckForm f;
  f.text = {.noun = "records", .description_width = 42, .closed_per_trial = false};
  f.draw = RecordsTrialDraw(o.trials);  // first: names a family without a nominal set
  const std::shared_ptr<const records::Family> family =
      records::MakeFamily(o.trials.family, synth::SyntheticStackScale());
  for (model::EffectKind k : records::RecordEffects())
    if (!family->Excludes(k.name())) f.effects.push_back(k);
  RecordDiagnoseOptions d = o.diagnose;
  d.family = o.trials.family;
  d.candidates.clear();
  d.propose = false;
  f.options = [d](int) { return d; };
  return f;
}

CheckSummary RunCheck(const CheckForm& form, int trials, uint64_t seed,
                      const std::function<void(const CheckTrial&, int)>& on_trial) {
  if (trials < 1) throw InputError(FieldError("trials", trials, "must be >= 1"));
  const auto start = std::chrono::steady_clock::now();
  CheckSummary sum(form.text, form.effects);
  for (int i = 0; i < trials; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const synth::SyntheticTrial st = form.draw(seed + static_cast<uint64_t>(i));
    const RecordDiagnosis dg = DiagnoseRecords(st.set, form.options(i));
    CheckTrial t;
    static_cast<TrialVerdict&>(t) = TrialVerdictOf(dg);
    t.seed = st.seed;
    t.truth = st.truth;
    t.description = st.description;
    t.magnitude = st.magnitude;
    t.closed = dg.closed_total;
    t.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    sum.Tally(std::move(t));
    if (on_trial) on_trial(sum.trials.back(), i);
  }
  sum.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return sum;
}

}  // namespace pz::diagnose
