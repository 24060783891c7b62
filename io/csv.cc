#include "io/csv.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <unistd.h>

#include "model/status.h"

namespace pz::io {
namespace {

std::string_view Trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> SplitFields(std::string_view line) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    out.emplace_back(
        Trim(line.substr(start, comma == std::string_view::npos ? comma : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string s;
  for (size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + names[i];
  return s;
}

}  // namespace

std::optional<double> ParseDouble(std::string_view s) {
  if (s.starts_with(
          '+')) {  // from_chars takes '-' but not '+'; accept one '+' before a digit or '.'
    s.remove_prefix(1);
    if (s.starts_with('-') || s.starts_with('+')) return std::nullopt;
  }
  if (s.empty()) return std::nullopt;
  double x = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  if (ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
  return x;
}

std::string FormatNumber(double x) {
  char buf[64];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, x);
  return ec == std::errc() ? std::string(buf, ptr) : std::string("nan");
}

CsvTable ParseCsv(std::string_view text, std::string source) {
  CsvTable t;
  t.source = std::move(source);
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
  // Split into lines (LF; a trailing CR is dropped), remembering 1-based line numbers.
  std::vector<std::string_view> lines;
  size_t start = 0;
  while (start <= text.size()) {
    size_t nl = text.find('\n', start);
    if (nl == std::string_view::npos) nl = text.size();
    std::string_view line = text.substr(start, nl - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    start = nl + 1;
  }
  while (!lines.empty() && Trim(lines.back()).empty()) lines.pop_back();  // blank trailing lines
  if (lines.empty()) throw InputError(t.source + ": empty file (expected a header row)");
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line_no = static_cast<int>(i) + 1;
    if (lines[i].find('"') != std::string_view::npos)
      throw InputError(t.source + ":" + std::to_string(line_no) +
                       ": quoted fields are not supported");
    if (i == 0) {
      t.header = SplitFields(lines[0]);
      for (size_t c = 0; c < t.header.size(); ++c) {
        if (t.header[c].empty())
          throw InputError(t.source + ":1: column " + std::to_string(c + 1) +
                           " of the header has no name");
        for (size_t d = 0; d < c; ++d)
          if (t.header[d] == t.header[c])
            throw InputError(t.source + ":1: duplicate column '" + t.header[c] + "' (columns " +
                             std::to_string(d + 1) + " and " + std::to_string(c + 1) + ")");
      }
      continue;
    }
    if (Trim(lines[i]).empty())
      throw InputError(t.source + ":" + std::to_string(line_no) +
                       ": blank line inside the data (only trailing blank lines are allowed)");
    CsvRow row{line_no, SplitFields(lines[i])};
    if (row.fields.size() != t.header.size())
      throw InputError(t.source + ":" + std::to_string(line_no) + ": " +
                       std::to_string(row.fields.size()) + " fields, expected " +
                       std::to_string(t.header.size()) + " (" + JoinNames(t.header) + ")");
    t.rows.push_back(std::move(row));
  }
  return t;
}

std::string ReadTextFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path.string() + ": no such file");
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path.string() + ": is a directory, expected a CSV file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path.string() + ": read error");
  return ss.str();
}

CsvTable ReadCsvFile(const std::filesystem::path& path) {
  return ParseCsv(ReadTextFile(path), path.string());
}

void WriteFileWith(const std::filesystem::path& path,
                   const std::function<void(std::ostream&)>& write) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error(path.string() + ": cannot open for writing");
  write(out);
  out.flush();
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

namespace {

void CheckWritableFolder(const std::filesystem::path& dir, std::string_view flag,
                         const std::filesystem::path& given) {
  const std::string at = std::string(flag) + " " + given.string();
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw InputError(at + ": the folder '" + dir.string() + "' does not exist");
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw InputError(at + ": the folder '" + dir.string() + "' is not writable");
}

}  // namespace

void CheckWritableFile(const std::filesystem::path& path, std::string_view flag) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(std::string(flag) + " " + path.string() + ": is a folder, not a file");
  const std::filesystem::path parent = path.has_parent_path() ? path.parent_path() : ".";
  CheckWritableFolder(parent, flag, path);
}

void PrepareOutputFolder(const std::filesystem::path& dir, std::string_view flag) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw InputError(std::string(flag) + " " + dir.string() +
                     ": cannot create the folder: " + ec.message());
  CheckWritableFolder(dir, flag, dir);
}

std::optional<int> CsvTable::FindColumn(std::string_view name) const {
  for (size_t c = 0; c < header.size(); ++c)
    if (header[c] == name) return static_cast<int>(c);
  return std::nullopt;
}

int CsvTable::RequireColumn(std::string_view name) const {
  RequireColumns({name});
  return *FindColumn(name);
}

void CsvTable::RequireColumns(const std::vector<std::string_view>& names) const {
  std::string missing;
  int n = 0;
  for (auto name : names)
    if (!FindColumn(name)) missing += (n++ ? ", '" : "'") + std::string(name) + "'";
  if (n)
    throw InputError(source + ":" + std::to_string(header_line) + ": missing column" +
                     (n > 1 ? "s " : " ") + missing + " (columns: " + JoinNames(header) + ")");
}

std::string CsvTable::Where(size_t row, int col) const {
  return source + ":" + std::to_string(rows[row].line) + ": column '" + header[col] + "' (" +
         std::to_string(col + 1) + ")";
}

double CsvTable::Number(size_t row, int col) const {
  const std::string& f = Field(row, col);
  if (f.empty()) throw InputError(Where(row, col) + ": empty field, expected a number");
  const auto x = ParseDouble(f);
  if (!x) throw InputError(Where(row, col) + ": '" + f + "' is not a number");
  if (!std::isfinite(*x))
    throw InputError(Where(row, col) + ": '" + f + "' is not finite (NaN and inf are not allowed)");
  return *x;
}

long CsvTable::Integer(size_t row, int col) const {
  const double x = Number(row, col);
  if (x != std::floor(x) || std::abs(x) > 1e15)
    throw InputError(Where(row, col) + ": '" + Field(row, col) + "' is not an integer");
  return static_cast<long>(x);
}

void CsvTable::RequireRows() const {
  if (rows.empty())
    throw InputError(source + ": no data rows after the header (" + JoinNames(header) + ")");
}

double CheckUniformTimeGrid(const CsvTable& csv, int ct, const std::vector<double>& t,
                            double rel_tol, const std::string& start_note) {
  const double dt0 = t[1] - t[0];
  if (!(dt0 > 0))
    throw InputError(csv.Where(1, ct) + ": time " + FormatNumber(t[1]) +
                     " s is not after the previous sample's " + FormatNumber(t[0]) + " s");
  const double tol = rel_tol * dt0;
  if (!(std::abs(t[0]) <= tol))
    throw InputError(csv.Where(0, ct) + ": the first sample time is " + FormatNumber(t[0]) +
                     " s; " + start_note);
  const double rate = 1.0 / dt0;
  for (size_t k = 1; k < t.size(); ++k) {
    const double dt = t[k] - t[k - 1];
    if (!(dt > 0))
      throw InputError(csv.Where(k, ct) + ": time " + FormatNumber(t[k]) +
                       " s is not after the previous sample's " + FormatNumber(t[k - 1]) +
                       " s (time must be strictly increasing)");
    if (!(std::abs(dt - dt0) <= tol))
      throw InputError(csv.Where(k, ct) + ": step " + FormatNumber(dt) +
                       " s from the previous sample differs from the first step " +
                       FormatNumber(dt0) + " s (sample rate " + FormatNumber(rate) +
                       " Hz inferred from it; relative tolerance " + FormatNumber(rel_tol) + ")");
  }
  return rate;
}

SampledColumns ReadSampledColumns(const CsvTable& csv, const std::string& output,
                                  const std::string& what, double rel_tol,
                                  const std::string& start_note, const std::string& context) {
  csv.RequireColumns({"t_s", "voltage_V", output});
  SampledColumns s;
  s.t_column = *csv.FindColumn("t_s");
  s.u_column = *csv.FindColumn("voltage_V");
  s.y_column = *csv.FindColumn(output);
  const size_t n = csv.rows.size();
  if (n < 2)
    throw InputError(csv.source + ": " + std::to_string(n) + " data rows; a " + what +
                     " needs at least 2 samples" + context);
  s.t.resize(n);
  s.u.resize(n);
  s.y.resize(n);
  for (size_t k = 0; k < n; ++k) {
    s.t[k] = csv.Number(k, s.t_column);
    s.u[k] = csv.Number(k, s.u_column);
    s.y[k] = csv.Number(k, s.y_column);
  }
  s.sample_rate_hz = CheckUniformTimeGrid(csv, s.t_column, s.t, rel_tol, start_note);
  return s;
}

}  // namespace pz::io
