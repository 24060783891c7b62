#include "client/check_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "diagnosis.pb.h"
#include "diagnose/verdict.h"
#include "io/proto_json.h"

namespace pz::client {
namespace {

std::string F(const char* fmt, double a) {
  if (!std::isfinite(a)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, a);
  return buf;
}
std::string Pct(double share) { return std::isfinite(share) ? F("%.0f %%", 100 * share) : "n/a"; }

std::string Pad(std::string s, size_t w) {
  // Pads by code points (the names hold UTF-8 Greek letters in some places).
  size_t len = 0;
  for (unsigned char c : s) len += (c & 0xC0) != 0x80;
  while (len++ < w) s += ' ';
  return s;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double r = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(r);
  return i + 1 < v.size() ? v[i] + (r - i) * (v[i + 1] - v[i]) : v[i];
}

}  // namespace

void PrintCheckSummary(std::ostream& o, const diagnose::CheckSummary& s) {
  o << "confusion matrix (rows: true effect, columns: named; " << s.trials.size() << " benches)\n";
  o << "  " << Pad("true \\ named", 18);
  for (int c = 0; c < diagnose::CheckCols(); ++c)
    o << Pad(diagnose::CheckColumnName(c).substr(0, 11), 12);
  o << "\n";
  for (int r = 0; r < diagnose::CheckRows(); ++r) {
    o << "  " << Pad(diagnose::CheckColumnName(r), 18);
    for (int c = 0; c < diagnose::CheckCols(); ++c) o << Pad(std::to_string(s.confusion[r][c]), 12);
    o << "\n";
  }
  o << "share of the gap closed (right effect named, " << s.closed.size() << " benches): min "
    << Pct(Quantile(s.closed, 0)) << ", 10 % " << Pct(Quantile(s.closed, 0.1)) << ", median "
    << Pct(Quantile(s.closed, 0.5)) << ", 90 % " << Pct(Quantile(s.closed, 0.9)) << ", max "
    << Pct(Quantile(s.closed, 1)) << "\n";
  // The counts and the calibration (is a stated confidence of 90 % right 90 % of the time?) in the
  // words of every check (diagnose/verdict.h).
  o << records::TallyText(s, "benches") << F("%.0f", s.wall_time_s) << " s in all\n";
}

void WriteCheckJson(std::ostream& out, const diagnose::CheckSummary& s) {
  proto::DiagnosisCheck m;
  for (int c = 0; c < diagnose::CheckCols(); ++c) m.add_columns(diagnose::CheckColumnName(c));
  for (int r = 0; r < diagnose::CheckRows(); ++r) {
    auto& row = (*m.mutable_confusion())[diagnose::CheckColumnName(r)];
    for (int c = 0; c < diagnose::CheckCols(); ++c)
      row.add_values()->set_number_value(s.confusion[r][c]);
  }
  m.set_single_significant(s.effect_trials);
  m.set_single_significant_right(s.effect_right);
  m.set_accuracy(s.accuracy());
  m.set_clean(s.clean);
  m.set_clean_alarms(s.clean_alarms);
  m.set_false_alarm_rate(s.false_alarm_rate());
  m.mutable_closed()->Assign(s.closed.begin(), s.closed.end());
  for (const auto& t : s.trials) {
    proto::DiagnosisCheckTrial& g = *m.add_trials();
    g.set_seed(t.seed);
    g.set_truth(model::EffectName(t.truth));
    g.set_truth_description(t.truth_description);
    g.set_magnitude(t.magnitude);
    g.set_verdict_kind(t.verdict_kind);
    g.set_named(model::EffectName(t.named));
    g.set_confidence(t.confidence);
    g.set_significant(t.significant);
    g.set_rms_over_floor(t.rms_ratio);
    g.set_closed(t.closed);
    g.set_correct(t.correct());
    g.set_wall_time_s(t.wall_time_s);
  }
  m.set_wall_time_s(s.wall_time_s);
  out << io::PrintJson(m, "check.json");
}

}  // namespace pz::client
