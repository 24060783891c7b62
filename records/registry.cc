#include "records/registry.h"

#include "model/status.h"
#include "records/preisach_family.h"

namespace pz::records {

// Every family's registration, in the order of records/families.h's header comment.
const std::vector<const FamilyDef*>& Families() {
  static const std::vector<const FamilyDef*> all = {
      &kStackBoucWenFamily, &kBacklashLikeFamily, &kDuhemFamily,    &kPrandtlIshlinskiiFamily,
      &kBwOscillatorFamily, &kBimorphFinFamily,   &kPreisachFamily, &kAsymmetricPiFamily};
  return all;
}

const FamilyDef* FindFamily(std::string_view name) {
  for (const FamilyDef* f : Families())
    if (name == f->name) return f;
  return nullptr;
}

std::string FamilyList(bool initial_state_only) {
  std::string s;
  for (const FamilyDef* f : Families())
    if (!initial_state_only || f->takes_initial_state)
      s += (s.empty() ? "" : ", ") + std::string(f->name);
  return s;
}

const FamilyDef& FamilyNamed(std::string_view name, std::string_view field) {
  if (const FamilyDef* f = FindFamily(name)) return *f;
  throw InputError(std::string(field) + " '" + std::string(name) +
                   "' is unknown (families: " + FamilyList() + ")");
}

const std::vector<std::string>& FamilyNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const FamilyDef* f : Families()) v.emplace_back(f->name);
    return v;
  }();
  return names;
}

bool TakesInitialState(std::string_view family) {
  const FamilyDef* f = FindFamily(family);
  return f != nullptr && f->takes_initial_state;
}

std::unique_ptr<Family> MakeFamily(std::string_view name, const DataScale& scale,
                                   const FamilyOptions& o) {
  if (o.substeps < 1 || o.substeps > 512)
    throw InputError(FieldError("substeps", o.substeps, "must be 1 … 512"));
  return FamilyNamed(name, "--family").make(scale, o);
}

}  // namespace pz::records
