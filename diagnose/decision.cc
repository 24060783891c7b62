#include "diagnose/decision.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "model/model_comparison.h"

namespace pz::diagnose {
namespace {

std::string Fmt(const char* fmt, double a = 0, double b = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

}  // namespace

Status DecisionRules::Validate() const {
  if (!(significance_ratio > 1))
    return InvalidArgument(FieldError("significance_ratio", significance_ratio, "must be > 1"));
  if (!(min_closed > 0 && min_closed <= 1))
    return InvalidArgument(FieldError("min_closed", min_closed, "must be in (0, 1]"));
  if (!(min_pattern >= 0 && min_pattern <= 1))
    return InvalidArgument(FieldError("min_pattern", min_pattern, "must be in [0, 1]"));
  if (!std::isfinite(separation_z))
    return InvalidArgument(FieldError("separation_z", separation_z, "must be finite"));
  if (blocks < 4) return InvalidArgument(FieldError("blocks", blocks, "must be >= 4"));
  return Status::Ok();
}

Gap MeasureGap(double s0, double t0, double s_floor, double var_w, double var_t, double nw,
               double nt, const DecisionRules& rules) {
  Gap g;
  g.s0 = s0;
  g.t0 = t0;
  g.s_floor = s_floor;
  g.var_w = var_w;
  g.var_t = var_t;
  g.nw = nw;
  g.nt = nt;
  g.rms_ratio = s_floor > 0 ? std::sqrt(s0 / s_floor) : std::numeric_limits<double>::infinity();
  g.significant = g.rms_ratio > rules.significance_ratio;
  return g;
}

double ClosedShare(double s0, double s_c, double s_floor) {
  const double excess = s0 - s_floor;
  return excess > 0 ? (s0 - s_c) / excess : std::numeric_limits<double>::quiet_NaN();
}

void ScoreCandidate(const Gap& gap, double s_withheld, double s_train, int added_params,
                    double pattern, const DecisionRules& rules, CandidateScore& c) {
  const double k = added_params;
  const double excess = gap.s0 - gap.s_floor;  // the gap above the floor (≤ 0: none to close)
  c.s_withheld = s_withheld;
  c.s_train = s_train;
  c.score = (gap.s0 - s_withheld) / gap.var_w - k * std::log(gap.nw);
  c.train_delta_bic = (s_train - gap.t0) / gap.var_t + k * std::log(gap.nt);
  c.closed = ClosedShare(gap.s0, s_withheld, gap.s_floor);
  c.raw_reduction = gap.s0 > 0 ? (gap.s0 - s_withheld) / gap.s0 : 0;
  c.pattern = pattern;
  std::vector<std::string> why;
  if (!gap.significant) why.push_back("no significant gap");
  if (!(c.score > 0)) why.push_back("held-out gain below the parameter penalty");
  if (!(c.train_delta_bic < 0)) why.push_back("no BIC gain on the training data");
  if (!(excess > 0)) {
    why.push_back("no gap above the floor to close");
  } else if (!(c.closed >= rules.min_closed)) {
    why.push_back(
        Fmt("closes %.0f %% of the gap (< %.0f %%)", 100 * c.closed, 100 * rules.min_closed));
  }
  if (!(c.pattern >= rules.min_pattern))
    why.push_back(Fmt("explains %.0f %% of the localised pattern (< %.0f %%)", 100 * c.pattern,
                      100 * rules.min_pattern));
  c.qualifies = why.empty();
  c.note.clear();
  for (size_t i = 0; i < why.size(); ++i) c.note += (i ? "; " : "") + why[i];
}

void FailCandidate(const std::string& message, CandidateScore& c) {
  c.score = -std::numeric_limits<double>::infinity();
  c.qualifies = false;
  c.note = "fit failed: " + message;
}

double PatternExplained(std::span<const double> before, std::span<const double> after) {
  double sb = 0, sa = 0;
  for (size_t i = 0; i < before.size() && i < after.size(); ++i) {
    if (before[i] <= 0) continue;  // only features that carried excess before
    sb += before[i];
    sa += std::min(after[i], before[i] * 10);
  }
  return sb > 0 ? 1.0 - sa / sb : 0.0;
}

void AssignWeights(const Gap& gap, std::span<CandidateScore* const> ranked) {
  if (ranked.empty() || !std::isfinite(ranked[0]->score)) return;
  const double s_best = std::min(gap.s0, ranked[0]->s_withheld);
  const double phi = std::max(1.0, s_best / gap.s_floor);
  double lmax = 0;
  for (const CandidateScore* c : ranked)
    if (std::isfinite(c->score)) lmax = std::max(lmax, c->score / (2 * phi));
  double z = std::exp(-lmax);
  for (const CandidateScore* c : ranked)
    if (std::isfinite(c->score)) z += std::exp(c->score / (2 * phi) - lmax);
  for (CandidateScore* c : ranked)
    c->weight = std::isfinite(c->score) ? std::exp(c->score / (2 * phi) - lmax) / z : 0;
}

bool AtFloor(const Gap& gap, const CandidateScore& c, const DecisionRules& rules) {
  return gap.s_floor > 0 && std::sqrt(c.s_withheld / gap.s_floor) <= rules.significance_ratio;
}

Naming NameEffect(const Gap& gap, std::span<CandidateScore* const> ranked,
                  const SquaredErrors& squares, const DecisionRules& rules) {
  Naming n;
  if (!gap.significant || ranked.empty() || !ranked[0]->qualifies) return n;
  n.named = 0;
  CandidateScore& best = *ranked[0];
  const std::vector<double> best_sq = squares(0);
  double confidence = model::NormalCdf(model::PairedBlockZ(squares(-1), best_sq, rules.blocks));
  for (size_t i = 1; i < ranked.size(); ++i) {
    const CandidateScore& other = *ranked[i];
    if (!other.qualifies) continue;
    const double z = model::PairedBlockZ(squares(static_cast<int>(i)), best_sq, rules.blocks);
    // Practically equivalent only when both leave no significant gap and the paired test does not
    // separate them; a rival that leaves a significant gap is evidence against itself however
    // small z is (never a tie).
    if (n.runner_up < 0 && z < rules.separation_z && AtFloor(gap, best, rules) &&
        AtFloor(gap, other, rules)) {
      n.runner_up = static_cast<int>(i);
      n.z_runner_up = z;
    }
    // The probability that the named one is the better of the two is Φ(z), tied or not: a tie is a
    // verdict that the difference is too small to act on, not evidence that it is zero (z = 0
    // gives ½, the equal split of two).
    confidence *= model::NormalCdf(z);
  }
  best.confidence = confidence;
  n.confidence = best.confidence;
  return n;
}

std::string VerdictKind(bool significant, const Naming& naming) {
  if (!significant) return "none";
  if (naming.named < 0) return "unexplained";
  return naming.runner_up >= 0 ? "inseparable" : "effect";
}

bool CalibrationTally::Add(bool clean_truth, bool significant, const std::string& verdict_kind,
                           bool named_is_truth, double stated_confidence) {
  const bool named = verdict_kind == "effect" || verdict_kind == "inseparable";
  const bool verdict_right = clean_truth ? verdict_kind == "none" : named && named_is_truth;
  if (clean_truth) {
    ++clean;
    if (verdict_kind != "none") ++clean_alarms;
  } else if (significant) {
    ++effect_trials;
    if (verdict_right) ++effect_right;
  }
  if (verdict_kind == "inseparable") ++inseparable;
  if (named) {
    confidence.push_back(stated_confidence);
    right.push_back(named_is_truth ? 1 : 0);
  }
  return verdict_right;
}

std::vector<model::ReliabilityBin> CalibrationTally::Reliability() const {
  return model::ReliabilityTable(confidence, right);
}

}  // namespace pz::diagnose
