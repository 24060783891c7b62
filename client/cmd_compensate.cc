// `piezoid compensate` (issue 23): a fitted model (fit.json's model section, reports/fit_file.h) as
// a feed-forward compensator. (`piezoid export FIT.json`: client/cmd_export.cc.)
//
//   compensate --model FIT.json --reference REF.csv --out DRIVE.csv [--check-model OTHER.json]
//              [--reference-zero absolute|rest|mean|auto]
//       the drive that makes the model follow the reference (records/stepper.h inverse, the
//       reference's preview used for a delay), with the predicted tracking error through the
//       forward model, the clipping events (how much, where) and, with --check-model, the error
//       another model predicts for that drive (the exposure to model error). The reference is the
//       model's absolute output or, the usual form, zero-mean relative to its rest output or to
//       the training records' mean response (ReferenceZero); the predicted column is in the
//       reference's frame.
//   compensate --model FIT.json --replay RECORDS
//       the inverse run on each record's measured response (less the record's own offset, as the
//       fit takes it: a sensor's zero is not a drive; a delay's response read that many samples
//       later); the drive it computes against the drive applied, in drive units and in response
//       units through the model's local gain, next to the records' noise floor and to what the
//       model's own response to the applied drive gives replayed, noiseless (the inverse's
//       exactness) and with noise of the floor's σ (the drive error of the inverse and the noise,
//       without model error).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "client/commands.h"
#include "controller/export_header.h"
#include "diagnose/diagnose.h"
#include "io/csv.h"
#include "io/records.h"
#include "model/format.h"
#include "opt/random.h"
#include "records/stepper.h"
#include "reports/fit_file.h"
#include "reports/record_windows.h"

namespace pz::client {
namespace fs = std::filesystem;
namespace {

std::string Fmt(double x, int prec = 4) { return FormatG(x, prec); }

/// The seed of the replay's noise (stream i for record i): the floor it reports is reproducible.
constexpr uint64_t kReplayNoiseSeed = 22;

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
    throw InputError(
        path + ": " + std::to_string(csv.header.size()) +
        " columns; a reference has two: time and desired response (e.g. t_s,displacement_" +
        m.response_unit + ")");
  }
  const io::UnitConversion tu = io::ConvertUnit(UnitOf(csv.header[0]));
  if (tu.quantity != "time") {
    throw InputError(path + ": column '" + csv.header[0] +
                     "': the first column must be time with its unit (t_s, t_ms)");
  }
  const std::string yu_name = UnitOf(csv.header[1]);
  const io::UnitConversion yu = io::ConvertUnit(yu_name);
  if (yu_name.empty() || yu.canonical != m.response_unit) {
    throw InputError(path + ": column '" + csv.header[1] + "' is in '" + yu_name +
                     "', the model's response is in '" + m.response_unit +
                     "': give the reference in " + m.response_unit);
  }
  Reference r;
  for (size_t i = 0; i < csv.rows.size(); ++i) {
    r.t.push_back(csv.Number(i, 0) * tu.factor);
    r.y.push_back(csv.Number(i, 1) * yu.factor);
  }
  if (r.t.size() < 2) throw InputError(path + ": at least two samples are needed");
  const double dt = (r.t.back() - r.t.front()) / static_cast<double>(r.t.size() - 1);
  if (!(std::abs(dt - m.dt) <= 0.01 * m.dt)) {
    throw InputError(path + ": sample step " + Fmt(dt, 6) + " s; the model runs at " +
                     Fmt(m.dt, 6) + " s per step (resample the reference)");
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

Tracking TrackingError(const std::vector<double>& t, const std::vector<double>& ref,
                       const std::vector<double>& y) {
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

/// What keeps the inverse from giving a model's own drive back ("" when nothing does): the
/// rate-dependence play's lag over a quarter of a sample
/// (records::Stepper::rate_dependence_inverse_gain), which the compensator meets by planning two
/// samples.
std::string InverseCaveat(const records::Stepper& inv) {
  const double gain = inv.rate_dependence_inverse_gain();
  if (!(gain > 1)) return "";
  double tau = 0;
  for (size_t i = 0; i < inv.blocks().size(); ++i)
    if (inv.blocks()[i].kind == records::pzk::PZK_RATE_DEPENDENCE)
      tau = std::max(tau, inv.block_params(i)[1]);
  return "the rate-dependence play lags the drive by tau_r = " + Fmt(1e3 * tau) +
         " ms below its knee (" + Fmt(tau / inv.spec().dt, 3) +
         " samples): solved one sample at a time, its inverse would carry a drive " +
         "difference forward " + Fmt(gain, 3) + " × per sample" +
         (tau / inv.spec().dt > 2.0 / 3 ? " (and several drives give the same output)" : "") +
         "; the compensator plans two samples instead (the reference one sample ahead): stable, "
         "not exact";
}

/// How the compensator undoes the delay's fraction s ("" without one): in the one-step map (up to a
/// half) or backwards over its horizon (model/kernels/effects.h), and what that costs a noisy
/// reference: the exact inverse of the interpolation multiplies the Nyquist rate by 1 / |1 - 2 s|.
std::string DelayCaveat(const records::Stepper& inv) {
  const double s = inv.delay_fraction();
  if (!(s > 0)) return "";
  const int horizon = inv.delay_horizon();
  std::string how =
      "; its fraction " + Fmt(s, 3) + " of a sample is undone exactly" +
      (horizon > 0 ? ", backwards over " + std::to_string(horizon) + " sample(s) of that preview"
                   : "");
  return how + " (what the reference has at the Nyquist rate comes back " +
         (std::abs(1 - 2 * s) > 1e-3 ? Fmt(1 / std::abs(1 - 2 * s), 3) + " ×" : "without bound") +
         " in the drive)";
}

/// The drive for the reference (the preview: the reference Stepper::preview_samples ahead, the last
/// value held), and the clipping events.
std::vector<double> Compensate(records::Stepper& inv, const Reference& ref, double u0,
                               std::vector<Clip>* clips) {
  const size_t preview = inv.preview_samples();
  std::vector<double> u(ref.y.size());
  u[0] = u0;
  inv.Init(u0);
  inv.InversePrimeFrom(ref.y);
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
  std::string reference_zero = "auto";
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

/// The mean of the model's output over its major loop: two periods of a sine through the drive
/// limits (2000 steps each) from rest at the lower limit, the mean over the second. A training
/// record's mean response, for a record that spans the range.
double MajorLoopMean(const records::ModelSpec& m) {
  records::Stepper st(m);
  constexpr int kSteps = 2000;
  const double mid = 0.5 * (m.drive_min + m.drive_max), amp = 0.5 * (m.drive_max - m.drive_min);
  st.Init(m.drive_min);
  double sum = 0;
  for (int k = 1; k <= 2 * kSteps; ++k) {
    const double y = st.Step(mid - amp * std::cos(2 * std::numbers::pi * k / kSteps));
    if (k > kSteps) sum += y;
  }
  return sum / kSteps;
}

/// The zero of `mean`: the training records' mean response (fit.json's model.train_mean_output,
/// `train_mean`), else (a fit.json of version 1, a model-only file) the mean of the model's major
/// loop. The zero and what it is.
std::pair<double, std::string> MeanZero(const records::ModelSpec& m,
                                        const std::optional<double>& train_mean) {
  const std::string unit = " " + m.response_unit;
  if (train_mean)
    return {*train_mean, "the training records' mean response, " + Fmt(*train_mean) + unit};
  const double z = MajorLoopMean(m);
  return {z, "the mean of the model's major loop, " + Fmt(z) + unit +
                 " (the fit.json does not carry the training records' mean)"};
}

/// Where the reference's zero lies in the model's absolute output (--reference-zero): `absolute`
/// (the reference is the model's output itself: zero 0), `rest` (relative to the model's output at
/// rest under the rest drive, --rest-drive or the lower drive limit), `mean` (relative to the
/// training records' mean response, MeanZero), `auto` (absolute when the reference's mean lies
/// within the model's output range over the drive limits, mean otherwise). The zero, and how it
/// was chosen.
std::pair<double, std::string> ReferenceZero(const CompensateArgs& a, const records::ModelSpec& m,
                                             const std::optional<double>& train_mean,
                                             const Reference& ref) {
  std::string mode = a.reference_zero;
  const std::string unit = " " + m.response_unit;
  if (mode == "auto") {
    records::Stepper st(m);
    const double lo = st.Init(m.drive_min), hi = st.Init(m.drive_max);
    double mean = 0;
    for (double y : ref.y) mean += y / static_cast<double>(ref.y.size());
    const bool inside = mean >= std::min(lo, hi) && mean <= std::max(lo, hi);
    mode = inside ? "absolute" : "mean";
    const std::string why = "the reference's mean " + Fmt(mean) + unit +
                            (inside ? " lies" : " lies not") +
                            " within the model's output over its drive limits (" + Fmt(lo) + " … " +
                            Fmt(hi) + unit + "; --reference-zero absolute, rest or mean to choose)";
    if (inside) return {0.0, "absolute: " + why};
    const auto [z, what] = MeanZero(m, train_mean);
    return {z, "relative to " + what + ": " + why};
  }
  if (mode == "absolute") return {0.0, "absolute (--reference-zero absolute)"};
  if (mode == "rest") {
    const double u = std::isnan(a.rest_drive) ? m.drive_min : a.rest_drive;
    records::Stepper st(m);
    const double z = st.Init(u);
    return {z, "relative to the model's rest output " + Fmt(z) + unit + " at " + Fmt(u) + " " +
                   m.drive_unit + " (--reference-zero rest)"};
  }
  if (mode == "mean") {
    const auto [z, what] = MeanZero(m, train_mean);
    return {z, "relative to " + what + " (--reference-zero mean)"};
  }
  throw InputError("--reference-zero '" + a.reference_zero + "': absolute, rest, mean or auto");
}

int RunReference(const CompensateArgs& a, const records::ModelSpec& m,
                 const std::optional<double>& train_mean) {
  Reference ref = ReadReference(a.reference, m);
  // Not a structured binding: clang 14 (the sanitizer build) cannot capture one in a lambda.
  const std::pair<double, std::string> zero_pair = ReferenceZero(a, m, train_mean, ref);
  const double zero = zero_pair.first;
  const std::string& zero_how = zero_pair.second;
  for (double& y : ref.y) y += zero;  // the model's absolute output from here on
  std::optional<records::ModelSpec> other;
  if (!a.check_model.empty()) {
    other = reports::LoadFit(a.check_model);
    if (other->response_unit != m.response_unit || other->drive_unit != m.drive_unit) {
      throw InputError("--check-model " + a.check_model + ": drive in " + other->drive_unit +
                       ", response in " + other->response_unit + "; the model's are " +
                       m.drive_unit + ", " + m.response_unit);
    }
  }
  const double u0 = std::isnan(a.rest_drive) ? RestDrive(m, ref.y[0]) : a.rest_drive;
  records::Stepper inv(m);
  std::vector<Clip> clips;
  const std::vector<double> u = Compensate(inv, ref, u0, &clips);
  records::Stepper fwd(m);
  const std::vector<double> y = Forward(fwd, u);
  const Tracking e = TrackingError(ref.t, ref.y, y);
  // The forward model may diverge on the drive (an unstable oscillator fitted on little data): its
  // prediction from there on is left empty, and said so, rather than written as NaN.
  const size_t diverged = static_cast<size_t>(
      std::find_if(y.begin(), y.end(), [](double v) { return !std::isfinite(v); }) - y.begin());
  io::WriteFileWith(a.out, [&](std::ostream& os) {
    os << "t_s,drive_" << m.drive_unit << ",predicted_" << m.response_unit << "\n";
    for (size_t k = 0; k < u.size(); ++k)
      os << io::FormatNumber(ref.t[k]) << "," << io::FormatNumber(u[k]) << ","
         << (k < diverged ? io::FormatNumber(y[k] - zero) : std::string()) << "\n";
  });
  const auto range = std::minmax_element(ref.y.begin(), ref.y.end());
  std::cout << "piezoid compensate: " << m.Model()->Describe() << " from " << a.model
            << ", reference " << a.reference << " (" << ref.y.size() << " samples, range "
            << Fmt(*range.second - *range.first) << " " << m.response_unit << ")\n"
            << "  reference " << zero_how << "\n"
            << "  drive written to " << a.out << " (rest drive " << Fmt(u0) << " " << m.drive_unit
            << ", limits " << Fmt(inv.ctl().u_lo) << " … " << Fmt(inv.ctl().u_hi) << " "
            << m.drive_unit << ")\n"
            << "  predicted tracking error (forward model on that drive): ";
  if (diverged < y.size()) {
    std::cout << "none: the forward model's output on that drive is not finite from "
              << Fmt(ref.t[diverged])
              << " s on (it diverges: the model is unstable there; the prediction column is left "
                 "empty)\n";
  } else {
    std::cout << "RMSE " << Fmt(e.rmse) << " " << m.response_unit << ", max " << Fmt(e.max_abs)
              << " at " << Fmt(e.max_at) << " s\n";
  }
  if (inv.has_delay()) {
    std::cout
        << "  the model's delay cannot be undone by a causal step: the reference's preview of "
        << inv.preview_samples() << " sample(s) was used (the drive leads it)" << DelayCaveat(inv)
        << "\n";
  }
  if (const std::string caveat = InverseCaveat(inv); !caveat.empty())
    std::cout << "  " << caveat << "\n";
  if (clips.empty()) {
    std::cout << "  clipping: none (the reference is reachable within the drive limits)\n";
  } else {
    size_t total = 0;
    double worst = 0;
    for (const Clip& c : clips) total += c.samples, worst = std::max(worst, c.worst);
    std::cout
        << "  clipping: " << total << " sample(s) in " << clips.size()
        << " event(s) where the reference is beyond what the drive limits reach; largest shortfall "
        << Fmt(worst) << " " << m.response_unit << "\n";
    for (size_t i = 0; i < clips.size() && i < 10; ++i) {
      std::cout << "    " << Fmt(clips[i].t_start) << "–" << Fmt(clips[i].t_end)
                << " s: " << clips[i].samples << " sample(s), shortfall up to "
                << Fmt(clips[i].worst) << " " << m.response_unit << "\n";
    }
    if (clips.size() > 10) std::cout << "    … " << clips.size() - 10 << " more\n";
  }
  if (other) {
    records::Stepper check(*other);
    const std::vector<double> yo = Forward(check, u);
    const Tracking eo = TrackingError(ref.t, ref.y, yo);
    std::cout << "  exposure to model error: " << other->Model()->Describe() << " ("
              << a.check_model << ") predicts RMSE " << Fmt(eo.rmse) << " " << m.response_unit
              << ", max " << Fmt(eo.max_abs) << " at " << Fmt(eo.max_at) << " s on this drive\n";
  }
  return 0;
}

int RunReplay(const CompensateArgs& a, const records::ModelSpec& m) {
  const io::RecordSet set = reports::LoadRecordSetWithWindows(a.replay, a.train_windows,
                                                              a.validate_windows, a.test_windows);
  if (set.response_unit != m.response_unit || set.drive_unit != m.drive_unit) {
    throw InputError("--replay " + a.replay + ": drive in " + set.drive_unit + ", response in " +
                     set.response_unit + "; the model's are " + m.drive_unit + ", " +
                     m.response_unit);
  }
  std::cout << "piezoid compensate --replay: " << m.Model()->Describe() << " from " << a.model
            << " on " << a.replay << "\n";
  double noise = NAN;
  std::string noise_how;
  try {
    const records::NoiseFloor nf = records::EstimateNoiseFloor(set);
    noise = nf.sigma;
    noise_how = nf.used;
  } catch (const InputError& e) {
    noise_how = std::string("no estimate: ") + e.what();
  }
  if (const std::string caveat = InverseCaveat(records::Stepper(m)); !caveat.empty()) {
    std::cout << "  " << caveat
              << " (the noiseless replay of the model's own response shows how far from exact)\n";
  }
  if (const records::Stepper st(m); st.has_delay()) {
    std::cout << "  the model's delay: each drive solved for the response " << st.preview_samples()
              << " sample(s) later" << DelayCaveat(st) << "\n";
  }
  const std::string& du = m.drive_unit;
  const std::string& yu = m.response_unit;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    if (std::abs(r.dt - m.dt) > 0.01 * m.dt) {
      throw InputError(r.Label() + ": sample step " + Fmt(r.dt, 6) + " s; the model runs at " +
                       Fmt(m.dt, 6) + " s");
    }
    // The model on the applied drive; the record's offset as the fit takes it (its offset mode: by
    // default the least-squares offset over the scored window), so that the inverse sees the
    // measured response in the model's frame: a sensor's zero is not a drive.
    const std::vector<double> sim = records::SimulateRecord(m, r);
    std::vector<double> signed_sim(sim.size());
    for (size_t k = 0; k < sim.size(); ++k) signed_sim[k] = sim[k] - m.offset;
    const double offset = records::RecordOffset(r, signed_sim, signed_sim[0]);
    std::vector<double> measured(r.size());
    for (size_t k = 0; k < r.size(); ++k) measured[k] = r.y[k] - offset + m.offset;
    const records::ReplayError e = records::ReplayDrive(m, r, measured);
    std::cout << "  " << r.name << " (" << model::CaseRoleName(r.role) << ", " << e.n
              << " samples): drive RMSE " << Fmt(e.rms_u) << " " << du
              << "; through the local gain " << Fmt(e.rms_y) << " " << yu << " RMS, max "
              << Fmt(e.max_y) << " " << yu;
    if (std::isfinite(noise)) std::cout << " (" << Fmt(e.rms_y / noise, 3) << " × the noise floor)";
    std::cout << "; record offset " << Fmt(offset) << " " << yu << " ("
              << io::OffsetModeName(r.offset_mode) << "; the model's " << Fmt(m.offset) << ")";
    if (e.clipped > 0)
      std::cout << "; " << e.clipped << " sample(s) clipped to the record's drive range";
    if (e.no_gain > 0)
      std::cout << "; " << e.no_gain
                << " sample(s) where the model's local gain is not finite, left out of the " << yu
                << " figures";
    std::cout << "\n";
    // What the inverse itself and the noise give without model error: the model's own response to
    // the applied drive replayed, noiseless (the inverse's exactness: ≈ 0 but for a drive the
    // output does not depend on, and a rate-dependence lag's two-sample plan) and with
    // white noise of the floor's σ (a fixed seed per record).
    const records::ReplayError exact = records::ReplayDrive(m, r, sim);
    std::cout << "    the model's own response replayed: noiseless " << Fmt(exact.rms_u) << " "
              << du;
    if (std::isfinite(noise)) {
      opt::Rng rng(opt::StreamSeed(kReplayNoiseSeed, i));
      std::vector<double> noisy(sim);
      for (double& v : noisy) v += noise * synth::NormalDraw(rng);
      const records::ReplayError floor = records::ReplayDrive(m, r, noisy);
      std::cout << ", with noise of the floor's σ " << Fmt(floor.rms_u) << " " << du << " ("
                << Fmt(floor.rms_y) << " " << yu
                << " through the local gain): the drive error of the inverse and the noise, "
                   "without model error";
      if (floor.rms_u > 0) std::cout << "; measured " << Fmt(e.rms_u / floor.rms_u, 3) << " × that";
    }
    std::cout << "\n";
  }
  if (std::isfinite(noise)) {
    std::cout << "  noise floor " << Fmt(noise) << " " << yu << " (" << noise_how << ")\n";
  } else {
    std::cout << "  noise floor: " << noise_how << "\n";
  }
  return 0;
}

}  // namespace

void RegisterCompensate(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<CompensateArgs>();
  CLI::App* cmd =
      app.add_subcommand("compensate",
                         "Feed-forward compensation with a fitted model (fit.json): the drive that "
                         "makes the model follow a reference "
                         "(--reference), or the inverse replayed on measured records (--replay).");
  cmd->add_option("--model", a->model, "fit.json of piezoid fit")
      ->required()
      ->type_name("FIT.json");
  auto* ref = cmd->add_option("--reference", a->reference,
                              "CSV: time and desired response (units in the column names)");
  auto* replay = cmd->add_option("--replay", a->replay,
                                 "record set: run the inverse on the measured responses");
  ref->excludes(replay);
  cmd->add_option("--out", a->out, "the drive CSV (with --reference)")->type_name("DRIVE.csv");
  cmd->add_option("--check-model", a->check_model,
                  "another fit.json: the tracking error it predicts for the drive");
  cmd->add_option("--rest-drive", a->rest_drive,
                  "the drive at rest before the reference (default: the rest drive "
                  "whose output is the reference's first value)");
  cmd->add_option("--reference-zero", a->reference_zero,
                  "where the reference's zero lies: absolute (the model's output itself), rest "
                  "(the model's output at rest under --rest-drive, default the lower drive "
                  "limit), mean (a zero-mean reference about the training records' mean response, "
                  "or the mean of the model's major loop for a fit.json without it), auto "
                  "(default: absolute when the reference's mean "
                  "lies within the model's output range, mean otherwise)")
      ->type_name("absolute|rest|mean|auto");
  cmd->add_option("--train-window", a->train_windows,
                  "--replay of one CSV: a training window START:END [s]");
  cmd->add_option("--validate-window", a->validate_windows,
                  "--replay of one CSV: a validation window START:END [s]");
  cmd->add_option("--test-window", a->test_windows,
                  "--replay of one CSV: a test window START:END [s]");
  cmd->callback([a, &exit_code] {
    std::optional<double> train_mean;
    const records::ModelSpec m = reports::LoadFit(a->model, &train_mean);
    if (!a->replay.empty()) {
      exit_code = RunReplay(*a, m);
      return;
    }
    if (a->reference.empty())
      throw InputError("compensate: give --reference REF.csv (with --out) or --replay RECORDS");
    if (a->out.empty()) throw InputError("compensate --reference: give --out DRIVE.csv");
    exit_code = RunReference(*a, m, train_mean);
  });
}

}  // namespace pz::client
