// The model selection of `piezoid fit --family auto` and `piezoid diagnose --records` without
// --family (records/select.h) in the terminal, report.md and the JSON files: the ranking table
// (candidate, CV RMSE ± SE, parameters, the withheld error shown after the choice) next to the
// noise floor, and the memory at rest each record's first branch shows.
#pragma once

#include <ostream>
#include <string>

#include "io/records.h"
#include "records/select.h"

namespace pz::proto {
class Selection;
}

namespace pz::reports {

/// The terminal summary: the ranking (the finalists and the best `screened` of the screening
/// round), the choice, the initial state per record.
void PrintSelection(std::ostream& os, const io::RecordSet& set, const records::SelectionResult& s,
                    size_t screened = 6);
/// report.md's section "## Model selection (--family auto)".
void WriteSelectionMarkdown(std::ostream& os, const io::RecordSet& set,
                            const records::SelectionResult& s);
/// The selection as its stored message (the one conversion: fit.json's and diagnosis.json's
/// "selection"; `out` replaced).
void SelectionOf(const records::SelectionResult& s, proto::Selection* out);

}  // namespace pz::reports
