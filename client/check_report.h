// The report of `piezoid diagnose-check`: the terminal summary of a calibration check and its
// check.json (proto/diagnosis.proto DiagnosisCheck, printed by io/proto_json.h).
#pragma once

#include <ostream>

#include "diagnose/fin_check.h"

namespace pz::client {

/// The confusion matrix (true effect × named effect) and the distribution of the share closed.
void PrintCheckSummary(std::ostream& out, const diagnose::CheckSummary& s);
void WriteCheckJson(std::ostream& out, const diagnose::CheckSummary& s);

}  // namespace pz::client
