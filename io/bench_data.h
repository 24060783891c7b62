// Bench case sets: a folder with a manifest `cases.csv` (case, amplitude_V, frequency_Hz, file,
// role) and one CSV per case (t_s, voltage_V, angle_deg), as in data/bimorph-fin/<set>/.
//
// Every check names the file, the line and the column of what is wrong:
// manifest — missing columns, non-numbers, NaN / inf, case not a positive integer, duplicate cases,
//   f ≤ 0 or V < 0, unknown roles (train / validate / test), missing case files, no cases;
// case file — missing columns, ragged rows, non-numbers, NaN / inf, fewer than 2 samples, first
// time
//   not 0, time not strictly increasing, a step that differs from the first step (the sample rate
//   is inferred from it), a sample count other than round(cycles · fs / f), and a voltage that is
//   not V sin(2π f t) within the tolerance.
// CRLF line ends, a UTF-8 BOM and blank trailing lines are accepted (see io/csv.h).
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/case_role.h"
#include "model/fin_case.h"
#include "model/signal.h"
#include "model/status.h"

namespace pz::io {

using model::CaseRole;  // model/case_role.h: the one train / validate / test enum
using model::CaseRoleName;
using model::ParseCaseRole;

/// One recorded case: the stated drive V sin(2π f t) and the record on its sample grid.
struct BenchCase {
  int number = 0;           ///< case number from the manifest, > 0
  double amplitude_v = 0;   ///< V [V]
  double frequency_hz = 0;  ///< f [Hz]
  CaseRole role = CaseRole::kTrain;
  std::filesystem::path file;     ///< the case's CSV (manifest directory / file)
  double sample_rate_hz = 0;      ///< fs [Hz] = 1 / (t_1 − t_0)
  std::vector<double> t;          ///< sample times [s], t_0 = 0, steps 1/fs
  std::vector<double> u;          ///< drive voltage [V]
  std::vector<double> angle_deg;  ///< measured fin angle [deg]
  double cycles = 0;  ///< the record length in drive cycles a job spec states (0: N f / fs)

  /// The stated drive on this record's grid: Sinusoid{V, f, cycles, fs}, cycles = N f / fs unless
  /// stated, so that SampleTimes() has exactly t.size() samples at k / fs.
  model::Sinusoid Drive() const;
  /// The recorded drive (t, u) as a sampled signal.
  model::SampledSignal SampledDrive() const;
};

/// Tolerances and expectations of the reader.
struct BenchReadOptions {
  double cycles =
      3.0;  ///< expected record length in drive cycles, N = round(cycles·fs/f); 0 = not checked
  double time_rel_tol =
      1e-6;  ///< every step must equal the first within time_rel_tol · Δt_0; t_0 within it of 0
  double voltage_rel_tol =
      1e-5;  ///< |u_k − V sin(2π f t_k)| ≤ voltage_rel_tol · V + voltage_abs_tol_v
  double voltage_abs_tol_v = 1e-6;  ///< [V], ≥ 0
  bool check_voltage = true;        ///< check the voltage column against the stated sinusoid
  pz::Status Validate() const;
};

/// A loaded case set, cases in manifest order.
struct CaseSet {
  std::filesystem::path dir;  ///< the folder read
  std::vector<BenchCase> cases;

  const BenchCase* Find(int number) const;  ///< nullptr if absent
  std::vector<const BenchCase*> WithRole(CaseRole role) const;
  std::vector<const BenchCase*> Training() const { return WithRole(CaseRole::kTrain); }
  std::vector<const BenchCase*> Validation() const { return WithRole(CaseRole::kValidate); }
  std::vector<const BenchCase*> Test() const { return WithRole(CaseRole::kTest); }
};

/// A bench case as given, before MakeBenchCase checks and completes it: a case file's columns, or
/// a job spec's case (job::HgannCaseSpec, the hgann and diagnose job kinds).
struct BenchCaseSamples {
  int number = 0;
  double amplitude_v = 0;   ///< the stated V [V]
  double frequency_hz = 0;  ///< the stated f [Hz]
  CaseRole role = CaseRole::kTrain;
  double sample_rate_hz = 0;      ///< fs [Hz]
  std::vector<double> angle_deg;  ///< measured fin angle [deg]
  std::vector<double> u;          ///< the recorded drive [V]; empty: the stated V sin(2π f t_k)
  std::vector<double> t;          ///< sample times [s]; empty: t_k = k / fs
  double cycles = 0;              ///< the stated record length in drive cycles (0: none stated)
  std::filesystem::path file;     ///< the case's file, or a label for a spec's case
};

/// Where a value of a case is, for messages: `field` is "amplitude_v", "frequency_hz",
/// "sample_rate_hz", "angle_deg", "u" or "t", `index` a sample (npos: the field as a whole; an
/// empty field: the case as a whole). E.g. "cases/c3.csv:12: column voltage_V" or
/// "hgann.cases[2].voltage_v[11]".
using BenchCaseWhere = std::function<std::string(std::string_view field, size_t index)>;

/// The samples of a job spec's case, labelled "case<number>": a job::HgannCaseSpec (the hgann and
/// diagnose kinds'), which io/ cannot name, or any struct with its fields (number, amplitude_v,
/// frequency_hz, role, sample_rate_hz, angle_deg, voltage_v).
template <typename CaseSpec>
BenchCaseSamples SamplesOfSpecCase(const CaseSpec& x) {
  BenchCaseSamples b;
  b.number = x.number;
  b.amplitude_v = x.amplitude_v;
  b.frequency_hz = x.frequency_hz;
  b.role = x.role;
  b.sample_rate_hz = x.sample_rate_hz;
  b.angle_deg = x.angle_deg;
  b.u = x.voltage_v;
  b.file = "case" + std::to_string(x.number);
  return b;
}

/// The places of a job spec's case (a job::HgannCaseSpec) for MakeBenchCase: "<prefix>" for the
/// case, "<prefix>.<field>[k]" for a sample, the drive u named voltage_v as in the spec.
BenchCaseWhere SpecCaseWhere(std::string prefix);

/// The one builder of a bench case: the case file reader (LoadCaseFile) and the hgann and
/// diagnose job kinds (a spec's cases) all make their cases here. Checks, each error naming its
/// place by `where` (and ending with `context`): V finite and >= 0; f and fs finite and > 0; at
/// least 2 angle samples, all finite; u and t empty or as many as the angle samples, u finite;
/// the sample count round(cycles · fs / f) for the stated cycles, else options.cycles (when > 0);
/// with options.check_voltage, u against V sin(2π f t) within the tolerance. Throws InputError.
BenchCase MakeBenchCase(BenchCaseSamples samples, const BenchReadOptions& options,
                        const BenchCaseWhere& where, const std::string& context = "");

/// The case ready to simulate (model::MakeFinCase, the one builder of a fin case): its stated
/// drive, its measured angle, trained on when its role is train, the saturations `given` or from
/// the measured extremes. Errors name the case's file.
model::FinCase MakeFinCase(const BenchCase& c,
                           const std::optional<model::SaturationPair>& given = std::nullopt);

/// Reads dir/cases.csv and every case file it lists. Throws pz::InputError (file:line: column …).
CaseSet LoadCaseSet(const std::filesystem::path& dir, const BenchReadOptions& options = {});

/// Reads one case file with its stated V, f (what the manifest says). Throws pz::InputError.
/// context (e.g. "case 3 of cases.csv line 4") is appended to whole-file errors such as a count
/// mismatch.
BenchCase LoadCaseFile(const std::filesystem::path& file, int number, double amplitude_v,
                       double frequency_hz, CaseRole role, const BenchReadOptions& options = {},
                       const std::string& context = "");

}  // namespace pz::io
