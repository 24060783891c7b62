// The bimorph-fin bench as a record set (issue 38): each case of an io::CaseSet (a bench folder,
// io/bench_data.h) becomes a record that the records engine fits and diagnoses, with the
// bimorph-fin family in its bench form (records/families.h FamilyOptions::bench_form).
//
//   record     case<N>, the case's role (train / validate / test), its file
//   drive      the case's stated sinusoid V sin(2π f t_k) sampled on the case's grid t_k = k / fs
//              (what the bench form simulates; the recorded drive column is not used)
//   response   the measured fin angle [deg]; the whole record scored, offset fixed at 0
//   metadata   Record::sinusoid: the case number, V, f, the cycles and fs as the case states them
//              (the V × f grid trends are rebuilt from them), Record::frequency_hz = f
//
// Pure conversion: no file is read here (io::LoadCaseSet reads the folder).
#pragma once

#include "io/bench_data.h"
#include "io/records.h"

namespace pz::io {

/// The cases of `set` as records, in case order (format "bimorph-fin-bench", drive unit V,
/// response unit deg). Throws InputError naming the case's file for a case without samples or
/// whose stated sinusoid does not have the case's sample count, and for an empty set.
RecordSet RecordsFromCaseSet(const CaseSet& set);

}  // namespace pz::io
