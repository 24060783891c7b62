#include "svcclient/job_file.h"

#include <fstream>
#include <sstream>

#include "io/bench_data.h"
#include "hgann/hgann_job.h"
#include "service/wire_codec.h"

namespace pz::svcclient {
namespace fs = std::filesystem;

Status ResolveCaseSetDir(job::JobSpec* spec, const fs::path& base_dir,
                         std::vector<job::FieldViolation>* violations) {
  auto* h = std::get_if<job::HgannProblem>(&spec->problem);
  if (!h || h->case_set_dir.empty()) return Status::Ok();
  auto fail = [&](const std::string& rule) {
    const std::string d = FieldError("hgann.case_set_dir", "\"" + h->case_set_dir + "\"", rule);
    if (violations) violations->push_back({"hgann.case_set_dir", d});
    return InvalidArgument(d);
  };
  if (!h->cases.empty()) return fail("cannot be combined with hgann.cases (give one or the other)");
  const fs::path dir = (fs::path(h->case_set_dir).is_absolute() ? fs::path(h->case_set_dir)
                                                                : base_dir / h->case_set_dir)
                           .lexically_normal();
  io::CaseSet set;
  try {
    set = io::LoadCaseSet(dir);
  } catch (const InputError& e) {
    return fail(std::string("cannot be read: ") + e.what());
  }
  job::HgannProblem loaded = hgann::HgannProblemFromCaseSet(set);
  h->cases = std::move(loaded.cases);
  if (h->source.empty()) {
    std::error_code ec;
    const fs::path rel = fs::relative(dir, fs::current_path(ec), ec);
    const std::string r = rel.string();
    h->source = !ec && !r.empty() && r.rfind("..", 0) != 0 ? r : dir.string();
  }
  h->case_set_dir.clear();
  return Status::Ok();
}

Status JobSpecFromJsonFile(const std::string& json, const fs::path& base_dir, job::JobSpec* spec,
                           std::vector<job::FieldViolation>* violations) {
  std::vector<job::FieldViolation> decode;
  if (Status s = service::JobSpecFromJson(json, spec, &decode); !s.ok()) return s;
  if (!decode.empty()) {
    std::string all;
    for (const auto& v : decode) all += (all.empty() ? "" : "; ") + v.description;
    if (violations) violations->insert(violations->end(), decode.begin(), decode.end());
    return InvalidArgument(all);
  }
  return ResolveCaseSetDir(spec, base_dir, violations);
}

Status LoadJobSpecFile(const fs::path& file, job::JobSpec* spec,
                       std::vector<job::FieldViolation>* violations) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return InvalidArgument(file.string() + ": cannot read the job spec");
  std::stringstream ss;
  ss << in.rdbuf();
  Status s = JobSpecFromJsonFile(ss.str(), file.parent_path(), spec, violations);
  if (!s.ok()) return {s.code(), file.string() + ": " + s.message()};
  return s;
}

}  // namespace pz::svcclient
