#include "diagnose/verdict.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "model/format.h"

namespace pz::diagnose {
namespace {

std::string G(double x) { return FormatG(x, 3); }
/// A threshold as the user gave it (an ostream's default precision).
std::string T(double x) { return FormatG(x, 6); }
std::string FormatFixed(double x, int decimals) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
  return buf;
}
/// s padded with spaces to `width` characters (on the left when `right`).
std::string Padded(const std::string& s, size_t width, bool right) {
  if (s.size() >= width) return s;
  return right ? std::string(width - s.size(), ' ') + s : s + std::string(width - s.size(), ' ');
}
/// A share as a whole percentage ("n/a" when not finite).
std::string Pct(double share) {
  return std::isfinite(share) ? FormatFixed(100 * share, 0) + " %" : std::string("n/a");
}
/// The q-quantile of v, linear between order statistics (NaN for none).
double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double r = q * static_cast<double>(v.size() - 1);
  const size_t i = static_cast<size_t>(r);
  return i + 1 < v.size() ? v[i] + (r - static_cast<double>(i)) * (v[i + 1] - v[i]) : v[i];
}

}  // namespace

std::string ComposeVerdict(const Gap& gap, std::span<const VerdictCandidate> ranked,
                           const Naming& naming, const DecisionRules& rules, const VerdictText& t) {
  const std::string kind = VerdictKind(gap.significant, naming);
  const double floor = t.floor >= 0 ? t.floor : std::sqrt(gap.s_floor / gap.nw);
  const double rms0 = std::sqrt(gap.s0 / gap.nw);
  const std::string u = t.unit.empty() ? "" : " " + t.unit;
  std::string v;
  if (kind == "none") {
    v = "No significant gap: the withheld RMS error of " + t.model + " is " + G(gap.rms_ratio) +
        " × the noise floor (" + G(floor) + u + ", from " + t.floor_source + "), at most " +
        T(rules.significance_ratio) + ".";
    if (!ranked.empty() && ranked[0].score->score > 0) {
      v += " The best candidate, " + ranked[0].name + ", would lower it to " +
           G(std::sqrt(ranked[0].score->s_withheld / gap.nw)) + u + ", within the floor band";
      if (!t.absorbed.empty()) {
        v += "; what it would explain is absorbed by the base model's";
        for (size_t i = 0; i < t.absorbed.size(); ++i) v += (i ? ", " : " ") + t.absorbed[i];
      }
      v += ".";
    }
  } else if (kind == "unexplained") {
    v = "A significant gap (withheld RMS " + G(rms0) + u + " = " + G(gap.rms_ratio) +
        " × the noise floor of " + G(floor) + u + ", from " + t.floor_source +
        ") that no candidate explains by the rules.";
    if (!ranked.empty())
      v += " Best candidate: " + ranked[0].name + " (" + ranked[0].score->note + ").";
  } else {
    const VerdictCandidate& best = ranked[static_cast<size_t>(naming.named)];
    const std::string confidence = G(100 * naming.confidence) + " %";
    const std::string second = t.second.empty()
                                   ? ""
                                   : ", with a second effect: " + t.second + " (confidence " +
                                         G(100 * t.second_confidence) + " %)";
    const double s_final = t.s_final >= 0 ? t.s_final : best.score->s_withheld;
    if (kind == "inseparable") {
      const VerdictCandidate& ru = ranked[static_cast<size_t>(naming.runner_up)];
      v = "The data cannot separate " + best.name + " from " + ru.name +
          ": both bring the withheld gap to the noise floor (" +
          G(std::sqrt(best.score->s_withheld / gap.s_floor)) + " × and " +
          G(std::sqrt(ru.score->s_withheld / gap.s_floor)) + " ×, at most " +
          T(rules.significance_ratio) + "; they close " + G(100 * best.score->closed) + " % and " +
          G(100 * ru.score->closed) + " %) and the paired block test does not separate them (z = " +
          FormatG(naming.z_runner_up, 2) + " < " + T(rules.separation_z) + "); confidence in " +
          best.name + " " + confidence + ".";
      if (!t.second.empty()) {
        v += " A second effect on top of " + best.name + ": " + t.second + " (confidence " +
             G(100 * t.second_confidence) + " %); the two close " +
             G(100 * ClosedShare(gap.s0, s_final, gap.s_floor)) +
             " % of the excess withheld gap; withheld RMS " + G(rms0) + " → " +
             G(std::sqrt(s_final / gap.nw)) + u + ".";
      }
      if (!t.next.empty()) v += " Next measurement: " + t.next + ".";
    } else {
      v = "The gap is " + best.name + " (confidence " + confidence + ")" + second + ": adding " +
          (t.second.empty() ? "it" : "them") + " closes " +
          G(100 * ClosedShare(gap.s0, s_final, gap.s_floor)) +
          " % of the excess withheld gap; withheld RMS " + G(rms0) + " → " +
          G(std::sqrt(s_final / gap.nw)) + u + " against a noise floor of " + G(floor) + u + " (" +
          t.floor_source + ").";
    }
  }
  if (!t.closing.empty()) v += " " + t.closing;
  return v;
}

std::string TrialLine(int index, const std::string& mark, const std::string& description, int width,
                      const TrialVerdict& v, const std::string& after_named,
                      const std::string& extra) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "%-11s %-16s%s ratio %6.2f conf %.2f", v.verdict_kind.c_str(),
                v.named.c_str(), after_named.c_str(), v.rms_ratio, v.confidence);
  std::string head = "trial " + Padded(std::to_string(index), 3, true) + " ";
  if (!mark.empty()) head += Padded(mark, 6, false) + " ";
  return head + Padded(description, static_cast<size_t>(std::max(width, 0)), false) + " -> " + buf +
         extra;
}

std::string TallyText(const CalibrationTally& t, const std::string& noun) {
  std::string s =
      noun + " with an effect and a significant gap: " + std::to_string(t.effect_trials) +
      ", right effect named in " + std::to_string(t.effect_right) + " (" + Pct(t.accuracy()) +
      "); verdicts 'cannot separate': " + std::to_string(t.inseparable) + "\n";
  s += "clean " + noun + ": " + std::to_string(t.clean) + ", false alarms " +
       std::to_string(t.clean_alarms) + " (" + Pct(t.false_alarm_rate()) + ")\n";
  s += "calibration of the stated confidence (" + std::to_string(t.confidence.size()) + " " + noun +
       " with a named effect):\n";
  for (const model::ReliabilityBin& b : t.Reliability()) {
    if (b.count == 0) continue;
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "  confidence %.2f – %.2f: %3d %s, mean stated %5.1f %%, right %5.1f %%\n", b.lo,
                  std::min(b.hi, 1.0), b.count, noun.c_str(), 100 * b.mean_confidence,
                  100 * b.frequency_right);
    s += buf;
  }
  return s;
}

std::string ConfusionText(std::span<const std::string> columns,
                          const std::vector<std::vector<int>>& confusion, size_t trials,
                          const std::string& noun) {
  std::string s = "confusion matrix (rows: true effect, columns: named; " + std::to_string(trials) +
                  " " + noun + ")\n  " + Padded("true \\ named", 18, false);
  for (const std::string& c : columns) s += Padded(c.substr(0, 11), 12, false);
  s += "\n";
  for (size_t r = 0; r < confusion.size(); ++r) {
    s += "  " + Padded(columns[r], 18, false);
    for (int n : confusion[r]) s += Padded(std::to_string(n), 12, false);
    s += "\n";
  }
  return s;
}

std::string ClosedText(std::vector<double> closed, const std::string& noun) {
  return "share of the gap closed (right effect named, " + std::to_string(closed.size()) + " " +
         noun + "): min " + Pct(Quantile(closed, 0)) + ", 10 % " + Pct(Quantile(closed, 0.1)) +
         ", median " + Pct(Quantile(closed, 0.5)) + ", 90 % " + Pct(Quantile(closed, 0.9)) +
         ", max " + Pct(Quantile(closed, 1)) + "\n";
}

}  // namespace pz::diagnose
