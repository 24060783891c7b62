// The service-client library (svcclient/) on its own, without the `piezoid` command: a program
// that links only pz::svcclient (and what its line names) submits, asks and watches through
// ServiceClient, and gets the library's answers — here from a master that is not there: every
// request is kUnavailable naming the endpoint, after its retries, within its timeouts.
#include "svcclient/service_client.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace pz::client {
namespace {

namespace fs = std::filesystem;

/// An endpoint nothing listens on: an ipc socket path in a fresh folder of this process.
std::string NobodyThere() {
  const fs::path dir = fs::temp_directory_path() / ("pz_svcclient_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return "ipc://" + (dir / "master.sock").string();
}

TEST(ServiceClientLibrary, AnAbsentMasterIsUnavailableNamingTheEndpoint) {
  svcclient::ServiceClientOptions o;
  o.endpoint = NobodyThere();
  o.timeout_ms = 50;
  o.retries = 2;
  o.watch_reconnect_s = 0.1;
  svcclient::ServiceClient c(o);
  const auto t0 = std::chrono::steady_clock::now();
  service::JobInfo info;
  const Status status = c.GetStatus("job-1", &info);
  EXPECT_EQ(status.code(), StatusCode::kUnavailable) << status.message();
  EXPECT_NE(status.message().find(o.endpoint), std::string::npos) << status.message();
  std::vector<service::JobInfo> jobs;
  EXPECT_EQ(c.List(&jobs).code(), StatusCode::kUnavailable);
  EXPECT_EQ(c.Cancel("job-1").code(), StatusCode::kUnavailable);
  const Status watch = c.Watch(
      "job-1", [](const service::JobEvent&) { return true; }, std::chrono::milliseconds(300));
  EXPECT_EQ(watch.code(), StatusCode::kUnavailable) << watch.message();
  // Bounded by the timeouts and retries, not by a hang.
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(10));
}

TEST(ServiceClientLibrary, AJobSpecThatDoesNotParseIsRefusedBeforeAnythingIsSent) {
  svcclient::ServiceClientOptions o;
  o.endpoint = NobodyThere();
  o.timeout_ms = 50;
  o.retries = 1;
  svcclient::ServiceClient c(o);
  svcclient::SubmitResult r;
  std::vector<job::FieldViolation> bad;
  const Status s = c.SubmitJson("{\"seed\": \"not a number\"}", &r, &bad);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << s.message();
  EXPECT_TRUE(r.job_id.empty());
}

}  // namespace
}  // namespace pz::client
