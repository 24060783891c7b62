#include "records/model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pz::records {
const std::vector<EffectKind>& RecordEffects() {
  static const std::vector<EffectKind> kinds = [] {
    std::vector<EffectKind> r;
    for (const model::EffectDef* e : model::Effects())
      if (e->stage() != model::EffectStage::kBeam) r.push_back(*e);
    return r;
  }();
  return kinds;
}

std::vector<EffectInfo> EffectLibrary(const DataScale& s) {
  std::vector<EffectInfo> lib;
  for (EffectKind k : RecordEffects()) {
    EffectInfo e{k, k->name(), k->title(), k->equation(), {}, {}};
    try {
      e.params = k->Params(s);
    } catch (const InputError& x) {
      e.unsupported = x.what();
    }
    lib.push_back(std::move(e));
  }
  return lib;
}

const std::vector<std::string>& EffectNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> r;
    for (EffectKind k : RecordEffects()) r.push_back(k.name());
    return r;
  }();
  return names;
}

EffectKind ParseEffect(std::string_view name) {
  const model::EffectDef* e = model::FindEffect(name);
  if (e != nullptr && e->stage() != model::EffectStage::kBeam) return *e;
  std::string known;
  for (const auto& n : EffectNames()) known += (known.empty() ? "" : ", ") + n;
  if (e != nullptr) {
    throw InputError("effect '" + std::string(name) + "' acts on the beam (" + e->title() +
                     "): it runs on the bimorph-fin bench's beam (`piezoid diagnose --cases`); "
                     "records families take drive and output effects only (effects: " +
                     known +
                     "); bimorph-fin's bench form, on a fin bench read as records, takes it "
                     "(records/families.h FamilyOptions::bench_form)");
  }
  throw InputError("effect '" + std::string(name) + "' is unknown (effects: " + known + ")");
}

RecordModel::RecordModel(std::shared_ptr<const Family> family, std::vector<EffectKind> effects,
                         const DataScale& scale)
    : family_(std::move(family)), effects_(std::move(effects)), scale_(scale) {
  std::vector<EffectKind> sorted = effects_;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
    throw InputError("an effect is listed twice");
  }
  params_ = family_->params();
  forms_ = family_->search_forms();
  if (forms_.size() != params_.size()) forms_.assign(params_.size(), Family::SearchForm{});
  if (family_->simulates_records()) {  // its own effects in its boxes, in the order given
    scale_.polarity = 1;               // its output is the response, sign included
    for (EffectKind e : effects_) {
      defs_.push_back(e.def());
      effect_offset_.push_back(params_.size() - family_->params().size());
      for (ParamInfo q : family_->EffectBox(e, &forms_)) {
        q.name = std::string(EffectName(e)) + "." + q.name;
        params_.push_back(q);
      }
      forms_.resize(params_.size());
    }
    return;
  }
  effects_ = std::move(sorted);
  for (EffectKind e : effects_) {
    if (e.none() || e->stage() == model::EffectStage::kBeam)
      throw InputError(std::string("effect '") + e.name() + "' is not a records effect");
    defs_.push_back(e.def());
    effect_offset_.push_back(params_.size() - family_->params().size());
    for (const ParamInfo& p : defs_.back()->Params(scale_)) {
      ParamInfo q = p;
      q.name = std::string(EffectName(e)) + "." + p.name;
      params_.push_back(q);
    }
  }
  forms_.resize(params_.size());
}

bool RecordModel::has_ratio() const {
  for (const Family::SearchForm& f : forms_)
    if (f.ratio_of >= 0) return true;
  return false;
}

std::string RecordModel::Describe() const {
  std::string s = family_->name();
  for (EffectKind e : effects_) s += std::string(" + ") + EffectName(e);
  return s;
}

std::pair<size_t, size_t> RecordModel::EffectParams(EffectKind e) const {
  for (size_t i = 0; i < effects_.size(); ++i) {
    if (effects_[i] != e) continue;
    const size_t end =
        i + 1 < effects_.size() ? effect_offset_[i + 1] : params_.size() - family_param_count();
    return {family_param_count() + effect_offset_[i], end - effect_offset_[i]};
  }
  return {0, 0};
}

void RecordModel::EffectiveDrive(const io::Record& r, std::span<const double> ep, size_t from,
                                 size_t end, std::vector<double>& ue) const {
  ue.assign(r.u.begin() + static_cast<std::ptrdiff_t>(from),
            r.u.begin() + static_cast<std::ptrdiff_t>(end));
  for (size_t i = 0; i < defs_.size(); ++i)
    if (defs_[i]->stage() == model::EffectStage::kDrive)
      defs_[i]->ApplyDrive(ep.subspan(effect_offset_[i]), r.dt, ue);
}

void RecordModel::ApplyOutputEffects(const io::Record& r, std::span<const double> ep, size_t,
                                     std::span<double> y) const {
  if (y.empty()) return;
  // Time from the window's start on the record's uniform grid (the same wherever the record is cut:
  // the service's workers receive it without its leading rest).
  const model::OutputFrame frame{r.dt, static_cast<double>(r.first_scored), scale_.y_half,
                                 scale_.duration};
  for (size_t i = 0; i < defs_.size(); ++i)
    if (defs_[i]->stage() == model::EffectStage::kOutput)
      defs_[i]->ApplyOutput(ep.subspan(effect_offset_[i]), frame, y);
}

namespace {

/// The effects of `defs` that open the output stage and are linear in y.
template <typename F>
void ForLeadingLinearOutput(const std::vector<const model::EffectDef*>& defs, F&& f) {
  for (size_t i = 0; i < defs.size(); ++i) {
    if (defs[i]->stage() != model::EffectStage::kOutput) continue;
    if (!defs[i]->linear_output()) return;
    f(i);
  }
}

}  // namespace

bool RecordModel::has_linear_output_effects() const {
  bool any = false;
  ForLeadingLinearOutput(defs_, [&](size_t) { any = true; });
  return any;
}

void RecordModel::ApplyLinearOutputEffects(const io::Record& r, std::span<const double> ep,
                                           size_t from, std::span<double> reg, size_t m) const {
  if (m == 0 || reg.empty()) return;
  const size_t n = reg.size() / m;
  const model::OutputFrame frame{r.dt,
                                 static_cast<double>(r.first_scored) - static_cast<double>(from),
                                 scale_.y_half, scale_.duration};
  std::vector<double> col(n);
  ForLeadingLinearOutput(defs_, [&](size_t i) {
    for (size_t j = 0; j < m; ++j) {
      for (size_t k = 0; k < n; ++k) col[k] = reg[k * m + j];
      defs_[i]->ApplyOutput(ep.subspan(effect_offset_[i]), frame, col);
      for (size_t k = 0; k < n; ++k) reg[k * m + j] = col[k];
    }
  });
}

size_t SimulatedFrom(const io::Record& r, size_t end) {
  return std::min(std::max<size_t>(r.rest_samples, 1) - 1, end >= 2 ? end - 2 : 0);
}

std::shared_ptr<const Family::Prepared> RecordModel::Prepare(const io::Record& r,
                                                             size_t end) const {
  if (family_->linear() || family_->simulates_records() || end > r.size() || end == 0)
    return nullptr;
  for (const model::EffectDef* e : defs_)
    if (e->stage() == model::EffectStage::kDrive) return nullptr;
  const size_t from = SimulatedFrom(r, end);
  return family_->Prepare(std::span<const double>(r.u).subspan(from, end - from), r.dt);
}

double RecordModel::Simulate(const io::Record& r, std::span<const double> p,
                             std::span<const double> weights, size_t end, std::span<double> yhat,
                             const Family::Prepared* prepared) const {
  if (!family_->linear()) {
    double rest = 0;
    SimulateMany(r, std::span<const std::span<const double>>(&p, 1), end,
                 std::span<const std::span<double>>(&yhat, 1), std::span<double>(&rest, 1),
                 prepared);
    return rest;
  }
  if (p.size() != params_.size()) {
    throw InputError(Describe() + ": " + std::to_string(p.size()) + " parameters given, " +
                     std::to_string(params_.size()) + " expected");
  }
  if (yhat.size() < end || end > r.size() || end == 0)
    throw InputError("RecordModel::Simulate: bad end");
  const size_t nf = family_->params().size();
  const size_t from = SimulatedFrom(r, end);
  std::vector<double> ue;
  EffectiveDrive(r, p.subspan(nf), from, end, ue);
  std::vector<double> reg(ue.size() * family_->regressors());
  family_->Regressors(ue, reg);
  return LinearOutput(r, p, weights, end, reg, yhat);
}

void RecordModel::SimulateMany(const io::Record& r, std::span<const std::span<const double>> ps,
                               size_t end, std::span<const std::span<double>> yhats,
                               std::span<double> rest, const Family::Prepared* prepared) const {
  if (family_->linear())
    throw InputError(Describe() + ": SimulateMany is for a family with searched parameters");
  const size_t L = ps.size();
  if (yhats.size() != L || rest.size() != L)
    throw InputError("RecordModel::SimulateMany: one output per parameter vector");
  for (const std::span<const double> p : ps) {
    if (p.size() != params_.size()) {
      throw InputError(Describe() + ": " + std::to_string(p.size()) + " parameters given, " +
                       std::to_string(params_.size()) + " expected");
    }
  }
  for (const std::span<double> y : yhats)
    if (y.size() < end || end > r.size() || end == 0)
      throw InputError("RecordModel::SimulateMany: bad end");
  const size_t nf = family_->params().size();
  if (family_->simulates_records()) {  // the whole record with its effects, by the family
    for (size_t l = 0; l < L; ++l) {
      family_->SimulateRecord(r, ps[l].first(nf), effects_, ps[l].subspan(nf), end, yhats[l]);
      rest[l] = yhats[l][0];
    }
    return;
  }
  const size_t from = SimulatedFrom(r, end);
  // Per lane: the family's parameters, its segment [from, end), and (drive effects) its own drive.
  thread_local std::vector<std::span<const double>> fp, us;
  thread_local std::vector<std::span<double>> segs;
  thread_local std::vector<std::vector<double>> ue;
  fp.resize(L);
  segs.resize(L);
  for (size_t l = 0; l < L; ++l) {
    fp[l] = ps[l].first(nf);
    segs[l] = yhats[l].subspan(from, end - from);
  }
  const bool drive = std::any_of(defs_.begin(), defs_.end(), [](const model::EffectDef* e) {
    return e->stage() == model::EffectStage::kDrive;
  });
  if (!drive) {
    family_->SimulatePreparedMany(
        prepared, fp, std::span<const double>(r.u).subspan(from, end - from), r.dt, segs);
  } else {
    if (ue.size() < L) ue.resize(L);
    us.resize(L);
    for (size_t l = 0; l < L; ++l) {
      EffectiveDrive(r, ps[l].subspan(nf), from, end, ue[l]);
      us[l] = ue[l];
    }
    family_->SimulateMany(fp, us, r.dt, segs);
  }
  for (size_t l = 0; l < L; ++l) {
    rest[l] = segs[l][0];
    std::fill(yhats[l].begin(), yhats[l].begin() + static_cast<std::ptrdiff_t>(from), rest[l]);
    ApplyOutputEffects(r, ps[l].subspan(nf), 0, yhats[l].first(end));
  }
}

double RecordModel::LinearOutput(const io::Record& r, std::span<const double> p,
                                 std::span<const double> weights, size_t end,
                                 std::span<const double> reg, std::span<double> yhat) const {
  const size_t m = family_->regressors(), nf = family_->params().size();
  if (weights.size() != m) throw InputError(family_->name() + ": weights not solved");
  if (yhat.size() < end || end > r.size() || end == 0)
    throw InputError("RecordModel::LinearOutput: bad end");
  const size_t from = SimulatedFrom(r, end);
  if (reg.size() != (end - from) * m)
    throw InputError("RecordModel::LinearOutput: regressor size mismatch");
  std::span<double> seg = yhat.subspan(from, end - from);
  for (size_t k = 0; k < seg.size(); ++k) {
    double acc = 0;
    for (size_t j = 0; j < m; ++j) acc += reg[k * m + j] * weights[j];
    seg[k] = acc;
  }
  const double rest_output = seg[0];
  std::fill(yhat.begin(), yhat.begin() + static_cast<std::ptrdiff_t>(from), rest_output);
  ApplyOutputEffects(r, p.subspan(nf), 0, yhat.first(end));
  return rest_output;
}

double RecordOffset(const io::Record& r, std::span<const double> y, double rest_output) {
  switch (r.offset_mode) {
    case io::OffsetMode::kFixed:
      return r.offset;
    case io::OffsetMode::kRest:
      return r.offset - rest_output;
    case io::OffsetMode::kFit: {
      double s = 0;
      for (size_t k = r.first_scored; k < r.end_scored; ++k) s += r.y[k] - y[k];
      return s / static_cast<double>(r.scored());
    }
  }
  return 0;
}

}  // namespace pz::records
