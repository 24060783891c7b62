#include "diagnose/check.h"

#include <algorithm>
#include <chrono>
#include <numbers>
#include <cmath>
#include <sstream>
#include <utility>

#include "diagnose/synthetic.h"
#include "opt/random.h"
#include "records/excitation.h"
#include "records/preisach_family.h"

namespace pz::records {

RecordsCheckSummary RunRecordsCheck(
    const RecordsCheckOptions& o,
    const std::function<void(const RecordsCheckTrial&, int)>& on_trial) {
  if (o.trials < 1) throw InputError(FieldError("trials", o.trials, "must be >= 1"));
  const auto start = std::chrono::steady_clock::now();
  const DataScale scale = SyntheticStackScale();
  std::shared_ptr<const Family> fam = MakeFamily(o.family, scale);
  const std::vector<double> nominal = fam->CheckNominal();
  if (nominal.empty()) {
    std::string with;
    for (const std::string& name : FamilyNames())
      if (!MakeFamily(name, scale)->CheckNominal().empty())
        with += (with.empty() ? "" : ", ") + name;
    throw InputError("diagnose-check --records-family: '" + o.family +
                     "' has no nominal parameter set for synthetic records (Family::CheckNominal; "
                     "families with one: " +
                     with + ")");
  }
  // The truths drawn: every records effect the family does not hold, but those that only records
  // at several rates identify (rate-dependence, records/excitation.h NeedsRateCoverage): the
  // trials' sine and triangle drives run at one rate, where the diagnosis does not offer them (it
  // does on the multisine drives: there they are candidates like any other).
  std::vector<EffectKind> kinds;
  const auto excluded = fam->excluded_effects();
  for (EffectKind k : RecordEffects())
    if (std::find(excluded.begin(), excluded.end(), k.name()) == excluded.end() &&
        !NeedsRateCoverage(k))
      kinds.push_back(k);
  RecordsCheckSummary sum;
  for (int i = 0; i < o.trials; ++i) {
    RecordsCheckTrial t;
    t.seed = o.seed + static_cast<uint64_t>(i);
    opt::Rng rng(t.seed * 104729 + 7);
    std::vector<double> p = nominal, weights;
    for (double& v : p) v *= UniformDraw(rng, 0.8, 1.25);
    if (fam->linear())
      weights = std::exchange(p, {});  // the truth's weights; p: the effect's parameters
    std::vector<EffectKind> effects;
    std::ostringstream desc;
    if (rng.Uniform01() >= o.none_probability) {
      const EffectKind e = kinds[rng.UniformBelow(kinds.size())];
      effects.push_back(e);
      t.truth = EffectName(e);
      model::TruthDraw draw([&rng] { return rng.Uniform01(); });
      const std::vector<double> truth = e->DrawRecordsTruth(draw, scale);
      if (truth.empty()) {
        throw InputError(std::string("diagnose-check --records: effect '") + EffectName(e) +
                         "' draws no truth (its DrawRecordsTruth in model/effect_library.cc)");
      }
      p.insert(p.end(), truth.begin(), truth.end());
      desc << t.truth << " " << p.back();
    } else {
      desc << "none";
    }
    DriveShape d;
    d.amplitude = 100;
    d.frequency_hz = 1;
    d.frequency_end_hz = 6;
    d.phase_rad = UniformDraw(rng, 0, 2 * std::numbers::pi);
    d.rest_s = 0.5;
    d.duration_s = 6;
    d.fs_hz = 500;
    d.seed = t.seed;
    const double w = rng.Uniform01();
    d.waveform = w < 0.4 ? Waveform::kSine : w < 0.7 ? Waveform::kMultisine : Waveform::kTriangle;
    desc << ", " << WaveformName(d.waveform);
    t.description = desc.str();
    RecordModel truth(fam, effects, scale);
    io::Record r =
        SynthesizeRecord(truth, p, weights, d, {UniformDraw(rng, -2, 2), 0.02, 0.005, t.seed},
                         "rec", model::CaseRole::kTrain);
    const double t0 = r.t[r.rest_samples] + 0.2, t2 = r.t.back(), t1 = t0 + 0.6 * (t2 - t0);
    io::RecordSet set;
    set.source = "synthetic";
    io::Record tr = r, wh = r;
    tr.name = "train";
    io::SetWindow(tr, t0, t1, 20, "train");
    wh.name = "withheld";
    wh.role = model::CaseRole::kValidate;
    io::SetWindow(wh, t1, t2, 20, "withheld");
    set.records = {tr, wh};
    RecordDiagnoseOptions dopt = o.diagnose;
    dopt.family = o.family;
    dopt.candidates.clear();
    dopt.propose = false;
    const RecordDiagnosis dg = DiagnoseRecords(set, dopt);
    static_cast<TrialVerdict&>(t) = TrialVerdictOf(dg);
    t.correct = sum.Add(t.truth == "none", dg.significant, dg.verdict_kind,
                        dg.named >= 0 && t.named == t.truth, t.confidence);
    sum.trials.push_back(t);
    if (on_trial) on_trial(t, i);
  }
  sum.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return sum;
}

}  // namespace pz::records
