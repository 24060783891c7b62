#include "client/pi_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "io/csv.h"

namespace pz::client {
namespace {

std::string Fmt(const char* format, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

std::string JsonNumber(double x) { return std::isfinite(x) ? io::FormatNumber(x) : "null"; }

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

PiReport ScoreCaseSet(const io::CaseSet& set, std::span<const CaseModel> models,
                      const Simulator& simulate) {
  if (models.size() != set.cases.size())
    throw InputError("scoring: " + std::to_string(models.size()) + " models for " +
                     std::to_string(set.cases.size()) + " cases");
  PiReport report;
  report.case_set = set.dir.string();
  for (size_t i = 0; i < set.cases.size(); ++i) {
    const io::BenchCase& bc = set.cases[i];
    const CaseModel& m = models[i];
    if (m.case_number != bc.number)
      throw InputError("scoring: model " + std::to_string(i) + " is for case " +
                       std::to_string(m.case_number) + " but the case set's entry is case " +
                       std::to_string(bc.number));
    CaseScore s;
    s.case_number = bc.number;
    s.amplitude_v = bc.amplitude_v;
    s.frequency_hz = bc.frequency_hz;
    s.role = bc.role;
    s.b1 = m.params.b1;
    s.b2 = m.params.b2;
    s.saturation_source = m.saturation_source;
    const model::BimorphTrace trace = simulate(m.params, m.drive);
    s.summary = trace.summary;
    if (trace.summary.ok()) {
      try {
        s.metrics = model::CompareTraces(bc.t, bc.angle_deg, trace.t, trace.angle_deg,
                                         1e-6 / bc.sample_rate_hz);
      } catch (const InputError& e) {
        throw InputError(bc.file.string() + " vs model trace: " + e.what());
      }
      s.scored = true;
      double* sum = bc.role == io::CaseRole::kTrain      ? &report.cf_train
                    : bc.role == io::CaseRole::kValidate ? &report.sum_validate
                                                         : &report.sum_test;
      *sum += s.metrics.pi;
    } else {
      ++report.failed;
    }
    report.cases.push_back(std::move(s));
  }
  return report;
}

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

std::string JsonEscape(const std::string& s) {
  std::string o;
  for (unsigned char ch : s) {
    switch (ch) {
      case '"':
        o += "\\\"";
        break;
      case '\\':
        o += "\\\\";
        break;
      case '\n':
        o += "\\n";
        break;
      case '\r':
        o += "\\r";
        break;
      case '\t':
        o += "\\t";
        break;
      default:
        if (ch < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", ch);
          o += buf;
        } else {
          o += static_cast<char>(ch);
        }
    }
  }
  return o;
}

void WritePiJson(std::ostream& out, const PiReport& r) {
  auto str = [](const std::string& s) { return "\"" + JsonEscape(s) + "\""; };
  out << "{\n  \"case_set\": " << str(r.case_set) << ",\n  \"solver\": " << str(r.solver)
      << ",\n  \"saturation\": " << str(r.saturation_mode) << ",\n  \"cases\": [";
  for (size_t i = 0; i < r.cases.size(); ++i) {
    const CaseScore& c = r.cases[i];
    const double nan = std::nan("");
    out << (i ? "," : "") << "\n    {\"case\": " << c.case_number
        << ", \"amplitude_V\": " << JsonNumber(c.amplitude_v)
        << ", \"frequency_Hz\": " << JsonNumber(c.frequency_hz)
        << ", \"role\": " << str(io::CaseRoleName(c.role)) << ", \"b1_deg\": " << JsonNumber(c.b1)
        << ", \"b2_deg\": " << JsonNumber(c.b2) << ", \"saturation\": " << str(c.saturation_source)
        << ", \"status\": " << str(model::SimStatusName(c.summary.status))
        << ", \"message\": " << str(c.summary.message)
        << ", \"pi_deg2\": " << JsonNumber(c.scored ? c.metrics.pi : nan)
        << ", \"rmse_deg\": " << JsonNumber(c.scored ? c.metrics.rmse : nan)
        << ", \"max_abs_error_deg\": " << JsonNumber(c.scored ? c.metrics.max_abs : nan)
        << ", \"r2\": " << JsonNumber(c.scored ? c.metrics.r2 : nan)
        << ", \"steps\": " << c.summary.steps
        << ", \"wall_time_s\": " << JsonNumber(c.summary.wall_time_s) << "}";
  }
  out << "\n  ],\n  \"cf_train_deg2\": " << JsonNumber(r.cf_train)
      << ",\n  \"sum_validate_deg2\": " << JsonNumber(r.sum_validate)
      << ",\n  \"sum_test_deg2\": " << JsonNumber(r.sum_test) << ",\n  \"failed\": " << r.failed
      << "\n}\n";
}

}  // namespace pz::client
