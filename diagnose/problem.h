// The cases of the nine-case fin bench (issue 6), each with its per-case saturations b1, b2 from
// its measured extremes (model/saturation.h) and its noise floor. Their fits are the records
// engine's (bimorph-fin's bench form, records/families.h; the bench's diagnosis:
// diagnose/fin_diagnose.h DiagnoseBench).
#pragma once

#include <string>
#include <vector>

#include "model/fin_case.h"
#include "records/noise_floor.h"

namespace pz::io {
struct CaseSet;
}

namespace pz::diagnose {

/// One bench case of the problem (saturations from the measured extremes) with its noise floor.
struct DiagCase : model::FinCase {
  records::CaseNoise noise;  ///< noise floor of the record
};

/// The cases of a bench with their noise. Throws InputError on a set without training or
/// without withheld cases, or a case whose extremes give no saturation.
std::vector<DiagCase> CasesFromCaseSet(const io::CaseSet& set);

}  // namespace pz::diagnose
