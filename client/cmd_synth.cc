// `piezoid synth-stack`: writes a real-like stack record set (synth/reallike.h, issue 22 item 5)
// in the manifest format (io/records.h; `piezoid fit`, `diagnose --records` and `records` read it)
// with its truth: truth.json (the plant, the sensor, each record's drive, offset and realised
// noise, the true noise floor) and a README.md saying how it was made.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "client/commands.h"
#include "fit.pb.h"
#include "io/csv.h"
#include "io/fit_model.h"
#include "io/records.h"
#include "model/status.h"
#include "synth/reallike.h"
#include "synth/reallike_ring.h"

namespace pz::client {
namespace fs = std::filesystem;
namespace {

struct SynthArgs {
  std::string out;
  synth::RealLikeOptions o;
  bool no_creep = false;
  bool ringing = false;     ///< --ringing: the second generator (synth/reallike_ring.h)
  std::string train_drive;  ///< --train-drive: a CSV (time, drive) the training record plays
};

/// The drive column of a CSV (first column time from 0 at the sample rate fs, second the drive).
std::vector<double> ReadDrive(const std::string& path, double fs) {
  const io::CsvTable csv = io::ReadCsvFile(path);
  csv.RequireRows();
  if (csv.header.size() < 2)
    throw InputError(path + ": --train-drive needs two columns (time [s], drive [V])");
  std::vector<double> t, u;
  for (size_t r = 0; r < csv.rows.size(); ++r) {
    t.push_back(csv.Number(r, 0));
    u.push_back(csv.Number(r, 1));
  }
  const double rate = io::CheckUniformTimeGrid(csv, 0, t, 0.01, "the played drive starts at t = 0");
  if (std::abs(rate - fs) > 1e-6 * fs) {
    throw InputError(path + ": sampled at " + io::FormatNumber(rate) + " Hz; --fs is " +
                     io::FormatNumber(fs) + " Hz (give --fs " + io::FormatNumber(rate) + ")");
  }
  return u;
}

/// The set's truth as truth.json (the one conversion of it; io/fit_model.h writes it).
std::string TruthJson(const synth::RealLikeSet& s) {
  const synth::RealLikeStack& st = s.options.stack;
  const synth::RealLikeSensor& se = s.options.sensor;
  proto::SynthTruth t;
  proto::SynthPlant& p = *t.mutable_plant();
  p.set_model(
      "Preisach (Everett function of a Gaussian width x Gaussian centre density, skewed) + "
      "reversible linear-quadratic part, then log creep (relaxations 3 per decade), then the "
      "sensor's lag");
  p.set_u_lo_v(st.u_lo);
  p.set_u_hi_v(st.u_hi);
  p.set_stroke_um(st.stroke_um);
  p.set_hysteresis_share(st.hysteresis_share);
  p.set_density_width(st.density_width);
  p.set_density_width_spread(st.density_width_spread);
  p.set_density_center_spread(st.density_center_spread);
  p.set_asymmetry(st.asymmetry);
  p.set_quadratic(st.quadratic);
  p.set_creep_per_decade(st.creep_per_decade);
  p.set_creep_tau_min_s(st.creep_tau_min_s);
  p.set_creep_tau_max_s(st.creep_tau_max_s);
  p.set_everett_grid(st.everett_grid);
  p.set_major_loop_width_share(s.major_loop_width);
  if (st.rate_lag_v > 0) {  // only when present: the default set's truth.json stays the same bytes
    p.set_rate_lag_v(st.rate_lag_v);
    p.set_rate_time_s(st.rate_time_s);
    p.set_rate_model(
        "effective drive held within +- lambda of the applied u, lambda = rate_lag_V "
        "tanh(rate_time_s |du/dt| / rate_lag_V), into the Preisach and reversible parts (du/dt "
        "after the amplifier)");
  }
  if (st.driver_tau_s > 0) p.set_driver_tau_s(st.driver_tau_s);
  proto::SynthSensor& q = *t.mutable_sensor();
  q.set_fs_hz(se.fs_hz);
  q.set_oversample(se.oversample);
  q.set_lag_samples(se.lag_samples);
  q.set_noise_white_um(se.noise_white_um);
  q.set_noise_colored_um(se.noise_colored_um);
  q.set_colored_time_s(se.colored_time_s);
  q.set_quantum_um(se.quantum_um);
  q.set_drive_quantum_v(se.drive_quantum_v);
  q.set_offset_range_um(se.offset_range_um);
  proto::SynthNoiseFloor& n = *t.mutable_noise_floor();
  n.set_nominal_um(s.nominal_floor_um);
  n.set_realised_um(s.realised_floor_um);
  n.set_definition(
      "RMS of measured - (noise-free response + offset): what a perfect model leaves; nominal = "
      "sqrt(white^2 + coloured^2 + quantum^2/12), realised = over every scored sample");
  for (const synth::RealLikeRecordTruth& r : s.truth) {
    proto::SynthRecordTruth& g = *t.add_records();
    g.set_record(r.name);
    g.set_role(r.role);
    g.set_drive(r.drive);
    g.set_offset_um(r.offset_um);
    g.set_noise_rms_um(r.noise_rms_um);
    g.set_scored_samples(static_cast<int64_t>(r.scored));
  }
  t.set_seed(s.options.seed);
  return io::WriteSynthTruth(t);
}

/// --ringing: the second generator's set (its own plant and sensor; --seed and --out only).
int RunRinging(const SynthArgs& a) {
  synth::RingingOptions o = synth::RingingDefaults();
  o.seed = a.o.seed;
  const synth::RingingSet s = synth::GenerateRingingSet(o);
  const fs::path out(a.out);
  io::WriteRecordSet(s.set, out);
  io::WriteFileWith(out / "README.md", [&](std::ostream& os) {
    os << "# A ringing stage's record set (generated)\n\nMade by `piezoid synth-stack --ringing "
       << "--out " << a.out << " --seed " << o.seed
       << "` (synth/reallike_ring.h): a Preisach stack (" << o.stack.u_lo << " … " << o.stack.u_hi
       << " V, " << o.stack.stroke_um << " um) with log creep, in a stage with a " << o.mode_hz
       << " Hz mode (zeta " << o.mode_zeta << "), recorded at " << o.sensor.fs_hz
       << " Hz; each record starts right after a step of " << o.step_um
       << " um to its rest, so the rest rings and settles.\n\n"
       << "| record | role | drive | offset [um] | noise RMS [um] |\n|---|---|---|---|---|\n";
    for (const auto& t : s.truth)
      os << "| " << t.name << " | " << t.role << " | " << t.drive << " | "
         << io::FormatNumber(t.offset_um) << " | " << io::FormatNumber(t.noise_rms_um) << " |\n";
    os << "\nThe sensor's white noise: " << io::FormatNumber(s.sensor_floor_um)
       << " um; with each recording's own wander (what the repeats scatter by): "
       << io::FormatNumber(s.realised_floor_um) << " um.\n";
  });
  std::cout << "written " << s.set.records.size() << " records to " << out.string()
            << " (sensor noise " << io::FormatNumber(s.sensor_floor_um) << " um, true floor "
            << io::FormatNumber(s.realised_floor_um) << " um; README.md)\n";
  return 0;
}

int RunSynth(const SynthArgs& a) {
  if (a.ringing) return RunRinging(a);
  synth::RealLikeOptions o = a.o;
  if (a.no_creep) o.stack.creep_per_decade = 0;
  if (!a.train_drive.empty()) o.train_drive = ReadDrive(a.train_drive, o.sensor.fs_hz);
  const synth::RealLikeSet s = synth::GenerateRealLikeSet(o);
  const fs::path out(a.out);
  io::WriteRecordSet(s.set, out);
  io::WriteFileWith(out / "truth.json", [&](std::ostream& os) { os << TruthJson(s); });
  io::WriteFileWith(out / "README.md", [&](std::ostream& os) {
    os << "# A real-like stack record set (generated)\n\nMade by `piezoid synth-stack --out "
       << a.out << " --seed " << o.seed
       << "` (synth/reallike.h; the other options at their values in truth.json). The plant is "
       << "written independently of the product's families: a Preisach model (return-point memory) "
          "with an "
       << "asymmetric density, a reversible quadratic part, log creep, a sensor lag of "
       << o.sensor.lag_samples
       << " samples, white and coloured noise, quantisation, an offset per record and a rest "
          "before each record.\n\n"
       << "| record | role | drive | offset [um] | noise RMS [um] |\n|---|---|---|---|---|\n";
    for (const auto& t : s.truth)
      os << "| " << t.name << " | " << t.role << " | " << t.drive << " | "
         << io::FormatNumber(t.offset_um) << " | " << io::FormatNumber(t.noise_rms_um) << " |\n";
    os << "\nThe true noise floor: " << io::FormatNumber(s.realised_floor_um) << " um (nominal "
       << io::FormatNumber(s.nominal_floor_um) << " um). The major loop is "
       << io::FormatNumber(100 * s.major_loop_width) << " % of its stroke wide.\n";
  });
  std::cout << "written " << s.set.records.size() << " records to " << out.string()
            << " (true noise floor " << io::FormatNumber(s.realised_floor_um)
            << " um; truth.json, README.md)\n";
  return 0;
}

}  // namespace

void RegisterSynthStack(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<SynthArgs>();
  synth::RealLikeOptions& o = a->o;
  CLI::App* cmd = app.add_subcommand("synth-stack",
                                     "Write a real-like piezo stack record set with its truth (a "
                                     "Preisach plant with an asymmetric density, log "
                                     "creep, sensor lag, noise, quantisation, offsets, rests; "
                                     "independent of the product's families): a major-loop "
                                     "training sine and withheld records (a second sine, an "
                                     "amplitude ramped to zero and back, random reversals).");
  cmd->add_option("--out", a->out,
                  "output folder (manifest.csv, one CSV per record, truth.json, README.md)")
      ->required()
      ->type_name("DIR");
  cmd->add_option("--seed", o.seed, "seed of phases, reversals, offsets and noise");
  cmd->add_option("--fs", o.sensor.fs_hz, "sample rate [Hz]")->check(CLI::Range(10.0, 1e6));
  cmd->add_option("--frequency", o.frequency_hz, "sine frequency [Hz]")
      ->check(CLI::Range(1e-3, 1e5));
  cmd->add_option("--train-s", o.train_s, "training sine length [s]")->check(CLI::Range(0.5, 1e5));
  cmd->add_option("--withheld-s", o.withheld_s, "each withheld record's length [s]")
      ->check(CLI::Range(0.5, 1e5));
  cmd->add_option("--amplitude-share", o.amplitude_share,
                  "sine amplitude, share of the 0-150 V range")
      ->check(CLI::Range(0.01, 0.5));
  cmd->add_option("--lag-samples", o.sensor.lag_samples,
                  "sensor lag [samples], whole and fractional")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--noise", o.sensor.noise_white_um, "white noise RMS [um]")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--colored-noise", o.sensor.noise_colored_um, "coloured noise RMS [um]")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--quantum", o.sensor.quantum_um, "response resolution [um] (0: none)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--creep-per-decade", o.stack.creep_per_decade,
                  "log creep per decade of time (share)")
      ->check(CLI::Range(0.0, 0.099));
  cmd->add_flag("--no-creep", a->no_creep, "no creep");
  cmd->add_flag("--ringing", a->ringing,
                "the second generator instead (synth/reallike_ring.h): a 10 kHz stage with a "
                "mode, rests that ring and settle, loops growing from the bottom, chatter drives "
                "recorded three times (--seed and --out only)");
  cmd->add_option(
         "--train-drive", a->train_drive,
         "a CSV (time [s] from 0 at --fs, drive [V]) the training record plays instead of the "
         "sine, e.g. "
         "the excitation_drive.csv of a fit or diagnosis; the withheld records stay the same")
      ->type_name("FILE");
  cmd->add_option("--rate-lag", o.stack.rate_lag_v,
                  "rate dependence: the bound of the drive's rate-dependent lag [V] (0: none)")
      ->check(CLI::Range(0.0, 150.0));
  cmd->add_option("--rate-time", o.stack.rate_time_s,
                  "rate dependence: lag per rate below the knee [s]")
      ->check(CLI::Range(1e-6, 10.0));
  cmd->add_option("--driver-tau", o.stack.driver_tau_s,
                  "an amplifier first-order low-pass [s] (0: none)")
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--train-frequencies", o.train_frequencies_hz,
                  "training sines at these frequencies [Hz] (records that cover rates) instead of "
                  "one at --frequency")
      ->delimiter(',');
  cmd->add_option("--withheld-frequencies", o.withheld_frequencies_hz,
                  "withheld sines at these frequencies [Hz]")
      ->delimiter(',');
  cmd->add_flag("--chirp", o.chirp,
                "a withheld logarithmic chirp over the training frequencies' span");
  cmd->add_option("--asymmetry", o.stack.asymmetry, "skew of the Preisach density")
      ->check(CLI::Range(-10.0, 10.0));
  cmd->add_option("--hysteresis-share", o.stack.hysteresis_share,
                  "share of the stroke carried by the hysterons")
      ->check(CLI::Range(0.0, 0.95));
  cmd->callback([a, &exit_code] { exit_code = RunSynth(*a); });
}

}  // namespace pz::client
