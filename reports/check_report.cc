#include "reports/check_report.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "diagnose/verdict.h"
#include "diagnosis.pb.h"
#include "io/proto_json.h"

namespace pz::reports {

std::string CheckTrialLine(const diagnose::CheckText& text, const diagnose::CheckTrial& t,
                           int index) {
  std::string extra;
  if (text.closed_per_trial) {
    char buf[100];
    std::snprintf(
        buf, sizeof buf, " closed %6s (%.0f s)",
        std::isfinite(t.closed)
            ? (std::to_string(static_cast<int>(std::lround(100 * t.closed))) + "%").c_str()
            : "n/a",
        t.wall_time_s);
    extra = buf;
  }
  return diagnose::TrialLine(index + 1, t.correct ? "right" : "WRONG", t.description,
                             text.description_width, t, "", extra);
}

void PrintCheckSummary(std::ostream& o, const diagnose::CheckSummary& s) {
  // The matrix, the shares closed, the counts and the calibration (is a stated confidence of 90 %
  // right 90 % of the time?) in the words of every check (diagnose/verdict.h).
  const std::string& noun = s.text.noun;
  char wall[32];
  std::snprintf(wall, sizeof wall, "%.0f s in all\n", s.wall_time_s);
  o << diagnose::ConfusionText(s.columns, s.confusion, s.trials.size(), noun)
    << diagnose::ClosedText(s.closed, noun) << diagnose::TallyText(s, noun) << wall;
}

void WriteCheckJson(std::ostream& out, const diagnose::CheckSummary& s) {
  proto::DiagnosisCheck m;
  for (const std::string& c : s.columns) m.add_columns(c);
  for (size_t r = 0; r < s.confusion.size(); ++r) {
    auto& row = (*m.mutable_confusion())[s.columns[r]];
    for (int n : s.confusion[r]) row.add_values()->set_number_value(n);
  }
  m.set_single_significant(s.effect_trials);
  m.set_single_significant_right(s.effect_right);
  m.set_accuracy(s.accuracy());
  m.set_clean(s.clean);
  m.set_clean_alarms(s.clean_alarms);
  m.set_false_alarm_rate(s.false_alarm_rate());
  m.mutable_closed()->Assign(s.closed.begin(), s.closed.end());
  for (const diagnose::CheckTrial& t : s.trials) {
    proto::DiagnosisCheckTrial& g = *m.add_trials();
    g.set_seed(t.seed);
    g.set_truth(model::EffectName(t.truth));
    g.set_truth_description(t.description);
    g.set_magnitude(t.magnitude);
    g.set_verdict_kind(t.verdict_kind);
    g.set_named(t.named);
    g.set_confidence(t.confidence);
    g.set_significant(t.significant);
    g.set_rms_over_floor(t.rms_ratio);
    g.set_closed(t.closed);
    g.set_correct(t.correct);
    g.set_wall_time_s(t.wall_time_s);
  }
  m.set_wall_time_s(s.wall_time_s);
  out << io::PrintJson(m, "check.json");
}

}  // namespace pz::reports
