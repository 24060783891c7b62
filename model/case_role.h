// The role of a recorded case (or record) in an identification, one enum for the bench files, the
// stack records, the job specs and the wire (numbered as proto/job.proto's CaseRole):
//   train     fitted;
//   validate  watched, not fitted (early stopping, selection);
//   test      withheld: only reported.
#pragma once

#include <optional>
#include <string_view>

namespace pz::model {

enum class CaseRole : int { kUnspecified = 0, kTrain = 1, kValidate = 2, kTest = 3 };

/// "train", "validate", "test" ("unspecified").
const char* CaseRoleName(CaseRole role);
/// Parses a role name (exact, lower case: "train", "validate", "test"); nullopt otherwise.
std::optional<CaseRole> ParseCaseRole(std::string_view name);

}  // namespace pz::model
