// The report of `piezoid diagnose-check` (either form: fin benches or records of a family): a
// trial's line, the terminal summary of the check and its check.json (proto/diagnosis.proto
// DiagnosisCheck, printed by io/proto_json.h).
#pragma once

#include <ostream>
#include <string>

#include "diagnose/check.h"

namespace pz::reports {

/// "trial   3 right  DESCRIPTION -> effect  delay  ratio …" (diagnose/verdict.h TrialLine), with
/// the share closed and the wall time where the form's text says so; `index` from 0.
std::string CheckTrialLine(const diagnose::CheckText& text, const diagnose::CheckTrial& trial,
                           int index);
/// The confusion matrix (true effect × named effect), the distribution of the share closed, the
/// counts and the calibration of the stated confidence.
void PrintCheckSummary(std::ostream& out, const diagnose::CheckSummary& s);
void WriteCheckJson(std::ostream& out, const diagnose::CheckSummary& s);

}  // namespace pz::reports
