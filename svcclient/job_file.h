// Job spec files as users write them: protobuf JSON (proto/job.proto, examples/). An hgann spec may
// name a case-set folder instead of listing its cases,
//
//   "hgann": { "case_set_dir": "../data/bimorph-fin/nominal", ... }
//
// which the client reads (io/bench_data.h LoadCaseSet; the path is relative to the JSON file's
// folder) and embeds as `cases` before submitting: the master never reads client paths.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "job/job_spec.h"
#include "model/status.h"

namespace pz::svcclient {

/// Parses `json` (a job spec; `base_dir` resolves a relative case_set_dir) and embeds the case set
/// it names. kInvalidArgument with every field violation in *violations when the spec is bad.
Status JobSpecFromJsonFile(const std::string& json, const std::filesystem::path& base_dir,
                           job::JobSpec* spec, std::vector<job::FieldViolation>* violations);

/// Reads `file` and calls JobSpecFromJsonFile with its folder. Errors start with the path.
Status LoadJobSpecFile(const std::filesystem::path& file, job::JobSpec* spec,
                       std::vector<job::FieldViolation>* violations);

/// Embeds the case set named by an hgann spec's case_set_dir (relative to base_dir) into its
/// cases and clears case_set_dir; source becomes the folder (relative to the current directory
/// when it lies below it). No-op for other kinds or an empty case_set_dir.
Status ResolveCaseSetDir(job::JobSpec* spec, const std::filesystem::path& base_dir,
                         std::vector<job::FieldViolation>* violations);

}  // namespace pz::svcclient
