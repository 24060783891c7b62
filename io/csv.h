// A small, strict CSV reader and number formatting shared by the io/ readers and writers.
//
// Accepted: comma-separated fields without quotes, a header row, LF or CRLF line ends, a UTF-8 byte
// order mark, spaces around fields, blank lines at the end. Rejected with a message that names the
// file, the line and the column: an empty file, duplicate or empty header names, a blank line
// inside the data, a row with the wrong number of fields (ragged), quoted fields, and — through
// Number() — empty fields, non-numbers and NaN / inf.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace pz::io {

/// One data row with its 1-based line number in the file.
struct CsvRow {
  int line = 0;
  std::vector<std::string> fields;
};

class CsvTable {
 public:
  std::string source;               ///< the file name used in messages
  std::vector<std::string> header;  ///< column names (trimmed)
  int header_line = 1;              ///< 1-based line of the header
  std::vector<CsvRow> rows;         ///< data rows, each with header.size() fields

  /// Column index by name, or nullopt.
  std::optional<int> FindColumn(std::string_view name) const;
  /// Column index by name; throws InputError "file:1: missing column 'x' (columns: a, b)".
  int RequireColumn(std::string_view name) const;
  /// Checks all the names at once; throws InputError naming every missing column.
  void RequireColumns(const std::vector<std::string_view>& names) const;

  /// "file:line: column 'name' (n)" for messages about one field (n is 1-based).
  std::string Where(size_t row, int col) const;
  const std::string& Field(size_t row, int col) const { return rows[row].fields[col]; }
  /// The field as a finite double; throws InputError naming file, line and column for an empty
  /// field, a non-number or NaN / inf.
  double Number(size_t row, int col) const;
  /// The field as an integer; throws InputError as Number().
  long Integer(size_t row, int col) const;
  /// Throws InputError "file: no data rows" when there are none.
  void RequireRows() const;
};

/// Parses CSV text; source names it in messages. Throws InputError.
CsvTable ParseCsv(std::string_view text, std::string source);
/// The whole content of a file. Throws InputError naming the path if it is missing, a directory or
/// unreadable.
std::string ReadTextFile(const std::filesystem::path& path);
/// Reads and parses a file. Throws InputError if it cannot be opened (naming the path).
CsvTable ReadCsvFile(const std::filesystem::path& path);

/// Opens path for writing (binary, truncating), calls write(out), flushes. Throws
/// std::runtime_error naming the path if it cannot be opened or written (a runtime failure, not bad
/// input).
void WriteFileWith(const std::filesystem::path& path,
                   const std::function<void(std::ostream&)>& write);

/// Before a long run whose results go to `path`: throws InputError naming `flag` and the path if
/// the file could not be written then (its folder missing or not writable, or it is a folder), so
/// the run's work is not lost at the end.
void CheckWritableFile(const std::filesystem::path& path, std::string_view flag);
/// The same for an output folder: creates it (and its parents) now, and throws InputError naming
/// `flag` if it cannot be made or is not writable.
void PrepareOutputFolder(const std::filesystem::path& dir, std::string_view flag);

/// Parses a whole string as a double ("+1", "1e-3", "-0"); nullopt if it is not exactly one number.
std::optional<double> ParseDouble(std::string_view s);
/// Shortest text that reads back to the same double (std::to_chars).
std::string FormatNumber(double x);

/// Checks that the times t (column `time_column` of csv) form a uniform grid from t = 0: strictly
/// increasing, first sample within rel_tol·dt of 0, every step within rel_tol·dt of the first one.
/// Throws InputError naming the file, line and column; `start_note` ends the message of a nonzero
/// start (e.g. "a case starts at t = 0 (from rest)"). Returns the sample rate 1/dt [Hz].
double CheckUniformTimeGrid(const CsvTable& csv, int time_column, const std::vector<double>& t,
                            double rel_tol, const std::string& start_note);

/// A sampled input/output record read from a CSV table with columns t_s, voltage_V and `output`:
/// the three series, their column indices, and the sample rate of the checked uniform grid
/// (CheckUniformTimeGrid with rel_tol and start_note). Throws InputError naming the missing column,
/// or "<file>: N data rows; a <what> needs at least 2 samples<context>".
struct SampledColumns {
  std::vector<double> t, u, y;
  int t_column = 0, u_column = 0, y_column = 0;
  double sample_rate_hz = 0;
};
SampledColumns ReadSampledColumns(const CsvTable& csv, const std::string& output,
                                  const std::string& what, double rel_tol,
                                  const std::string& start_note, const std::string& context);

}  // namespace pz::io
