// Record sets of a piezo stack stage (the committee-machine data, data/piezo-stack-bench/): a folder
// with a manifest `records.csv` (record, frequency_Hz, offset_V, amplitude_V, file, role) and one CSV
// per record (t_s, voltage_V, displacement_um), drive u = offset + A sin(2π f t) from rest at the
// offset.
//
// Every check names the file, the line and the column of what is wrong:
// manifest — missing columns, non-numbers, NaN / inf, record not a positive integer, duplicate
//   records, f ≤ 0, A < 0, unknown roles (train / test), empty or missing record files, no records;
// record file — missing columns, ragged rows, non-numbers, NaN / inf, fewer than 2 samples, first
//   time not 0, time not strictly increasing, a step that differs from the first step (the sample
//   rate is inferred from it), and (optionally) a voltage that is not offset + A sin(2π f t) within
//   the tolerance.
// CRLF line ends, a UTF-8 BOM and blank trailing lines are accepted (see io/csv.h).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/case_role.h"
#include "model/status.h"

namespace pz::io {

using model::CaseRole;  // model/case_role.h: the one train / validate / test enum

/// A stack record's role: "train" or "test" (exact, lower case); nullopt otherwise.
std::optional<CaseRole> ParseRecordRole(std::string_view name);

/// One record of the stage: the stated drive and the samples.
struct StackRecord {
  int number = 0;            ///< record number from the manifest, > 0
  double frequency_hz = 0;   ///< excitation frequency f [Hz], > 0
  double offset_v = 0;       ///< drive offset [V]
  double amplitude_v = 0;    ///< drive amplitude A [V], ≥ 0
  CaseRole role = CaseRole::kTrain;
  std::filesystem::path file;  ///< the record's CSV (manifest folder / file)
  double sample_rate_hz = 0;   ///< fs = 1 / (t_1 − t_0)
  std::vector<double> t;       ///< [s], t_0 = 0, uniform steps 1 / fs
  std::vector<double> u;       ///< drive voltage [V]
  std::vector<double> y;       ///< measured displacement [µm]

  double dt() const { return 1.0 / sample_rate_hz; }
  /// "record 3 (40 Hz, A = 400 V, train)".
  std::string Label() const;
};

struct StackReadOptions {
  double time_rel_tol = 1e-6;      ///< every step equals the first within time_rel_tol · Δt_0
  bool check_voltage = true;       ///< check voltage_V against offset + A sin(2π f t)
  double voltage_rel_tol = 1e-4;   ///< tolerance relative to |offset| + A
  double voltage_abs_tol_v = 1e-3; ///< [V], added to the relative tolerance
  pz::Status Validate() const;
};

/// A loaded record set, in manifest order.
struct StackRecordSet {
  std::filesystem::path dir;
  std::vector<StackRecord> records;

  const StackRecord* Find(int number) const;  ///< nullptr if absent
  std::vector<const StackRecord*> WithRole(CaseRole role) const;
};

/// Reads dir/records.csv and every record file it lists. Throws pz::InputError (file:line: column …).
StackRecordSet LoadStackRecordSet(const std::filesystem::path& dir,
                                  const StackReadOptions& options = {});

/// Reads one record file with what the manifest states about it. `context` (e.g. "record 3 of
/// records.csv line 4") is appended to whole-file errors. Throws pz::InputError.
StackRecord LoadStackRecordFile(const std::filesystem::path& file, int number, double frequency_hz,
                                double offset_v, double amplitude_v, CaseRole role,
                                const StackReadOptions& options = {},
                                const std::string& context = "");

}  // namespace pz::io
