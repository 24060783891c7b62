#include "model/case_role.h"

namespace pz::model {

const char* CaseRoleName(CaseRole role) {
  switch (role) {
    case CaseRole::kTrain:
      return "train";
    case CaseRole::kValidate:
      return "validate";
    case CaseRole::kTest:
      return "test";
    case CaseRole::kUnspecified:
      return "unspecified";
  }
  return "unknown";
}

std::optional<CaseRole> ParseCaseRole(std::string_view name) {
  for (CaseRole r : {CaseRole::kTrain, CaseRole::kValidate, CaseRole::kTest})
    if (name == CaseRoleName(r)) return r;
  return std::nullopt;
}

}  // namespace pz::model
