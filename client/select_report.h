// The model selection of `piezoid fit --family auto` and `piezoid diagnose --records` without
// --family (records/select.h) in the terminal, report.md and the JSON files: the ranking table
// (candidate, CV RMSE ± SE, parameters, the withheld error shown after the choice) next to the
// noise floor, and the memory at rest each record's first branch shows.
#pragma once

#include <ostream>
#include <string>

#include "client/json_values.h"
#include "io/records.h"
#include "records/select.h"

namespace pz::client {

/// The terminal summary: the ranking (the finalists and the best `screened` of the screening
/// round), the choice, the initial state per record.
void PrintSelection(std::ostream& os, const io::RecordSet& set, const records::SelectionResult& s,
                    size_t screened = 6);
/// report.md's section "## Model selection (--family auto)".
void WriteSelectionMarkdown(std::ostream& os, const io::RecordSet& set,
                            const records::SelectionResult& s);
/// fit.json's / diagnosis.json's "selection" object.
json::Value SelectionJson(const records::SelectionResult& s);

}  // namespace pz::client
