#include "records/record_rows.h"

#include <algorithm>
#include <cmath>

namespace pz::records {

double RecordCentre(const io::Record& r, size_t from, std::span<const double> reg, size_t m,
                    std::vector<double>& c) {
  auto row = [&](size_t k) { return reg.data() + RegressorRow(k, from) * m; };
  double d = 0;
  c.assign(m, 0.0);
  if (r.offset_mode == io::OffsetMode::kFit) {
    for (size_t k = r.first_scored; k < r.end_scored; ++k) {
      for (size_t j = 0; j < m; ++j) c[j] += row(k)[j];
      d += r.y[k];
    }
    for (double& v : c) v /= static_cast<double>(r.scored());
    d /= static_cast<double>(r.scored());
  } else if (r.offset_mode == io::OffsetMode::kRest) {
    std::copy_n(row(0), m, c.begin());
    d = r.offset;
  } else {
    d = r.offset;
  }
  return d;
}

void AddRecordRows(const io::Record& r, size_t from, std::span<const double> reg, size_t m, int pol,
                   NormalEquationsBuilder& builder) {
  auto row = [&](size_t k) { return reg.data() + RegressorRow(k, from) * m; };
  thread_local std::vector<double> c;
  const double d = RecordCentre(r, from, reg, m, c);
  for (size_t k = r.first_scored; k < r.end_scored; ++k) {
    double* out = builder.Row();
    for (size_t j = 0; j < m; ++j) out[j] = pol * (row(k)[j] - c[j]);
    builder.Add(r.y[k] - d);
  }
}

}  // namespace pz::records
