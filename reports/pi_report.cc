#include "reports/pi_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "io/csv.h"
#include "io/proto_json.h"
#include "pi.pb.h"

namespace pz::reports {
namespace {

std::string Fmt(const char* format, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

std::string StatusText(const CaseScore& c) {
  return c.summary.ok()
             ? "ok"
             : std::string(model::SimStatusName(c.summary.status)) + ": " + c.summary.message;
}

int FailedIn(const PiReport& r, io::CaseRole role) {
  int n = 0;
  for (const auto& c : r.cases) n += c.role == role && !c.scored;
  return n;
}

std::string Incomplete(const PiReport& r, io::CaseRole role) {
  const int n = FailedIn(r, role);
  return n ? " (incomplete: " + std::to_string(n) + " case(s) failed)" : "";
}

std::string CaseList(const PiReport& r, io::CaseRole role) {
  std::string s;
  for (const auto& c : r.cases)
    if (c.role == role) s += (s.empty() ? "" : ", ") + std::to_string(c.case_number);
  return s.empty() ? "none" : s;
}

}  // namespace

void PrintPiReport(std::ostream& out, const PiReport& r) {
  out << "case set " << r.case_set << " (" << r.cases.size() << " cases), solver " << r.solver
      << ", saturation " << r.saturation_mode << "\n\n";
  char line[512];
  std::snprintf(line, sizeof line, "%5s %8s %7s %-9s %9s %9s %-11s %11s %10s %12s  %s\n", "case",
                "V [V]", "f [Hz]", "role", "b1 [deg]", "b2 [deg]", "saturation", "PI [deg^2]",
                "RMSE [deg]", "max|e| [deg]", "status");
  out << line;
  for (const auto& c : r.cases) {
    const bool ok = c.scored;
    std::snprintf(line, sizeof line, "%5d %8g %7g %-9s %9.4f %9.4f %-11s %11s %10s %12s  %s\n",
                  c.case_number, c.amplitude_v, c.frequency_hz, io::CaseRoleName(c.role), c.b1,
                  c.b2, c.saturation_source.c_str(), ok ? Fmt("%.4f", c.metrics.pi).c_str() : "-",
                  ok ? Fmt("%.4f", c.metrics.rmse).c_str() : "-",
                  ok ? Fmt("%.4f", c.metrics.max_abs).c_str() : "-", StatusText(c).c_str());
    out << line;
  }

  // The paper's grid: amplitudes down, frequencies across.
  std::vector<double> vs, fs;
  for (const auto& c : r.cases) {
    vs.push_back(c.amplitude_v);
    fs.push_back(c.frequency_hz);
  }
  std::sort(vs.begin(), vs.end());
  vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
  std::sort(fs.begin(), fs.end());
  fs.erase(std::unique(fs.begin(), fs.end()), fs.end());
  out << "\nPI [deg^2] by amplitude x frequency (* training case, - none, x failed):\n";
  out << std::string(10, ' ');
  for (double f : fs) out << Fmt("%10g", f) << " Hz";
  out << '\n';
  for (double v : vs) {
    out << Fmt("%8g", v) << " V";
    for (double f : fs) {
      std::string cell = "-";
      for (const auto& c : r.cases)
        if (c.amplitude_v == v && c.frequency_hz == f) {
          cell = c.scored ? Fmt("%.4f", c.metrics.pi) : "x";
          if (c.role == io::CaseRole::kTrain) cell += "*";
          break;
        }
      std::snprintf(line, sizeof line, "%13s", cell.c_str());
      out << line;
    }
    out << '\n';
  }
  out << "\nCF = sum of PI over the training cases (" << CaseList(r, io::CaseRole::kTrain)
      << "): " << Fmt("%.6g", r.cf_train) << " deg^2" << Incomplete(r, io::CaseRole::kTrain)
      << "\n";
  out << "sum of PI over the validation cases (" << CaseList(r, io::CaseRole::kValidate)
      << "): " << Fmt("%.6g", r.sum_validate) << " deg^2" << Incomplete(r, io::CaseRole::kValidate)
      << "\n";
  if (CaseList(r, io::CaseRole::kTest) != "none")
    out << "sum of PI over the test cases (" << CaseList(r, io::CaseRole::kTest)
        << "): " << Fmt("%.6g", r.sum_test) << " deg^2" << Incomplete(r, io::CaseRole::kTest)
        << "\n";
  if (r.failed) out << r.failed << " case(s) failed to simulate and are left out of the sums\n";
}

void WritePiCsv(std::ostream& out, const PiReport& r) {
  out << "case,amplitude_V,frequency_Hz,role,b1_deg,b2_deg,saturation,status,pi_deg2,rmse_deg,"
         "max_abs_error_deg,r2\n";
  for (const auto& c : r.cases) {
    out << c.case_number << ',' << io::FormatNumber(c.amplitude_v) << ','
        << io::FormatNumber(c.frequency_hz) << ',' << io::CaseRoleName(c.role) << ','
        << io::FormatNumber(c.b1) << ',' << io::FormatNumber(c.b2) << ',' << c.saturation_source
        << ',' << model::SimStatusName(c.summary.status);
    if (c.scored)
      out << ',' << io::FormatNumber(c.metrics.pi) << ',' << io::FormatNumber(c.metrics.rmse) << ','
          << io::FormatNumber(c.metrics.max_abs) << ',' << io::FormatNumber(c.metrics.r2);
    else
      out << ",,,,";
    out << '\n';
  }
}

namespace {

/// The report as its message (proto/pi.proto; the one conversion). A case whose simulation failed
/// has its metrics as NaN (printed as null).
proto::PiScores ScoresOf(const PiReport& r) {
  proto::PiScores out;
  out.set_case_set(r.case_set);
  out.set_solver(r.solver);
  out.set_saturation(r.saturation_mode);
  const double nan = std::nan("");
  for (const CaseScore& c : r.cases) {
    proto::PiCaseScore& s = *out.add_cases();
    s.set_case_(c.case_number);
    s.set_amplitude_v(c.amplitude_v);
    s.set_frequency_hz(c.frequency_hz);
    s.set_role(io::CaseRoleName(c.role));
    s.set_b1_deg(c.b1);
    s.set_b2_deg(c.b2);
    s.set_saturation(c.saturation_source);
    s.set_status(model::SimStatusName(c.summary.status));
    s.set_message(c.summary.message);
    s.set_pi_deg2(c.scored ? c.metrics.pi : nan);
    s.set_rmse_deg(c.scored ? c.metrics.rmse : nan);
    s.set_max_abs_error_deg(c.scored ? c.metrics.max_abs : nan);
    s.set_r2(c.scored ? c.metrics.r2 : nan);
    s.set_steps(c.summary.steps);
    s.set_wall_time_s(c.summary.wall_time_s);
  }
  out.set_cf_train_deg2(r.cf_train);
  out.set_sum_validate_deg2(r.sum_validate);
  out.set_sum_test_deg2(r.sum_test);
  out.set_failed(r.failed);
  return out;
}

}  // namespace

void WritePiJson(std::ostream& out, const PiReport& r) {
  out << io::PrintJson(ScoresOf(r), "the scores' JSON");
}

}  // namespace pz::reports
