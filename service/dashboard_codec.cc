// The dashboard's JSON documents: domain structs → proto/dashboard.proto → protobuf's JSON printer.
#include <google/protobuf/util/json_util.h>

#include "dashboard.pb.h"
#include "service/codec_detail.h"

namespace pz::service {
using namespace detail;

namespace {

std::string Json(const google::protobuf::Message& m) {
  google::protobuf::util::JsonPrintOptions o;
  o.always_print_primitive_fields = true;
  o.preserve_proto_field_names = true;
  std::string out;
  (void)google::protobuf::util::MessageToJsonString(m, &out, o);
  return out;
}

}  // namespace

std::string DashboardStateJson(const std::string& master, double polled_unix_s, uint64_t polls,
                               const std::string& error, const std::vector<JobInfo>& jobs,
                               const WorkersSnapshot& workers, const std::string& workers_error,
                               const std::vector<std::string>& reports) {
  pw::DashboardState s;
  s.set_master(master);
  s.set_polled_unix_s(polled_unix_s);
  s.set_polls(polls);
  s.set_error(error);
  for (const JobInfo& j : jobs) InfoToProto(j, s.add_jobs());
  ToProto(workers, s.mutable_workers());
  s.set_workers_error(workers_error);
  for (const std::string& r : reports) s.add_reports(r);
  return Json(s);
}

std::string DashboardCurveJson(const std::string& job_id,
                               const std::vector<GenerationRecord>& records) {
  pw::DashboardCurve c;
  c.set_job_id(job_id);
  for (const GenerationRecord& r : records) ToProto(r, c.add_records());
  return Json(c);
}

}  // namespace pz::service
