// The "complete_model" job kind's fitness as a worker builds it: the spec through the binary
// encoding (as a worker gets it) or the JSON one (as a user writes it), checked to lose nothing,
// validated and made into a fitness by a registry holding the kind.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "complete/job_kind.h"
#include "job/job_kind.h"
#include "service/wire_codec.h"

namespace pz::testing {

inline std::unique_ptr<opt::FitnessFunction> RemoteCompleteFitness(const job::JobSpec& spec,
                                                                   bool json) {
  job::JobSpec decoded;
  std::vector<job::FieldViolation> v;
  if (json)
    EXPECT_TRUE(service::JobSpecFromJson(service::JobSpecToJson(spec), &decoded, &v).ok());
  else
    EXPECT_TRUE(service::DecodeJobSpec(service::EncodeJobSpec(spec), &decoded, &v).ok());
  EXPECT_TRUE(v.empty());
  EXPECT_EQ(service::EncodeJobSpec(decoded), service::EncodeJobSpec(spec));  // nothing lost
  decoded.external = job::ExternalSettings{};
  job::JobKindRegistry registry;
  registry.Register(complete::CompleteModelJobKind());
  for (const auto& x : registry.Validate(decoded)) ADD_FAILURE() << x.description;
  std::unique_ptr<opt::FitnessFunction> f;
  EXPECT_TRUE(registry.MakeFitness(decoded, &f).ok());
  return f;
}

}  // namespace pz::testing
