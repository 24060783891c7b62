// The excitation and identifiability report (records/excitation.h) in the reports of `piezoid fit`
// and `piezoid diagnose --records`: a section of report.md, an "excitation" object of the JSON,
// terminal lines, and the proposed training drive as a CSV the user can play
// (excitation_drive.csv: t_s, drive_<unit>).
#pragma once

#include <filesystem>
#include <ostream>

#include "io/records.h"
#include "records/excitation.h"

namespace pz::proto {
class Excitation;
}

namespace pz::reports {

/// The proposed training drive's file in a report folder.
inline constexpr const char* kProposedDriveFile = "excitation_drive.csv";

/// "## Excitation" section: what training excites, each withheld record's needs, the proposal.
void WriteExcitationMarkdown(std::ostream& os, const io::RecordSet& set,
                             const records::ExcitationReport& report,
                             const records::TrainingDriveProposal& proposal,
                             const std::string& drive_file);
/// The report and the proposal as their stored message (the one conversion: fit.json's and
/// diagnosis.json's "excitation"; `out` replaced).
void ExcitationOf(const io::RecordSet& set, const records::ExcitationReport& report,
                  const records::TrainingDriveProposal& proposal, const std::string& drive_file,
                  proto::Excitation* out);
/// One line per withheld record with needs (none: one line saying so).
void PrintExcitationSummary(std::ostream& os, const io::RecordSet& set,
                            const records::ExcitationReport& report);
/// Writes the proposal as t_s,drive_<unit> (t = k / fs).
void WriteProposedDrive(const std::filesystem::path& path, const io::RecordSet& set,
                        const records::TrainingDriveProposal& proposal);

}  // namespace pz::reports
