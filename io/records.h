// Record sets (issue 14): measured drive → response records of any actuator, read by `piezoid fit`
// and `piezoid records` (docs/records.md is the user's description of the format).
//
// A record set is a folder with a manifest `manifest.csv`, one row per record:
//
//   record,file,role[,t_start_s,t_end_s,offset,frequency_Hz,repeat,time_column,drive_column,  // NOLINT(length)
//                     response_column,time_unit,drive_unit,response_unit]
//
//   record    a unique name (letters, digits, - _ .)
//   file      the record's CSV, relative to the folder; several rows may use one file (windows)
//   role      train | validate | test
//   t_start_s, t_end_s   the scored window in the file's own time [s] (empty = whole record); the
//             samples before t_start are simulated (the model's warm-up), not scored
//   offset    fit (default: the least-squares response offset over the window) | rest (the mean
//             response over the record's leading rest segment, where the drive is constant, is the
//             model's rest output) | a number (response units: added to the model output)
//   *_column  the CSV's column names (defaults t_s, voltage_V, displacement_um)
//   frequency_Hz  the stated excitation frequency of the record (optional; `piezoid committee`
//             bands records by it)
//   repeat    the repeat group of the record (optional: letters, digits, - _ .): records of one
//             group are recordings of the same drive, and their scatter about each other is the
//             repeatability floor (records/noise_floor.h)
//   *_unit    the columns' units; when absent, the unit is the column name's suffix after the last
//             '_' (t_s → s). A unit stated in both places must agree.
//
// Units are converted to one set per quantity: time [s] (s, ms, us/µs); drive [V] (V, mV, kV) or
// as declared; response: length [µm] (m, mm, um/µm, nm), angle [deg] (deg, rad), or as declared
// (any other name is kept as is). Every record of a set must have the same drive and response
// quantity; otherwise "mismatched units" names both records.
//
// The drive is the measured samples, nothing is assumed about its shape (phase, offset, waveform).
// The time column must increase strictly; its steps must be uniform within `time_jitter` of the
// mean step (a recorder's rounded time stamps are accepted). The model starts at rest at the
// first sample of the file: the rest segment (the leading samples whose drive equals the first
// one) is detected and reported.
//
// Also read (converted on load, with their own checks): the stack bench folder of
// `piezoid committee` (records.csv: record, frequency_Hz, offset_V, amplitude_V, file, role; roles
// train/test, records named record<N>, offset 0, the stated frequency kept; the drive checked
// against offset + A sin(2π f t) on request), the bimorph-fin bench folder (cases.csv,
// io/bench_data.h, its voltage column checked against the stated sinusoid; the records of
// io/fin_records.h: the stated sinusoid is the drive, offset 0), and a single CSV file (one
// record, role train; windows are given by the command line, see SplitIntoWindows).
//
// Every error is a pz::InputError that names the file, the line and the column, or the record.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/case_role.h"

namespace pz::io {

enum class OffsetMode : int { kFit = 0, kRest = 1, kFixed = 2 };
/// "fit", "rest", "fixed".
const char* OffsetModeName(OffsetMode m);

/// One record (or one window of a file) in canonical units.
struct Record {
  std::string name;
  model::CaseRole role = model::CaseRole::kTrain;
  std::filesystem::path file;
  std::vector<double>
      t;  ///< [s], the file's own times (strictly increasing, uniform within jitter)
  std::vector<double> u;    ///< drive, canonical drive unit
  std::vector<double> y;    ///< response, canonical response unit
  double dt = 0;            ///< mean step (t.back() − t.front()) / (n − 1) [s]
  size_t first_scored = 0;  ///< the window: samples [first_scored, end_scored) are scored
  size_t end_scored = 0;
  size_t rest_samples = 0;  ///< leading samples with the drive of sample 0 (the rest segment)
  OffsetMode offset_mode = OffsetMode::kFit;
  double offset = 0;        ///< kFixed: the value; kRest: the mean response over the rest
  double quantum = 0;       ///< the response's quantisation step (0 if not quantised)
  double frequency_hz = 0;  ///< the stated excitation frequency [Hz] (a bench's, or a manifest's
                            ///< frequency_Hz column); 0 = not stated
  int manifest_line = 0;    ///< 0 when not from a manifest
  /// The repeat group (a manifest's repeat column): records of one group were recorded with the
  /// same drive; "" = none stated.
  std::string repeat;
  /// A bimorph-fin bench case's stated drive u = V sin(2π f t) on k / fs (io/fin_records.h): the
  /// grid trends and the bench form of the bimorph-fin family read it (the form simulates that
  /// sinusoid, records/families.h FamilyOptions::bench_form). None stated: stated() false.
  struct StatedSinusoid {
    int case_number = 0;        ///< the bench's case number (> 0)
    double amplitude_v = 0;     ///< V [V]
    double frequency_hz = 0;    ///< f [Hz]
    double cycles = 0;          ///< the record's length in drive cycles
    double sample_rate_hz = 0;  ///< fs [Hz] as stated (dt = 1 / fs)
    bool stated() const { return frequency_hz > 0 && sample_rate_hz > 0 && cycles > 0; }
  } sinusoid;

  size_t size() const { return t.size(); }
  size_t scored() const { return end_scored - first_scored; }
  double sample_rate_hz() const { return 1.0 / dt; }
  /// "train record 'a' (file.csv, 4–7 s)".
  std::string Label() const;
};

struct RecordSet {
  std::filesystem::path source;  ///< the folder or file read
  std::string format;            ///< "manifest", "stack-bench", "bimorph-fin-bench", "csv"
  std::string drive_unit = "V";  ///< canonical units of the set
  std::string response_unit = "um";
  std::vector<Record> records;

  std::vector<const Record*> WithRole(model::CaseRole role) const;
  const Record* Find(std::string_view name) const;
};

struct RecordReadOptions {
  double time_jitter = 0.01;     ///< every step within this fraction of the mean step, in (0, 0.5)
  size_t min_scored = 20;        ///< a window must hold at least this many samples
  double rest_tolerance = 1e-9;  ///< rest: |u − u_0| ≤ this × max |u| (plus 1e-12)
  /// A bench that states its drive (the stack bench: offset + A sin(2π f t)): check the measured
  /// drive against it (`piezoid committee`); off by default (the drive is the measured samples).
  bool check_stated_drive = false;
};

/// Reads a record set: a folder with manifest.csv, a stack bench folder (records.csv), a
/// bimorph-fin bench folder (cases.csv), or one CSV file. Throws pz::InputError.
RecordSet LoadRecordSet(const std::filesystem::path& path, const RecordReadOptions& options = {});

/// A window [t0, t1] of the file time as [first, end) sample indices of a record; throws
/// InputError naming `what` when it is empty, reversed, outside the record or shorter than
/// min_scored samples.
void SetWindow(Record& record, double t0_s, double t1_s, size_t min_scored,
               const std::string& what);

/// The settling convention (issue 22): every model of this project starts at rest at the first
/// sample's drive, by default with its memory centred there (the plays of a Prandtl–Ishlinskii
/// operator at u_0, a Bouc–Wen z at 0: a demagnetised stack; records/families.h
/// FamilyOptions::initial_state sets another), while a real stack at rest sits where its last move
/// left it — resting at the bottom of its range, below every hysteron, as after a descent. Until
/// the first large reversal wipes that memory out the two differ (on a real-like 45 µm stack,
/// 0.6–1.4 µm RMS over the first 0.5 s for prandtl-ishlinskii; docs/records.md), so a record can be
/// scored from `settle_s` after the end of its rest (its first sample whose drive leaves the rest
/// level) instead: its scored window starts at the later of that and its own start. settle_s ≥ 0
/// and finite; each record must keep min_scored samples, else InputError naming `what` and the
/// record.
void SkipSettling(RecordSet& set, double settle_s, size_t min_scored, const std::string& what);

/// Splits a one-record set (a single CSV) into windows: each (role, t0, t1) becomes a record named
/// by its role. Throws InputError if the set has more than one record or a window is bad.
struct WindowSpec {
  model::CaseRole role = model::CaseRole::kTrain;
  double t0_s = 0, t1_s = 0;
};
void SplitIntoWindows(RecordSet& set, const std::vector<WindowSpec>& windows,
                      const RecordReadOptions& options = {});
/// Parses "4:7" (seconds); throws InputError naming `flag` and the text.
WindowSpec ParseWindow(std::string_view text, model::CaseRole role, const std::string& flag);

/// Canonical unit of a declared unit name and the factor to it: "mm" → ("um", 1000). nullopt for a
/// name this table does not know (kept as is, factor 1).
struct UnitConversion {
  std::string canonical;
  double factor = 1;
  std::string quantity;  ///< "time", "voltage", "length", "angle", "force", or the unit name itself
};
UnitConversion ConvertUnit(std::string_view unit);

/// Writes a record set in the manifest format (each record's own CSV, the manifest); creates dir.
void WriteRecordSet(const RecordSet& set, const std::filesystem::path& dir);

}  // namespace pz::io
