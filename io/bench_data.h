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
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/case_role.h"
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

  /// The stated drive on this record's grid: Sinusoid{V, f, cycles = N f / fs, fs}, so that
  /// SampleTimes() has exactly t.size() samples at k / fs.
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

/// Reads dir/cases.csv and every case file it lists. Throws pz::InputError (file:line: column …).
CaseSet LoadCaseSet(const std::filesystem::path& dir, const BenchReadOptions& options = {});

/// Reads one case file with its stated V, f (what the manifest says). Throws pz::InputError.
/// context (e.g. "case 3 of cases.csv line 4") is appended to whole-file errors such as a count
/// mismatch.
BenchCase LoadCaseFile(const std::filesystem::path& file, int number, double amplitude_v,
                       double frequency_hz, CaseRole role, const BenchReadOptions& options = {},
                       const std::string& context = "");

}  // namespace pz::io
