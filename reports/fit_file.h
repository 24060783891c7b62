// fit.json of a fit, and its model section as a records::ModelSpec: written by `piezoid fit`, read
// by `piezoid export FIT.json`, `piezoid compensate` and python's piezoid.Model.load. The JSON is
// io/fit_model.h's (protobuf JSON of proto/fit.proto); the one conversion of a fit's result to the
// stored message, and between the message's model section and the model both ways, is here. A
// fit.json of a format_version it does not read is refused with the ones it reads; a bad field is
// named.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "io/fit_model.h"
#include "io/records.h"
#include "records/excitation.h"
#include "records/fit.h"
#include "records/select.h"
#include "records/stepper.h"

namespace pz::records {
struct ExtrapolationCheck;  // records/extrapolation.h (not on the fuzzer's floor)
}

namespace pz::reports {

using io::kFitFormatVersion;

/// The model of a fit (the offset: the mean of the training records' offsets; the drive limits:
/// the training records' drive range; the sample step: the first training record's).
records::ModelSpec FittedModelSpec(const io::RecordSet& set, const records::FitResult& r,
                                   int substeps, int pi_operators);

/// The mean of the measured response over the training records' scored samples (fit.json's
/// model.train_mean_output: `compensate --reference-zero mean`'s zero). NaN without training
/// samples.
double TrainMeanOutput(const io::RecordSet& set);

/// What fit.json records of a run beside its result.
struct FitRun {
  double settle_s = 0;   ///< --settle-s
  int substeps = 2;      ///< --substeps
  int pi_operators = 0;  ///< the plays / levels (the fit's chosen levels replace it when it chose)
  std::string search;    ///< the search as run, one sentence (report.md's)
  std::string drive_file;  ///< the proposed training drive's file
};

/// fit.json's text of a fit (`selection`: --family auto's, or null): the model section (as
/// FittedModelSpec, with TrainMeanOutput), each record's errors, the uncertainty, the search, the
/// excitation and the selection.
std::string FitJson(const io::RecordSet& set, const records::FitResult& r,
                    const records::ExcitationReport& excitation,
                    const records::TrainingDriveProposal& proposal,
                    const std::vector<records::ExtrapolationCheck>& extrapolation,
                    const records::SelectionResult* selection, const FitRun& run);

/// The model section's JSON (fit.json's "model" object) of `m`.
std::string FitModelJson(const records::ModelSpec& m);

/// The spec of a fit.json's model section; `train_mean_output` (when given): its
/// train_mean_output, empty for a file without it (version 1, a model-only file). Throws
/// InputError naming the file and the field, the versions read, or a family/effect/parameter that
/// does not fit.
records::ModelSpec LoadFit(const std::string& path,
                           std::optional<double>* train_mean_output = nullptr);
/// LoadFit of a fit.json's text (`path` names it in the errors): the fuzzer's entry point.
records::ModelSpec LoadFitText(const std::string& path, const std::string& text,
                               std::optional<double>* train_mean_output = nullptr);

/// True when the file is a fit.json (a JSON object with "model"), not a network file.
bool LooksLikeFitJson(const std::string& path);

}  // namespace pz::reports
