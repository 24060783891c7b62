#include "records/preisach_family.h"

#include <algorithm>
#include <cmath>

#include "io/csv.h"
#include "model/kernels/pzk.h"
#include "model/prandtl_ishlinskii.h"
#include "model/preisach.h"
#include "records/fitness.h"
#include "records/preisach_normal.h"

namespace pz::records {
namespace {

std::string Names(const std::vector<const io::Record*>& records) {
  std::string s;
  for (const io::Record* r : records) s += (s.empty() ? "" : ", ") + r->name;
  return s;
}

/// Reversals of the drive by more than `depth` over the scored windows (a maximum then a fall of
/// more than depth, or a minimum then a rise).
int Reversals(const io::Record& r, double depth) {
  int reversals = 0, dir = 0;
  double hi = r.u[r.first_scored], lo = hi;
  for (size_t k = r.first_scored; k < r.end_scored; ++k) {
    const double v = r.u[k];
    hi = std::max(hi, v);
    lo = std::min(lo, v);
    if (dir >= 0 && v < hi - depth) {
      if (dir > 0) ++reversals;
      dir = -1;
      lo = v;
    } else if (dir <= 0 && v > lo + depth) {
      if (dir < 0) ++reversals;
      dir = 1;
      hi = v;
    }
  }
  return reversals;
}

class PreisachFamily final : public Family {
 public:
  PreisachFamily(const DataScale& s, const FamilyOptions& o)
      : grid_{s.u_min, s.u_max, o.pi_operators},
        start_(o.initial_state),
        fold_(o.cross_validation_fold) {
    ThrowIfError(grid_.Validate());
  }
  std::string name() const override { return kPreisachFamily.name; }
  std::string title() const override {
    return "discrete Preisach model (" + std::to_string(grid_.levels) + " levels, " +
           std::to_string(grid_.cells()) + " cells on the triangle over the training drive range)";
  }
  std::string equation() const override {
    return "y = sum_ij w_ij (clamp(play_{r_i}[u], c_ij, c_ij + D) - c_ij + k_i), w >= 0, r_i = i "
           "D/2, "
           "c_ij = u_min + r_i + j D, D = (u_max - u_min)/n";
  }
  const std::vector<ParamInfo>& params() const override { return params_; }
  bool linear() const override { return true; }
  size_t regressors() const override { return grid_.cells(); }
  void Simulate(std::span<const double> p, std::span<const double> u, double,
                std::span<double> y) const override {
    model::ApplyPreisach(grid_, p, u, y, Start(u));
  }
  void Regressors(std::span<const double> u, std::span<double> out) const override {
    model::PreisachRegressors(grid_, u, out, Start(u));
  }
  bool AddNormalEquations(const io::Record& r, size_t from, std::span<const double> u, int pol,
                          NormalEquationsBuilder& builder) const override {
    return AddPreisachRecordRows(grid_, Start(u), r, from, u, pol, builder);
  }
  model::InitialState initial_state() const override { return start_; }
  std::vector<std::string> weight_names() const override {
    std::vector<std::string> names;
    for (int i = 0; i < grid_.levels; ++i)
      for (int j = 0; j < grid_.levels - i; ++j) names.push_back(grid_.CellName(i, j));
    return names;
  }
  std::vector<std::string> excluded_effects() const override { return {"friction"}; }
  /// The density's roughness along the centre (towards the PI operator) or over the whole triangle
  /// (the interior filled in smoothly from the branches): a major loop identifies neither interior,
  /// the validation keeps the one the training records contradict less.
  std::vector<Penalty> regularisation() const override {
    return {{"roughness along the centre", model::PreisachRoughness(grid_)},
            {"roughness over the triangle", model::PreisachTriangleRoughness(grid_)}};
  }
  /// A density falling with the relay width and leaning with the centre (an asymmetric loop).
  std::vector<double> CheckNominal() const override {
    const int n = grid_.levels;
    double norm = 0;
    for (int i = 0; i < n; ++i) norm += std::exp(-i / 3.0);
    std::vector<double> w;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n - i; ++j)
        w.push_back(0.1 * std::exp(-i / 3.0) / norm * (1 + 0.3 * (2.0 * (j + 0.5) / (n - i) - 1)));
    return w;
  }
  void CheckTraining(const std::vector<const io::Record*>& train) const override {
    const double delta = grid_.step();
    int reversals = 0;
    std::vector<size_t> per_level(static_cast<size_t>(grid_.levels), 0);
    for (const io::Record* r : train) {
      reversals += Reversals(*r, delta);
      for (size_t k = r->first_scored; k < r->end_scored; ++k) {
        const double x = (r->u[k] - grid_.u_min) / delta;
        ++per_level[static_cast<size_t>(std::clamp(x, 0.0, grid_.levels - 1.0))];
      }
    }
    if (reversals < 2) {
      throw InputError(
          "preisach: the training drive of " + Names(train) + " has " + std::to_string(reversals) +
          " reversal(s) deeper than one grid step (" + io::FormatNumber(delta) +
          "); a Preisach grid needs at least 2 (a rise and a fall through the range) to identify "
          "its "
          "relays: train on a record that goes up and down, or use fewer levels (--pi-operators)");
    }
    for (size_t j = 0; j < per_level.size(); ++j) {
      if (per_level[j] < kMinSamplesPerLevel && !fold_) {
        throw InputError(
            "preisach: the training drive of " + Names(train) + " has " +
            std::to_string(per_level[j]) + " sample(s) between " +
            io::FormatNumber(grid_.u_min + static_cast<double>(j) * delta) + " and " +
            io::FormatNumber(grid_.u_min + static_cast<double>(j + 1) * delta) + " (grid level " +
            std::to_string(j + 1) + " of " + std::to_string(grid_.levels) + "); at least " +
            std::to_string(kMinSamplesPerLevel) +
            " per level are needed to identify its cells: use fewer levels (--pi-operators) or a "
            "drive that passes through that range");
      }
    }
  }

 private:
  static constexpr size_t kMinSamplesPerLevel = 4;
  model::InitialState Start(std::span<const double> u) const {
    return u.empty() ? start_ : model::ResolveInitialState(start_, u[0], grid_.u_min, grid_.u_max);
  }
  model::PreisachGrid grid_;
  model::InitialState start_;
  bool fold_ = false;  ///< FamilyOptions::cross_validation_fold: a level may have no sample
  std::vector<ParamInfo> params_;
};

class AsymmetricPiFamily final : public Family {
 public:
  AsymmetricPiFamily(const DataScale& s, const FamilyOptions& o)
      : thresholds_(model::PiThresholds(o.pi_operators, s.u_half)),
        knots_(model::AsymmetricPiKnots(kAsymmetricPiKnots, s.u_min, s.u_max)),
        start_(o.initial_state),
        u_min_(s.u_min),
        u_max_(s.u_max) {}
  std::string name() const override { return kAsymmetricPiFamily.name; }
  std::string title() const override {
    return "asymmetric Prandtl–Ishlinskii operator (plays + one-sided dead zones)";
  }
  std::string equation() const override {
    return "y = w0 u + sum_i w_i play_{r_i}[u] + sum_j a_j max(u - z_j, 0) + sum_j b_j min(u - "
           "z_j, 0), all >= 0";
  }
  const std::vector<ParamInfo>& params() const override { return params_; }
  bool linear() const override { return true; }
  size_t regressors() const override { return 1 + thresholds_.size() + 2 * knots_.size(); }
  void Simulate(std::span<const double> p, std::span<const double> u, double,
                std::span<double> y) const override {
    model::AsymmetricPi op = Operator(p);
    if (!u.empty()) op.start = model::ResolveInitialState(start_, u[0], u_min_, u_max_);
    model::ApplyAsymmetricPi(op, u, y);
  }
  void Regressors(std::span<const double> u, std::span<double> out) const override {
    if (out.size() != u.size() * regressors())
      throw InputError("asymmetric-pi: regressor size mismatch");
    model::AsymmetricPiRegressors(
        thresholds_, knots_, u, out,
        u.empty() ? start_ : model::ResolveInitialState(start_, u[0], u_min_, u_max_));
  }
  model::InitialState initial_state() const override { return start_; }
  std::vector<std::string> weight_names() const override {
    std::vector<std::string> names = {"w0"};
    for (size_t i = 0; i < thresholds_.size(); ++i)
      names.push_back("w" + std::to_string(i + 1) + "(r=" + io::FormatNumber(thresholds_[i]) + ")");
    for (size_t j = 0; j < knots_.size(); ++j)
      names.push_back("a" + std::to_string(j + 1) + "(z=" + io::FormatNumber(knots_[j]) + ")");
    for (size_t j = 0; j < knots_.size(); ++j)
      names.push_back("b" + std::to_string(j + 1) + "(z=" + io::FormatNumber(knots_[j]) + ")");
    return names;
  }
  std::vector<std::string> excluded_effects() const override { return {"friction"}; }
  /// w0, the plays (falling with the threshold), the dead zones: a steeper top, no bottom bend.
  std::vector<double> CheckNominal() const override {
    std::vector<double> w(regressors(), 0.0);
    const size_t plays = thresholds_.size();
    w[0] = 0.04;
    for (size_t i = 0; i < plays; ++i) w[1 + i] = 0.02 * std::exp(-static_cast<double>(i) / 3);
    w[plays + knots_.size()] = 0.03;  // the last upper dead zone
    return w;
  }
  /// A ridge on the dead zones: it shrinks the bend towards the symmetric PI operator where the
  /// data do not ask for it (and resolves max(u − z, 0) + min(u − z, 0) = u − z).
  std::vector<Penalty> regularisation() const override {
    const size_t m = regressors();
    std::vector<double> R(m * m, 0.0);
    for (size_t j = 1 + thresholds_.size(); j < m; ++j) R[j * m + j] = 1;
    return {{"ridge on the dead zones", std::move(R)}};
  }
  void CheckTraining(const std::vector<const io::Record*>& train) const override {
    size_t samples = 0;
    for (const io::Record* r : train) samples += r->scored();
    if (samples < 2 * regressors()) {
      throw InputError("asymmetric-pi: " + std::to_string(samples) + " training samples in " +
                       Names(train) + " for " + std::to_string(regressors()) +
                       " weights; at least " + std::to_string(2 * regressors()) +
                       " are needed (a longer window or fewer plays, --pi-operators)");
    }
  }
  model::AsymmetricPi Operator(std::span<const double> p) const {
    if (p.size() != regressors()) {
      throw InputError("asymmetric-pi: " + std::to_string(p.size()) + " weights given, " +
                       std::to_string(regressors()) + " expected");
    }
    const size_t n = thresholds_.size(), K = knots_.size();
    model::AsymmetricPi op;
    op.w0 = p[0];
    op.thresholds = thresholds_;
    op.weights.assign(p.begin() + 1, p.begin() + 1 + static_cast<std::ptrdiff_t>(n));
    op.knots = knots_;
    op.up.assign(p.begin() + 1 + static_cast<std::ptrdiff_t>(n),
                 p.begin() + 1 + static_cast<std::ptrdiff_t>(n + K));
    op.down.assign(p.begin() + 1 + static_cast<std::ptrdiff_t>(n + K), p.end());
    return op;  // centred: Simulate sets the state resolved on the drive
  }

 private:
  std::vector<double> thresholds_, knots_;
  model::InitialState start_;
  double u_min_, u_max_;
  std::vector<ParamInfo> params_;
};

}  // namespace

const std::vector<int>& PreisachLevelCandidates() {
  static const std::vector<int> levels = {12, 20, 28, 40};
  return levels;
}

namespace {

/// The training records with the creep spectrum at `params` undone on their responses: the
/// spectrum is a linear filter of the output (model/effect_library.h creep-spectrum, on the change
/// since the first simulated sample), so the measured response through its inverse is the
/// spectrum-free model's output plus the filtered noise and offset — and the family's rows keep
/// their structure (records/preisach_normal.h) where the filtered rows of every evaluation would be
/// dense. Copies; their other effects and parameters in `effects`, `params`.
struct LevelsProblem {
  std::vector<io::Record> records;
  std::vector<EffectKind> effects;
  std::vector<double> params;
};

LevelsProblem Undo(const std::vector<const io::Record*>& train, const DataScale& scale,
                   const std::vector<EffectKind>& effects, std::span<const double> params) {
  LevelsProblem lp;
  for (const io::Record* r : train) lp.records.push_back(*r);
  const EffectKind spectrum = EffectKind::Named("creep-spectrum");
  bool undo =
      !params.empty() && std::find(effects.begin(), effects.end(), spectrum) != effects.end();
  for (const EffectKind& e : effects)  // another output effect: the filter is not the last stage
    if (e != spectrum && e->stage() != model::EffectStage::kDrive) undo = false;
  // The parameters by effect, in each model's own order (RecordModel::EffectParams).
  FamilyOptions coarse;
  coarse.pi_operators = 2;
  const RecordModel full(MakePreisachFamily(scale, coarse), effects, scale);
  if (!params.empty() && params.size() != full.params().size())
    throw InputError("preisach levels: " + std::to_string(params.size()) + " effect parameters, " +
                     std::to_string(full.params().size()) + " expected");
  for (const EffectKind& e : effects)
    if (!(undo && e == spectrum)) lp.effects.push_back(e);
  if (params.empty()) return lp;
  const RecordModel rest(MakePreisachFamily(scale, coarse), lp.effects, scale);
  lp.params.assign(rest.params().size(), 0.0);
  for (const EffectKind& e : lp.effects) {
    const auto [from, count] = full.EffectParams(e);
    const auto [to, n] = rest.EffectParams(e);
    std::copy_n(params.begin() + static_cast<std::ptrdiff_t>(from), count,
                lp.params.begin() + static_cast<std::ptrdiff_t>(to));
    (void)n;
  }
  std::vector<double> w;
  if (undo) {
    const auto [from, count] = full.EffectParams(spectrum);
    w.assign(params.begin() + static_cast<std::ptrdiff_t>(from),
             params.begin() + static_cast<std::ptrdiff_t>(from + count));
  }
  if (!undo) return lp;
  const std::vector<double> taus = spectrum->KernelData(scale);
  for (io::Record& r : lp.records) {
    // e_k − y0 = d_k (1 − Σ w_i (1 − c_i)) + Σ w_i x̃_i, x̃_i = a_i x_i + (1 − a_i − c_i) d_{k−1}:
    // d_k.
    std::vector<double> a, c, x(taus.size(), 0.0);
    double gain = 1;
    for (size_t i = 0; i < taus.size(); ++i) {
      const model::LowpassStep st = model::LowpassConsts(taus[i], r.dt);
      a.push_back(st.a);
      c.push_back(st.c);
      gain -= w[i] * (1 - st.c);
    }
    const size_t from = SimulatedFrom(r, r.end_scored);
    const double y0 = r.y[from];
    double prev = 0;
    for (size_t k = from + 1; k < r.end_scored; ++k) {
      double acc = 0;
      for (size_t i = 0; i < taus.size(); ++i) {
        x[i] = a[i] * x[i] + (1 - a[i]) * prev - prev * c[i];  // without this sample's c_i d_k
        acc += w[i] * x[i];
      }
      const double d = (r.y[k] - y0 - acc) / gain;
      for (size_t i = 0; i < taus.size(); ++i) x[i] += c[i] * d;
      prev = d;
      r.y[k] = y0 + d;
    }
  }
  return lp;
}

}  // namespace

PreisachLevelFits FitPreisachLevels(const std::vector<const io::Record*>& train,
                                    const DataScale& scale, const FamilyOptions& options,
                                    const std::vector<EffectKind>& effects,
                                    std::span<const double> params,
                                    const std::vector<int>& candidates) {
  PreisachLevelFits out;
  LevelsProblem lp = Undo(train, scale, effects, params);
  out.records = std::make_shared<std::vector<io::Record>>(std::move(lp.records));
  std::vector<const io::Record*> recs;
  for (const io::Record& r : *out.records) recs.push_back(&r);
  out.params = lp.params;
  std::vector<WeightValidation> v;
  std::vector<std::string> refused;
  for (int levels : candidates) {
    FamilyOptions o = options;
    o.pi_operators = levels;
    auto model = std::make_shared<RecordModel>(MakePreisachFamily(scale, o), lp.effects, scale);
    try {
      auto fitness =
          std::make_shared<RecordFitness>(*model, recs, opt::kDefaultErrorCost, lp.params);
      v.push_back(fitness->validation());
      refused.emplace_back();
      out.fitness.push_back(std::move(fitness));
    } catch (const InputError& e) {
      v.emplace_back();
      refused.emplace_back(e.what());
      out.fitness.push_back(nullptr);
    }
    out.models.push_back(std::move(model));
  }
  if (std::all_of(refused.begin(), refused.end(), [](const std::string& r) { return !r.empty(); }))
    throw InputError("preisach: no grid of the candidate levels fits the training records: " +
                     refused.front());
  out.choice = ChooseResolution(candidates, v, refused);
  for (std::string& r : out.choice.refused)  // the reason, short
    if (r.find("samples between") != std::string::npos)
      r = "a level with fewer than 4 training samples";
  return out;
}

ResolutionChoice ChoosePreisachLevels(const std::vector<const io::Record*>& train,
                                      const DataScale& scale, const FamilyOptions& options,
                                      const std::vector<EffectKind>& effects,
                                      std::span<const double> params,
                                      const std::vector<int>& candidates) {
  return FitPreisachLevels(train, scale, options, effects, params, candidates).choice;
}

std::unique_ptr<Family> MakePreisachFamily(const DataScale& scale, const FamilyOptions& options) {
  return std::make_unique<PreisachFamily>(scale, options);
}

std::unique_ptr<Family> MakeAsymmetricPiFamily(const DataScale& scale,
                                               const FamilyOptions& options) {
  return std::make_unique<AsymmetricPiFamily>(scale, options);
}

const FamilyDef kPreisachFamily = {
    .name = "preisach",
    .takes_initial_state = true,
    .linear = true,
    .auto_grid = true,
    .kernel = pzk::PZK_PREISACH,
    .make = MakePreisachFamily,
    .kernel_shape = [](const FamilyOptions& o,
                       std::span<const double>) { return KernelSizes(o.pi_operators); },
};
const FamilyDef kAsymmetricPiFamily = {
    .name = "asymmetric-pi",
    .takes_initial_state = true,
    .linear = true,
    .auto_grid = true,
    .kernel = pzk::PZK_ASYMMETRIC_PI,
    .make = MakeAsymmetricPiFamily,
    .kernel_shape =
        [](const FamilyOptions& o, std::span<const double>) {
          return KernelSizes(o.pi_operators, kAsymmetricPiKnots);
        },
};

}  // namespace pz::records
