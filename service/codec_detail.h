// Shared pieces of the codecs (service/*_codec.cc): serialisation helpers and the conversions of
// the messages that several envelopes carry (genomes, results, individuals, generation records,
// job specs, job info). Internal to service/: users include service/wire_codec.h.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "job.pb.h"
#include "service/wire_codec.h"
#include "wire.pb.h"

namespace pz::service::detail {

using job::CaseRole;
using job::CompleteModelProblem;
using job::CompleteModelRecord;
using job::ExternalSettings;
using job::FieldViolation;
using job::GaSettings;
using job::HgannCaseSpec;
using job::HgannProblem;
using job::JobSpec;
using job::ParameterRange;
using job::SyntheticProblem;
using opt::FitnessResult;
using opt::FitnessStatus;
using opt::GaState;
using opt::Genome;
using opt::RngState;
namespace pw = ::pz::wire;

inline constexpr uint32_t kCheckpointVersion = 1;
inline constexpr uint32_t kMaxGenomeBits = 1u << 20;

Status Malformed(const std::string& what);
/// Serialises with deterministic map order, so equal messages give equal bytes (content hashes).
std::string Deterministic(const google::protobuf::MessageLite& msg);
bool Parse(std::string_view bytes, google::protobuf::MessageLite* msg);
int ClampInt(uint64_t v);
bool ValidState(int s);
Status VersionCheck(uint32_t got);

void ToProto(const Genome& g, pw::Genome* p);
Status FromProto(const pw::Genome& p, Genome* g);
pw::FitnessCode ToProto(FitnessStatus s);
Status FromProto(pw::FitnessCode c, double cost, FitnessStatus* s);
void ToProto(const FitnessResult& r, int index, pw::TaskResult* t);
Status FromProto(const pw::TaskResult& t, FitnessResult* r);
void ToProto(const ScoredGenome& s, pw::Individual* p);
Status FromProto(const pw::Individual& p, ScoredGenome* s);
void ToProto(const GenerationRecord& r, pw::GenerationRecord* p);
GenerationRecord FromProto(const pw::GenerationRecord& p);
/// The GA's stopping rule on the wire (GA_TERMINATION_UNSPECIFIED = none).
pw::GaTermination ToProto(std::optional<opt::GaTermination> t);
std::optional<opt::GaTermination> FromProto(pw::GaTermination t);
void ToProto(const QuarantineRecord& q, pw::QuarantineRecord* p);
QuarantineRecord FromProto(const pw::QuarantineRecord& p);
void ToProto(const JobSpec& s, pw::JobSpec* p);
void FromProto(const pw::JobSpec& p, JobSpec* s, std::vector<FieldViolation>* v);
void InfoToProto(const JobInfo& i, pw::JobInfo* p);
void ToProto(const WorkersSnapshot& w, pw::WorkersReply* p);
WorkersSnapshot FromProto(const pw::WorkersReply& p);
Status InfoFromProto(const pw::JobInfo& p, JobInfo* i);
void ToProto(const job::LawCommittee& c, pw::LawCommittee* p);
/// Malformed (naming the field) when a case's lo / hi is not the 7 parameters or a candidate's
/// index is out of range.
Status FromProto(const pw::LawCommittee& p, job::LawCommittee* c);

template <typename Domain, typename ProtoList>
Status IndividualsFromProto(const ProtoList& list, std::vector<Domain>* out) {
  out->resize(list.size());
  for (int i = 0; i < list.size(); ++i)
    if (Status s = FromProto(list[i], &(*out)[i]); !s.ok()) return s;
  return Status::Ok();
}

}  // namespace pz::service::detail
