// A record set from the command line: a folder or a CSV, and for one CSV the windows given by
// --train-window / --validate-window / --test-window (START:END in seconds, repeatable); then the
// settling window of --settle-s (io::SkipSettling).
#pragma once

#include <string>
#include <vector>

#include "io/records.h"
#include "records/families.h"

namespace pz::reports {

io::RecordSet LoadRecordSetWithWindows(const std::string& path,
                                       const std::vector<std::string>& train,
                                       const std::vector<std::string>& validate,
                                       const std::vector<std::string>& test, double settle_s = 0);

/// The report's sentence on the settling window ("" when settle_s is 0).
std::string SettlingSentence(double settle_s);

/// The report's sentence on the family's initial state at rest (--initial-state; "" for a family
/// that does not take one).
std::string InitialStateSentence(const records::Family& family);

/// The same sentence for state `s` after `subject` ("The model starts", "The backlash-like model
/// starts").
std::string InitialStateSentence(model::InitialState s, const std::string& subject);

/// The width of a terminal column of record names: the longest name and two spaces, at least 16.
int NameColumnWidth(const io::RecordSet& set);

/// The width of a terminal column of roles: the longest role name of the set and two spaces.
int RoleColumnWidth(const io::RecordSet& set);

}  // namespace pz::reports
