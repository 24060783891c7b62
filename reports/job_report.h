// What `piezoid fetch` writes for a job fetched from the master: the best networks and, for an
// hgann job, the same validation report as `piezoid identify` (reports/identify_report.h
// WriteIdentifyReport), rebuilt from the job's spec (spec → HgannFitnessConfig → HgannFitness), its
// generation log and its best genomes.
#pragma once

#include <filesystem>
#include <optional>
#include <ostream>
#include <vector>

#include "reports/identify_report.h"
#include "service/service_types.h"

namespace pz::reports {

/// A job as the master answers a fetch.
struct FetchedJob {
  service::JobInfo info;
  job::JobSpec spec;
  std::vector<service::ScoredGenome> best;     ///< best first
  std::vector<service::GenerationRecord> log;  ///< one record per generation
  std::vector<io::SavedNetwork> networks;  ///< best[i] as the master decoded it (hgann), or empty
  std::optional<job::LawCommittee> committee;  ///< the law's committee on best[0] (hgann), or none
};

/// The GA's final summary of a job: termination from its state and message, best from best[0],
/// best generation = the last generation that improved, counters from the log.
opt::GaSummary GaSummaryOfJob(const FetchedJob& job);

/// A job's k-th best genome as a network file (chromosome, decoded network, provenance).
io::SavedNetwork SavedNetworkOfJob(const FetchedJob& job, const hgann::HgannFitness& fitness,
                                   size_t k);

/// The identification result of an hgann job (what RunIdentify returns for a local run).
hgann::IdentifyResult IdentifyResultOfJob(const FetchedJob& job,
                                          const hgann::HgannFitness& fitness);

/// The report options of an hgann job: population, seed, ranges, spread penalty from its spec.
IdentifyOptions IdentifyOptionsOfJob(const FetchedJob& job, const std::filesystem::path& out_dir,
                                     bool plots);

struct FetchOutput {
  std::vector<std::filesystem::path> written;
  std::filesystem::path report;  ///< report.md (hgann jobs), else empty
};

/// Writes a fetched job into out_dir: for hgann jobs networks/best-<k>.pb and .json for each
/// fetched individual and the identify report (report.md, network.pb/.json = the best,
/// progress.csv, validation.csv, parameters.csv, traces, figures); for other kinds best.csv and
/// progress.csv. Prints a summary to `terminal`. Errors (no individual yet, a spec that does not
/// build) are a Status; files already written stay.
Status WriteFetchedJob(const FetchedJob& job, const std::filesystem::path& out_dir, bool plots,
                       std::ostream& terminal, FetchOutput* out);

}  // namespace pz::reports
