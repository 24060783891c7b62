// libFuzzer target: everything the master decodes from the network or a user, and the job-spec
// validation behind it. The first input byte picks the decoder, the rest is its input:
//   0 worker → master frame      (DecodeWorkerToMaster; re-encoded and decoded again)
//   1 client request frame       (DecodeClientRequest; a submitted spec is validated)
//   2 binary JobSpec             (DecodeJobSpec + kinds::All().Validate)
//   3 protobuf-JSON JobSpec      (JobSpecFromJson + kinds::All().Validate)
//   4 master → worker frame      (DecodeMasterToWorker, the worker's side; a context's spec is
//                                 validated as the worker does)
//   5 CURVE key file text        (ParseCurveKeyFile)
// Build and run: fuzz/run.sh [seconds] (clang, -fsanitize=fuzzer,address,undefined).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include <google/protobuf/stubs/logging.h>

#include "kinds/kinds.h"
#include "service/security.h"
#include "service/wire_codec.h"

namespace {

using namespace pz::job;
using namespace pz::service;
using pz::opt::Genome;
namespace kinds = pz::kinds;

[[noreturn]] void Fail(const char* what) {
  std::fprintf(stderr, "fuzz_master: %s\n", what);
  std::abort();
}

void Validate(const JobSpec& spec) {
  const auto violations = kinds::All().Validate(spec);
  for (const auto& v : violations)
    if (v.description.empty()) Fail("a violation without a description");
  // A spec that validates must encode to bytes that decode to the same encoding (the master
  // stores and hashes these bytes; workers decode them).
  if (violations.empty()) {
    const std::string bytes = EncodeJobSpec(spec);
    JobSpec again;
    std::vector<FieldViolation> v2;
    if (!DecodeJobSpec(bytes, &again, &v2).ok() || !v2.empty())
      Fail("a valid spec's encoding does not decode");
    if (EncodeJobSpec(again) != bytes) Fail("a valid spec's encoding is not stable");
  }
}

}  // namespace

// protobuf logs every string field with invalid UTF-8 it meets: silence it (the decoders' answers
// are what is checked).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  google::protobuf::SetLogHandler(nullptr);
  (void)kinds::All();  // every kind the master and the workers have (kinds/kinds.h) is fuzzed
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string_view in(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 6) {
    case 0: {
      WorkerMsg m;
      if (!DecodeWorkerToMaster(in, &m).ok()) break;
      WorkerMsg again;
      if (!DecodeWorkerToMaster(EncodeWorkerToMaster(m), &again).ok())
        Fail("a decoded worker message does not survive re-encoding");
      break;
    }
    case 1: {
      ClientRequestMsg m;
      if (!DecodeClientRequest(in, &m).ok()) break;
      if (m.type == ClientRequestMsg::Type::kSubmit && m.decode_violations.empty())
        Validate(m.spec);
      ClientRequestMsg again;
      if (!DecodeClientRequest(EncodeClientRequest(m), &again).ok())
        Fail("a decoded client request does not survive re-encoding");
      break;
    }
    case 2: {
      JobSpec spec;
      std::vector<FieldViolation> v;
      if (DecodeJobSpec(in, &spec, &v).ok() && v.empty()) Validate(spec);
      break;
    }
    case 3: {
      JobSpec spec;
      std::vector<FieldViolation> v;
      if (JobSpecFromJson(std::string(in), &spec, &v).ok() && v.empty()) Validate(spec);
      break;
    }
    case 4: {
      WorkerMsg m;
      if (!DecodeMasterToWorker(in, &m).ok()) break;
      if (m.type == WorkerMsg::Type::kContext) {
        JobSpec spec;
        std::vector<FieldViolation> v;
        if (DecodeJobSpec(m.context_spec, &spec, &v).ok() && v.empty()) Validate(spec);
      }
      break;
    }
    case 5: {
      CurveKeyPair p;
      (void)ParseCurveKeyFile(in, "fuzz", &p);
      break;
    }
  }
  return 0;
}
