// Per-case parameter files: a CSV with one row per case,
//
//   case, mu, delta, alpha, beta, gamma, a1, a2[, b1, b2]
//
// units as in model::BimorphParams (mu [1/s], delta [s], alpha [N/V], beta [1/V], gamma [1/V],
// a1, a2, b1, b2 [deg]). The b1, b2 columns are optional, together; a row may leave both empty,
// meaning "no saturations given" (the caller fits them). Errors name the file, line and column:
// missing columns, non-numbers, NaN / inf, out-of-range values (BimorphParams::Validate), only one
// of b1/b2, a case that is not a positive integer, duplicate cases, no rows.
#pragma once

#include <filesystem>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "model/bimorph.h"

namespace pz::io {

struct CaseParams {
  int case_number = 0;          ///< > 0
  model::BimorphParams params;  ///< b1, b2 hold the defaults when !has_saturation
  bool has_saturation = false;  ///< b1, b2 were given
  int line = 0;                 ///< 1-based line in the file it was read from (0 if not read)
};

struct ParamsFile {
  std::string source;                             ///< file name for messages
  std::vector<CaseParams> rows;                   ///< file order
  const CaseParams* Find(int case_number) const;  ///< nullptr if absent
};

/// Parses the text of a parameter CSV (source names it in messages). Throws pz::InputError.
ParamsFile ParseParamsCsv(std::string_view text, std::string source);
/// Reads a parameter CSV. Throws pz::InputError.
ParamsFile ReadParamsCsv(const std::filesystem::path& path);

/// Writes rows as a parameter CSV (b1, b2 columns if any row has them; empty cells for the others).
/// Numbers are written to round-trip exactly.
void WriteParamsCsv(std::ostream& out, std::span<const CaseParams> rows);
/// Same, to a file; throws std::runtime_error if it cannot be written.
void WriteParamsCsvFile(const std::filesystem::path& path, std::span<const CaseParams> rows);

}  // namespace pz::io
