// `piezoid compensate` and `piezoid export FIT.json` (issue 23): a fitted model (fit.json's model
// section, client/fit_file.h) as a feed-forward compensator.
//
//   compensate --model FIT.json --reference REF.csv --out DRIVE.csv [--check-model OTHER.json]
//       the drive that makes the model follow the reference (records/stepper.h inverse, the
//       reference's preview used for a delay), with the predicted tracking error through the
//       forward model, the clipping events (how much, where) and, with --check-model, the error
//       another model predicts for that drive (the exposure to model error).
//   compensate --model FIT.json --replay RECORDS
//       the inverse run on each record's measured response; the drive it computes against the
//       drive applied, in drive units and in response units through the model's local gain, next
//       to the records' noise floor.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "client/commands.h"
#include "client/fit_file.h"
#include "client/record_windows.h"
#include "io/csv.h"
#include "io/records.h"
#include "model/format.h"
#include "records/diagnose.h"
#include "records/export_header.h"
#include "records/stepper.h"

namespace pz::client {
namespace fs = std::filesystem;
namespace {

std::string Fmt(double x, int prec = 4) { return FormatG(x, prec); }

/// The unit of a column name: its suffix after the last '_' ("t_s" -> "s").
std::string UnitOf(const std::string& column) {
  const size_t at = column.rfind('_');
  return at == std::string::npos ? std::string() : column.substr(at + 1);
}

struct Reference {
  std::vector<double> t, y;
};

/// REF.csv: a time column and a desired-response column, units as the columns' suffixes. The
/// response unit must be the model's (after the unit table's conversion within a quantity), the
/// time step the model's sample step (1 %).
Reference ReadReference(const std::string& path, const records::ModelSpec& m) {
  const io::CsvTable csv = io::ReadCsvFile(path);
  csv.RequireRows();
  if (csv.header.size() != 2) {
    throw InputError(path + ": " + std::to_string(csv.header.size()) +
                     " columns; a reference has two: time and desired response (e.g. t_s,displacement_" +
                     m.response_unit + ")");
  }
  const io::UnitConversion tu = io::ConvertUnit(UnitOf(csv.header[0]));
  if (tu.quantity != "time") {
    throw InputError(path + ": column '" + csv.header[0] + "': the first column must be time with its unit (t_s, t_ms)");
  }
  const std::string yu_name = UnitOf(csv.header[1]);
  const io::UnitConversion yu = io::ConvertUnit(yu_name);
  if (yu_name.empty() || yu.canonical != m.response_unit) {
    throw InputError(path + ": column '" + csv.header[1] + "' is in '" + yu_name + "', the model's response is in '" +
                     m.response_unit + "': give the reference in " + m.response_unit);
  }
  Reference r;
  for (size_t i = 0; i < csv.rows.size(); ++i) {
    r.t.push_back(csv.Number(i, 0) * tu.factor);
    r.y.push_back(csv.Number(i, 1) * yu.factor);
  }
  if (r.t.size() < 2) throw InputError(path + ": at least two samples are needed");
  const double dt = (r.t.back() - r.t.front()) / static_cast<double>(r.t.size() - 1);
  if (!(std::abs(dt - m.dt) <= 0.01 * m.dt)) {
    throw InputError(path + ": sample step " + Fmt(dt, 6) + " s; the model runs at " + Fmt(m.dt, 6) +
                     " s per step (resample the reference)");
  }
  for (size_t k = 1; k < r.t.size(); ++k) {
    if (!(r.t[k] > r.t[k - 1])) throw InputError(csv.Where(k, 0) + ": time must increase");
  }
  return r;
}

/// A clipping event: consecutive samples whose drive was clipped.
struct Clip {
  double t_start = 0, t_end = 0, worst = 0;
  size_t samples = 0;
};

struct Tracking {
  double rmse = 0, max_abs = 0, max_at = 0;
};

Tracking TrackingError(const std::vector<double>& t, const std::vector<double>& ref, const std::vector<double>& y) {
  Tracking e;
  double sse = 0;
  for (size_t k = 0; k < ref.size(); ++k) {
    const double d = y[k] - ref[k];
    sse += d * d;
    if (std::abs(d) > e.max_abs) e.max_abs = std::abs(d), e.max_at = t[k];
  }
  e.rmse = std::sqrt(sse / static_cast<double>(ref.size()));
  return e;
}

/// The drive for the reference (the preview: with a delay of n samples, the reference n samples
/// ahead, and one more for the fin's two-sample plan; the last value held), and the clipping events.
std::vector<double> Compensate(records::Stepper& inv, const Reference& ref, double u0, std::vector<Clip>* clips) {
  size_t preview = static_cast<size_t>(inv.inverse_plan_samples() - 1);
  for (size_t i = 0; i < inv.blocks().size(); ++i) {
    if (inv.blocks()[i].kind == records::pzk::PZK_DELAY) {
      preview += static_cast<size_t>(std::lround(inv.block_params(i)[0] / inv.spec().dt));
    }
  }
  std::vector<double> u(ref.y.size());
  u[0] = u0;
  inv.Init(u0);
  Clip open;
  for (size_t k = 1; k < ref.y.size(); ++k) {
    const long before = inv.ctl().saturated;
    const double clip_before = inv.ctl().max_clip;
    inv.ctl().max_clip = 0;
    u[k] = inv.InverseStep(ref.y[std::min(k + preview, ref.y.size() - 1)]);
    const bool clipped = inv.ctl().saturated != before;
    const double shortfall = inv.ctl().max_clip;
    inv.ctl().max_clip = std::max(clip_before, shortfall);
    if (clipped) {
      if (open.samples == 0) open.t_start = ref.t[k];
      open.t_end = ref.t[k];
      open.worst = std::max(open.worst, shortfall);
      ++open.samples;
    } else if (open.samples > 0) {
      clips->push_back(open);
      open = Clip{};
    }
  }
  if (open.samples > 0) clips->push_back(open);
  return u;
}

std::vector<double> Forward(records::Stepper& st, const std::vector<double>& u) {
  std::vector<double> y(u.size());
  y[0] = st.Init(u[0]);
  for (size_t k = 1; k < u.size(); ++k) y[k] = st.Step(u[k]);
  return y;
}

struct CompensateArgs {
  std::string model, reference, out, check_model, replay;
  std::vector<std::string> train_windows, validate_windows, test_windows;
  double rest_drive = NAN;
};

/// The drive at rest for the reference's first value: the rest state whose output it is
/// (bisection over the drive limits on the rest output).
double RestDrive(const records::ModelSpec& m, double y0) {
  records::Stepper st(m);
  double lo = m.drive_min, hi = m.drive_max;
  const double flo = st.Init(lo), fhi = st.Init(hi), sign = fhi >= flo ? 1 : -1;
  if (sign * y0 <= sign * flo) return lo;
  if (sign * y0 >= sign * fhi) return hi;
  for (int it = 0; it < 200; ++it) {
    const double mid = lo + 0.5 * (hi - lo);
    if (!(mid > lo && mid < hi)) break;
    (sign * st.Init(mid) < sign * y0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

int RunReference(const CompensateArgs& a, const records::ModelSpec& m) {
  const Reference ref = ReadReference(a.reference, m);
  std::optional<records::ModelSpec> other;
  if (!a.check_model.empty()) {
    other = LoadFit(a.check_model);
    if (other->response_unit != m.response_unit || other->drive_unit != m.drive_unit) {
      throw InputError("--check-model " + a.check_model + ": drive in " + other->drive_unit + ", response in " +
                       other->response_unit + "; the model's are " + m.drive_unit + ", " + m.response_unit);
    }
  }
  const double u0 = std::isnan(a.rest_drive) ? RestDrive(m, ref.y[0]) : a.rest_drive;
  records::Stepper inv(m);
  std::vector<Clip> clips;
  const std::vector<double> u = Compensate(inv, ref, u0, &clips);
  records::Stepper fwd(m);
  const std::vector<double> y = Forward(fwd, u);
  const Tracking e = TrackingError(ref.t, ref.y, y);
  io::WriteFileWith(a.out, [&](std::ostream& os) {
    os << "t_s,drive_" << m.drive_unit << ",predicted_" << m.response_unit << "\n";
    for (size_t k = 0; k < u.size(); ++k)
      os << io::FormatNumber(ref.t[k]) << "," << io::FormatNumber(u[k]) << "," << io::FormatNumber(y[k]) << "\n";
  });
  const auto range = std::minmax_element(ref.y.begin(), ref.y.end());
  std::cout << "piezoid compensate: " << m.Model()->Describe() << " from " << a.model << ", reference " << a.reference
            << " (" << ref.y.size() << " samples, range " << Fmt(*range.second - *range.first) << " "
            << m.response_unit << ")\n"
            << "  drive written to " << a.out << " (rest drive " << Fmt(u0) << " " << m.drive_unit << ", limits "
            << Fmt(inv.ctl().u_lo) << " … " << Fmt(inv.ctl().u_hi) << " " << m.drive_unit << ")\n"
            << "  predicted tracking error (forward model on that drive): RMSE " << Fmt(e.rmse) << " "
            << m.response_unit << ", max " << Fmt(e.max_abs) << " at " << Fmt(e.max_at) << " s\n";
  if (inv.has_delay()) {
    std::cout << "  the model's delay cannot be undone: the reference's preview was used (the drive leads it)\n";
  }
  if (clips.empty()) {
    std::cout << "  clipping: none (the reference is reachable within the drive limits)\n";
  } else {
    size_t total = 0;
    double worst = 0;
    for (const Clip& c : clips) total += c.samples, worst = std::max(worst, c.worst);
    std::cout << "  clipping: " << total << " sample(s) in " << clips.size()
              << " event(s) where the reference is beyond what the drive limits reach; largest shortfall "
              << Fmt(worst) << " " << m.response_unit << "\n";
    for (size_t i = 0; i < clips.size() && i < 10; ++i) {
      std::cout << "    " << Fmt(clips[i].t_start) << "–" << Fmt(clips[i].t_end) << " s: " << clips[i].samples
                << " sample(s), shortfall up to " << Fmt(clips[i].worst) << " " << m.response_unit << "\n";
    }
    if (clips.size() > 10) std::cout << "    … " << clips.size() - 10 << " more\n";
  }
  if (other) {
    records::Stepper check(*other);
    const std::vector<double> yo = Forward(check, u);
    const Tracking eo = TrackingError(ref.t, ref.y, yo);
    std::cout << "  exposure to model error: " << other->Model()->Describe() << " (" << a.check_model
              << ") predicts RMSE " << Fmt(eo.rmse) << " " << m.response_unit << ", max " << Fmt(eo.max_abs) << " at "
              << Fmt(eo.max_at) << " s on this drive\n";
  }
  return 0;
}

int RunReplay(const CompensateArgs& a, const records::ModelSpec& m) {
  const io::RecordSet set = LoadRecordSetWithWindows(a.replay, a.train_windows, a.validate_windows, a.test_windows);
  if (set.response_unit != m.response_unit || set.drive_unit != m.drive_unit) {
    throw InputError("--replay " + a.replay + ": drive in " + set.drive_unit + ", response in " + set.response_unit +
                     "; the model's are " + m.drive_unit + ", " + m.response_unit);
  }
  std::cout << "piezoid compensate --replay: " << m.Model()->Describe() << " from " << a.model << " on " << a.replay
            << "\n";
  double noise = NAN;
  std::string noise_how;
  try {
    const records::NoiseFloor nf = records::EstimateNoiseFloor(set);
    noise = nf.sigma;
    noise_how = nf.used;
  } catch (const InputError& e) {
    noise_how = std::string("no estimate: ") + e.what();
  }
  for (const io::Record& r : set.records) {
    if (std::abs(r.dt - m.dt) > 0.01 * m.dt) {
      throw InputError(r.Label() + ": sample step " + Fmt(r.dt, 6) + " s; the model runs at " + Fmt(m.dt, 6) + " s");
    }
    records::Stepper inv(m);
    inv.Init(r.u[0]);
    // Replay: the limits are the model's, widened to the record's drive (the applied drive is the truth).
    inv.ctl().u_lo = std::min(m.drive_min, *std::min_element(r.u.begin(), r.u.end()));
    inv.ctl().u_hi = std::max(m.drive_max, *std::max_element(r.u.begin(), r.u.end()));
    double sse_u = 0, sse_y = 0, max_y = 0;
    size_t n = 0;
    for (size_t k = 1; k < r.end_scored; ++k) {
      // The local gain of the one-step map at the applied drive, before the step.
      const double h = 1e-6 * m.scale.u_half;
      const double g = (inv.Trial(r.u[k] + h) - inv.Trial(r.u[k] - h)) / (2 * h);
      // The fin's compensator plans two samples: its target is the response one sample ahead.
      const size_t ahead = std::min(k + static_cast<size_t>(inv.inverse_plan_samples() - 1), r.size() - 1);
      const double u = inv.InverseStep(r.y[ahead]);
      if (k < r.first_scored) continue;
      const double du = u - r.u[k], dy = g * du;
      sse_u += du * du;
      sse_y += dy * dy;
      max_y = std::max(max_y, std::abs(dy));
      ++n;
    }
    const double rms_u = std::sqrt(sse_u / static_cast<double>(n)), rms_y = std::sqrt(sse_y / static_cast<double>(n));
    std::cout << "  " << r.name << " (" << model::CaseRoleName(r.role) << ", " << n << " samples): drive RMSE "
              << Fmt(rms_u) << " " << m.drive_unit << "; through the local gain " << Fmt(rms_y) << " "
              << m.response_unit << " RMS, max " << Fmt(max_y) << " " << m.response_unit;
    if (std::isfinite(noise)) std::cout << " (" << Fmt(rms_y / noise, 3) << " × the noise floor)";
    std::cout << "\n";
  }
  if (std::isfinite(noise)) {
    std::cout << "  noise floor " << Fmt(noise) << " " << m.response_unit << " (" << noise_how << ")\n";
  } else {
    std::cout << "  noise floor: " << noise_how << "\n";
  }
  return 0;
}

}  // namespace

int ExportFit(const std::string& fit_json, const std::string& out, const std::string& name_flag) {
  const records::ModelSpec m = LoadFit(fit_json);
  records::Stepper st(m);
  std::string name = name_flag;
  if (name.empty()) {
    name = out.empty() ? "piezoid_model" : fs::path(out).stem().string();
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) name = "pz_" + name;
  }
  const std::string header = records::ExportHeader(st, name, m.Model()->Describe() + " from " + fit_json);
  if (out.empty()) {
    std::cout << header;
    return 0;
  }
  io::WriteFileWith(out, [&](std::ostream& os) { os << header; });
  std::cerr << "piezoid: wrote " << out << ": " << name << "_init, " << name << "_step, " << name
            << "_inverse_step (" << m.Model()->Describe() << ")\n";
  return 0;
}

void RegisterCompensate(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<CompensateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compensate",
      "Feed-forward compensation with a fitted model (fit.json): the drive that makes the model follow a reference "
      "(--reference), or the inverse replayed on measured records (--replay).");
  cmd->add_option("--model", a->model, "fit.json of piezoid fit")->required()->type_name("FIT.json");
  auto* ref = cmd->add_option("--reference", a->reference, "CSV: time and desired response (units in the column names)");
  auto* replay = cmd->add_option("--replay", a->replay, "record set: run the inverse on the measured responses");
  ref->excludes(replay);
  cmd->add_option("--out", a->out, "the drive CSV (with --reference)")->type_name("DRIVE.csv");
  cmd->add_option("--check-model", a->check_model, "another fit.json: the tracking error it predicts for the drive");
  cmd->add_option("--rest-drive", a->rest_drive, "the drive at rest before the reference (default: the rest drive "
                                                 "whose output is the reference's first value)");
  cmd->add_option("--train-window", a->train_windows, "--replay of one CSV: a training window START:END [s]");
  cmd->add_option("--validate-window", a->validate_windows, "--replay of one CSV: a validation window START:END [s]");
  cmd->add_option("--test-window", a->test_windows, "--replay of one CSV: a test window START:END [s]");
  cmd->callback([a, &exit_code] {
    const records::ModelSpec m = LoadFit(a->model);
    if (!a->replay.empty()) {
      exit_code = RunReplay(*a, m);
      return;
    }
    if (a->reference.empty()) throw InputError("compensate: give --reference REF.csv (with --out) or --replay RECORDS");
    if (a->out.empty()) throw InputError("compensate --reference: give --out DRIVE.csv");
    exit_code = RunReference(*a, m);
  });
}

}  // namespace pz::client
