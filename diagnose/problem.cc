#include "diagnose/problem.h"

#include <algorithm>
#include <cmath>

#include "io/bench_data.h"
#include "model/saturation.h"

namespace pz::diagnose {

// ---- cases
// ---------------------------------------------------------------------------------------

DiagCase MakeCase(int number, const model::Sinusoid& drive, std::vector<double> measured,
                  bool training) {
  model::FinCase f = model::MakeFinCase(number, drive, std::move(measured), training);
  records::CaseNoise noise = records::EstimateCaseNoise(
      f.measured_deg, std::max(1, static_cast<int>(std::lround(drive.cycles))));
  return DiagCase{std::move(f), std::move(noise)};
}

std::vector<DiagCase> CasesFromCaseSet(const io::CaseSet& set) {
  std::vector<DiagCase> cases;
  int train = 0;
  for (const io::BenchCase& bc : set.cases) {
    const bool training = bc.role == io::CaseRole::kTrain;
    train += training;
    cases.push_back(MakeCase(bc.number, bc.Drive(), bc.angle_deg, training));
  }
  if (train == 0)
    throw InputError(set.dir.string() + ": no training case (role train) to identify on");
  if (train == static_cast<int>(cases.size()))
    throw InputError(set.dir.string() + ": no withheld case (role validate/test) to score on");
  return cases;
}

// ---- layout
// --------------------------------------------------------------------------------------

ParameterLayout::ParameterLayout(std::vector<model::EffectKind> structure)
    : structure_(std::move(structure)) {
  for (model::EffectKind k : structure_)
    size_ += static_cast<int>(model::GetEffectInfo(k).params.size());
}

void ParameterLayout::Decode(std::span<const double> x, model::BimorphParams* p,
                             std::vector<model::Effect>* effects) const {
  PZ_CHECK(x.size() == static_cast<size_t>(size_));
  p->mu = x[0];
  p->delta = x[1];
  p->alpha = x[2];
  p->beta = x[3];
  p->gamma = x[4];
  p->a1 = x[5];
  p->a2 = x[6];
  effects->clear();
  size_t i = kBase;
  for (model::EffectKind k : structure_) {
    model::Effect e;
    e.kind = k;
    const size_t n = model::GetEffectInfo(k).params.size();
    e.params.assign(x.begin() + static_cast<std::ptrdiff_t>(i),
                    x.begin() + static_cast<std::ptrdiff_t>(i + n));
    i += n;
    effects->push_back(std::move(e));
  }
}

std::string ParameterLayout::Describe() const {
  std::string s = "base";
  for (model::EffectKind k : structure_) s += std::string(" + ") + model::EffectName(k);
  return s;
}

// ---- model
// ---------------------------------------------------------------------------------------

DiagnosisModel::DiagnosisModel(std::shared_ptr<const model::BimorphPlant> plant,
                               std::vector<DiagCase> cases, model::EffectSimOptions sim)
    : plant_(std::move(plant)), cases_(std::move(cases)), sim_options_(sim) {
  PZ_CHECK(plant_ != nullptr);
  ThrowIfError(sim_options_.Validate());
  sim_ = std::make_unique<model::EffectSimulator>(*plant_);
  for (const DiagCase& c : cases_)
    (c.training ? n_train_ : n_withheld_) += static_cast<int>(c.measured_deg.size());
}

model::SimulationSummary DiagnosisModel::Simulate(const ParameterLayout& layout,
                                                  std::span<const double> x, size_t c,
                                                  std::vector<double>& angle) const {
  model::BimorphParams p;
  std::vector<model::Effect> effects;
  layout.Decode(x, &p, &effects);
  const DiagCase& dc = cases_[c];
  p.b1 = dc.b1;
  p.b2 = dc.b2;
  angle.resize(dc.measured_deg.size());
  return sim_->SimulateAngle(p, effects, dc.drive, angle, sim_options_);
}

}  // namespace pz::diagnose
