// Traces in and out: CSV with named columns (numbers written to round-trip exactly), the bimorph
// plant's trace, and a drive input file (t_s, voltage_V) read into a model::SampledSignal.
#pragma once

#include <filesystem>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "model/bimorph.h"
#include "model/signal.h"

namespace pz::io {

/// A named column, e.g. {"t_s", t}. The name should carry the unit.
struct NamedColumn {
  std::string name;
  std::span<const double> values;
};

/// Writes the columns as CSV (header row of names). Throws pz::InputError if the columns differ in
/// length (naming both) or there are none, or a name holds a comma, quote or line break.
void WriteColumnsCsv(std::ostream& out, std::span<const NamedColumn> columns);
/// Same, to a file; throws std::runtime_error if it cannot be written.
void WriteColumnsCsvFile(const std::filesystem::path& path, std::span<const NamedColumn> columns);

/// The columns of a plant trace: t_s, voltage_V, z_N, w_tip_m, theta_linear_deg, angle_deg.
/// The spans point into trace, which must outlive them.
std::vector<NamedColumn> TraceColumns(const model::BimorphTrace& trace);
/// WriteColumnsCsv(out, TraceColumns(trace)).
void WriteTraceCsv(std::ostream& out, const model::BimorphTrace& trace);

/// Reads a drive input file with columns t_s [s] and voltage_V [V] (other columns are ignored):
/// time strictly increasing, all finite, at least 2 samples. Throws pz::InputError naming the file,
/// line and column.
model::SampledSignal ReadInputSignalCsv(const std::filesystem::path& path);

}  // namespace pz::io
