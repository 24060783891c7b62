#include "dashboard/dashboard.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "dashboard/dashboard_assets.h"
#include "reports/job_report.h"
#include "service/wire_codec.h"

// Last: <resolv.h>, which httplib.h includes, defines a macro `_res` that Eigen's headers use as a
// name.
#include "dashboard/http_guard.h"

namespace pz::dashboard {
namespace fs = std::filesystem;

namespace {

double UnixNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

bool IsLoopback(const std::string& host) {
  return host == "127.0.0.1" || host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

/// Equal strings in a time that does not depend on where they differ.
bool SameSecret(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < a.size(); ++i)
    diff |= static_cast<unsigned char>(a[i] ^ b[i % std::max<size_t>(1, b.size())]);
  return diff == 0;
}

std::string MimeOf(const fs::path& p) {
  const std::string e = p.extension().string();
  if (e == ".html") return "text/html; charset=utf-8";
  if (e == ".svg") return "image/svg+xml";
  if (e == ".png") return "image/png";
  if (e == ".json") return "application/json";
  if (e == ".js") return "text/javascript; charset=utf-8";
  if (e == ".css") return "text/css; charset=utf-8";
  if (e == ".pb" || e == ".bin") return "application/octet-stream";
  return "text/plain; charset=utf-8";  // .md, .csv, .h, .txt, .log …
}

/// `rel` inside `base` (no "..", no absolute path, an existing regular file), or empty.
fs::path SafeFile(const fs::path& base, const std::string& rel) {
  if (rel.empty() || rel.front() == '/' || rel.find('\0') != std::string::npos) return {};
  const fs::path r(rel);
  for (const fs::path& part : r)
    if (part == ".." || part == ".") return {};
  std::error_code ec;
  const fs::path full = fs::weakly_canonical(base / r, ec);
  const fs::path root = fs::weakly_canonical(base, ec);
  if (ec) return {};
  const std::string f = full.string(), b = root.string() + "/";
  if (f.compare(0, b.size(), b) != 0 || !fs::is_regular_file(full, ec)) return {};
  return full;
}

/// The files of a folder, relative, sorted (JSON array of strings).
std::string FilesJson(const fs::path& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
    if (it->is_regular_file() && it->path().filename() != ".complete")
      files.push_back(fs::relative(it->path(), dir).string());
  std::sort(files.begin(), files.end());
  std::string out = "[";
  for (size_t i = 0; i < files.size(); ++i) {
    out += i ? ",\"" : "\"";
    for (char c : files[i]) {
      if (c == '"' || c == '\\') out += '\\';
      if (static_cast<unsigned char>(c) >= 0x20) out += c;
    }
    out += '"';
  }
  return out + "]";
}

void Text(httplib::Response& res, int status, const std::string& text) {
  res.status = status;
  res.set_content(text + "\n", "text/plain; charset=utf-8");
}

}  // namespace

struct Dashboard::Impl {
  explicit Impl(DashboardOptions o) : options(std::move(o)) {}

  DashboardOptions options;
  GuardedServer server;  // a slow or half-open client cannot stall the others
  int port = 0;
  std::thread http_thread, poll_thread;
  std::atomic<bool> stop{false};
  std::mutex stop_mu;
  std::condition_variable stop_cv;
  fs::path cache_dir;
  bool own_cache = false;

  // Under mu: what the poller found.
  std::mutex mu;
  std::string state_json;
  std::map<std::string, std::vector<service::GenerationRecord>> logs;  // job → records, in order
  std::map<std::string, service::JobInfo> infos;
  uint64_t polls = 0;

  // On-demand requests of the HTTP threads (curves of jobs not polled, reports): one client.
  std::mutex request_mu;
  std::unique_ptr<svcclient::ServiceClient> request_client;
  std::mutex report_mu;  // one report built at a time

  std::vector<std::string> Reports() const {
    std::vector<std::string> names;
    if (options.reports_dir.empty()) return names;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(options.reports_dir, ec))
      if (e.is_directory() && fs::exists(e.path() / "report.md"))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

  // ------------------------------------------------------------------ polling
  void PollOnce(svcclient::ServiceClient& client, double* polled_at, std::string* error) {
    std::vector<service::JobInfo> jobs;
    Status s = client.List(&jobs);
    service::WorkersSnapshot snapshot;
    std::string workers_error;
    if (s.ok()) {
      if (Status w = client.Workers(&snapshot); !w.ok()) workers_error = w.message();
      *error = "";
      *polled_at = UnixNow();
      // Running jobs first (longest running first), then the ended ones, most recent first.
      std::stable_sort(
          jobs.begin(), jobs.end(), [](const service::JobInfo& a, const service::JobInfo& b) {
            const bool ra = !service::IsFinal(a.state), rb = !service::IsFinal(b.state);
            if (ra != rb) return ra;
            if (ra) return a.elapsed_s > b.elapsed_s;
            return a.ended_unix_s > b.ended_unix_s;
          });
      for (const service::JobInfo& j : jobs) {
        if (j.archived) continue;
        uint64_t from = 0;
        bool complete = false;
        {
          std::lock_guard lock(mu);
          const auto& log = logs[j.job_id];
          if (!log.empty()) from = log.back().generation + 1;
          auto it = infos.find(j.job_id);
          // Caught up: a GA job's last record is generation `generation − 1` (generation counts
          // generation 0 too), a session's batch `generation`; nothing new unless the state moved.
          complete = !log.empty() && from >= j.generation && it != infos.end() &&
                     it->second.state == j.state;
        }
        if (complete) continue;
        std::vector<service::GenerationRecord> more;
        if (!client.FetchLog(j.job_id, from, nullptr, &more).ok())
          continue;  // e.g. pruned meanwhile
        std::lock_guard lock(mu);
        auto& log = logs[j.job_id];
        for (auto& r : more)
          if (log.empty() || r.generation > log.back().generation) log.push_back(std::move(r));
      }
    } else {
      *error = s.message();
    }
    const std::vector<std::string> reports = Reports();  // the disk is read outside the lock
    std::lock_guard lock(mu);
    if (s.ok()) {
      infos.clear();
      for (const auto& j : jobs) infos[j.job_id] = j;
      for (auto it = logs.begin();
           it != logs.end();)  // jobs pruned from the master: forget their curves
        it = infos.count(it->first) ? std::next(it) : logs.erase(it);
      ++polls;
    }
    std::vector<service::JobInfo> shown = jobs;
    if (!s.ok())  // keep showing what was last known
      for (const auto& [id, j] : infos) shown.push_back(j);
    state_json = service::DashboardStateJson(options.client.endpoint, *polled_at, polls, *error,
                                             shown, snapshot, workers_error, reports);
  }

  void PollLoop() {
    svcclient::ServiceClient client(options.client);
    double polled_at = 0;
    std::string error;
    while (!stop.load()) {
      PollOnce(client, &polled_at, &error);
      std::unique_lock lock(stop_mu);
      stop_cv.wait_for(lock, std::chrono::milliseconds(options.poll_ms),
                       [this] { return stop.load(); });
    }
  }

  // ------------------------------------------------------------------ HTTP
  bool Authorised(const httplib::Request& req) const {
    if (options.token.empty()) return true;
    if (req.has_param("token") && SameSecret(req.get_param_value("token"), options.token))
      return true;
    const std::string auth = req.get_header_value("Authorization");
    return auth.rfind("Bearer ", 0) == 0 && SameSecret(auth.substr(7), options.token);
  }

  void Curve(const httplib::Request& req, httplib::Response& res) {
    const std::string job = req.get_param_value("job");
    if (job.empty()) return Text(res, 400, "job: missing (api/curve?job=ID&from=GENERATION)");
    uint64_t from = 0;
    if (req.has_param("from")) {
      const std::string f = req.get_param_value("from");
      char* end = nullptr;
      errno = 0;
      const unsigned long long v = std::strtoull(f.c_str(), &end, 10);
      if (f.empty() || *end != '\0' || errno != 0 || f.front() == '-')
        return Text(res, 400, "from = '" + f + "': must be a generation number (0, 1, …)");
      from = v;
    }
    std::vector<service::GenerationRecord> records;
    bool known;
    {
      std::lock_guard lock(mu);
      auto it = logs.find(job);
      known = it != logs.end() && !it->second.empty();
      if (known)
        for (const auto& r : it->second)
          if (r.generation >= from) records.push_back(r);
    }
    if (!known) {  // not polled (archived, or new): ask the master
      std::lock_guard lock(request_mu);
      Status s = request_client->FetchLog(job, from, nullptr, &records);
      if (s.code() == StatusCode::kNotFound)
        return Text(res, 404, "job " + job + ": " + s.message());
      if (!s.ok()) return Text(res, 503, "the master did not answer: " + s.message());
    }
    res.set_content(service::DashboardCurveJson(job, records), "application/json");
  }

  /// Builds an ended job's report (once) into cache_dir/ID; the folder, or an error response.
  std::optional<fs::path> JobReport(const std::string& job, httplib::Response& res) {
    if (job.empty() || job.size() > 64 ||
        job.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_-") != std::string::npos) {
      Text(res, 400, "job id '" + job + "': not a job id");
      return std::nullopt;
    }
    const fs::path dir = cache_dir / job;
    std::lock_guard lock(report_mu);
    if (fs::exists(dir / ".complete")) return dir;
    reports::FetchedJob fetched;
    Status s;
    {
      std::lock_guard rl(request_mu);
      s = request_client->Fetch(job, 5, &fetched.best, &fetched.log, &fetched.info, &fetched.spec,
                                &fetched.networks, &fetched.committee);
    }
    if (s.code() == StatusCode::kNotFound) {
      Text(res, 404, "job " + job + ": " + s.message());
      return std::nullopt;
    }
    if (!s.ok()) {
      Text(res, 503, "the master did not answer: " + s.message());
      return std::nullopt;
    }
    if (!service::IsFinal(fetched.info.state)) {
      Text(res, 409,
           "job " + job + " is still running (generation " +
               std::to_string(fetched.info.generation) +
               "): its report is built when it has ended; `piezoid fetch " + job +
               "` gives the best so far");
      return std::nullopt;
    }
    std::error_code ec;
    fs::remove_all(dir, ec);
    fs::create_directories(dir, ec);
    std::ostringstream terminal;
    reports::FetchOutput out;
    s = reports::WriteFetchedJob(fetched, dir, options.plots, terminal, &out);
    if (!s.ok()) {
      Text(res, 500, "the report of job " + job + " could not be written: " + s.message());
      return std::nullopt;
    }
    std::ofstream(dir / "fetch.log") << terminal.str();
    std::ofstream(dir / ".complete") << "";
    return dir;
  }

  /// A report folder's files; its index is the report page (report.md rendered), whose links to the
  /// dashboard go up `root` ("../../" from /reports/NAME/).
  void ServeFolder(const fs::path& dir, const std::string& rel, const std::string& root,
                   httplib::Response& res) {
    if (rel.empty() || rel == "index.html") {
      std::string page(assets::kReportHtml);
      for (size_t at; (at = page.find("@ROOT@")) != std::string::npos;) page.replace(at, 6, root);
      return res.set_content(page, "text/html; charset=utf-8");
    }
    if (rel == "files.json") return res.set_content(FilesJson(dir), "application/json");
    const fs::path file = SafeFile(dir, rel);
    if (file.empty() || file.filename() == ".complete")
      return Text(res, 404, "no file '" + rel + "' in this report");
    std::ifstream in(file, std::ios::binary);
    std::ostringstream data;
    data << in.rdbuf();
    res.set_content(data.str(), MimeOf(file));
  }

  void Routes() {
    server.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      res.set_header("X-Content-Type-Options", "nosniff");
      res.set_header("Cache-Control", "no-store");
      res.set_header("Content-Security-Policy",
                     "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; "
                     "script-src 'self' 'unsafe-inline'; frame-ancestors 'none'");
      if (Authorised(req)) return httplib::Server::HandlerResponse::Unhandled;
      Text(res, 401,
           "this dashboard needs its access token: open it as http://HOST:PORT/?token=TOKEN (the "
           "token of "
           "`piezoid dashboard --token-file`), or send 'Authorization: Bearer TOKEN'");
      return httplib::Server::HandlerResponse::Handled;
    });
    struct Asset {
      const char* path;
      std::string_view body;
      const char* type;
    };
    for (const Asset& a :
         {Asset{"/", assets::kIndexHtml, "text/html; charset=utf-8"},
          Asset{"/static/dashboard.js", assets::kDashboardJs, "text/javascript; charset=utf-8"},
          Asset{"/static/chart.min.js", assets::kChartJs, "text/javascript; charset=utf-8"},
          Asset{"/static/marked.min.js", assets::kMarkedJs, "text/javascript; charset=utf-8"}})
      server.Get(a.path, [a](const httplib::Request&, httplib::Response& res) {
        res.set_content(std::string(a.body), a.type);
      });
    server.Get("/api/state", [this](const httplib::Request&, httplib::Response& res) {
      std::string json;
      {
        std::lock_guard lock(mu);
        json = state_json;
      }
      if (json.empty())
        return Text(res, 503, "the dashboard has not polled the master yet; retry in a moment");
      res.set_content(json, "application/json");
    });
    server.Get("/api/curve",
               [this](const httplib::Request& req, httplib::Response& res) { Curve(req, res); });
    server.Get(R"(/jobs/([^/]+)/report/(.*))",
               [this](const httplib::Request& req, httplib::Response& res) {
                 if (auto dir = JobReport(req.matches[1], res))
                   ServeFolder(*dir, req.matches[2], "../../../", res);
               });
    server.Get(R"(/reports/([^/]+)/(.*))",
               [this](const httplib::Request& req, httplib::Response& res) {
                 const std::string name = req.matches[1];
                 const std::vector<std::string> names = Reports();
                 if (std::find(names.begin(), names.end(), name) == names.end())
                   return Text(res, 404, "no report folder '" + name + "' under --reports");
                 ServeFolder(options.reports_dir / name, req.matches[2], "../../", res);
               });
    server.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
      if (res.body.empty())
        Text(res, res.status,
             "HTTP " + std::to_string(res.status) + ": " + req.method + " " + req.path);
    });
  }
};

Dashboard::Dashboard(DashboardOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}

Dashboard::~Dashboard() {
  Stop();
  if (impl_->own_cache) {
    std::error_code ec;
    fs::remove_all(impl_->cache_dir, ec);
  }
}

Status Dashboard::Start() {
  DashboardOptions& o = impl_->options;
  if (o.poll_ms < 100 || o.poll_ms > 3600000)
    return InvalidArgument(FieldError("--poll-ms", o.poll_ms, "must be in [100, 3600000]"));
  if (o.port < 0 || o.port > 65535)
    return InvalidArgument(FieldError("--listen port", o.port, "must be in [0, 65535]"));
  if (!o.token.empty() && o.token.size() < 16)
    return InvalidArgument("--token-file: the token has " + std::to_string(o.token.size()) +
                           " characters; use at least 16 (e.g. `openssl rand -hex 16 > token`)");
  if (o.token.empty() && !IsLoopback(o.host))
    return InvalidArgument("--listen " + o.host +
                           ": beyond loopback the dashboard needs an access token "
                           "(--token-file FILE; e.g. `openssl rand -hex 16 > FILE`)");
  if (o.token.empty() && o.client.curve)
    return InvalidArgument(
        "the master uses CURVE: the dashboard needs its own access token too "
        "(--token-file FILE; e.g. `openssl rand -hex 16 > FILE`)");
  if (!o.reports_dir.empty() && !fs::is_directory(o.reports_dir))
    return InvalidArgument("--reports " + o.reports_dir.string() + ": not a folder");
  std::error_code ec;
  if (o.cache_dir.empty()) {
    impl_->cache_dir =
        fs::temp_directory_path(ec) / ("piezoid-dashboard-" + std::to_string(::getpid()));
    impl_->own_cache = true;
  } else {
    impl_->cache_dir = o.cache_dir;
  }
  fs::create_directories(impl_->cache_dir, ec);
  if (ec) return InvalidArgument("--cache " + impl_->cache_dir.string() + ": " + ec.message());
  impl_->request_client = std::make_unique<svcclient::ServiceClient>(o.client);
  impl_->Routes();
  impl_->port = impl_->server.Bind(o.host, o.port);
  if (impl_->port <= 0)
    return Status(StatusCode::kUnavailable,
                  "--listen " + o.host + ":" + std::to_string(o.port) +
                      ": cannot listen there (address in use, or not this machine's)");
  impl_->http_thread = std::thread([this] { impl_->server.listen_after_bind(); });
  impl_->poll_thread = std::thread([this] { impl_->PollLoop(); });
  return Status::Ok();
}

std::string Dashboard::url() const {
  const std::string& h = impl_->options.host;
  const std::string host = h.find(':') != std::string::npos ? "[" + h + "]" : h;
  return "http://" + host + ":" + std::to_string(impl_->port) + "/";
}

void Dashboard::Wait() {
  std::unique_lock lock(impl_->stop_mu);
  impl_->stop_cv.wait(lock, [this] { return impl_->stop.load(); });
}

void Dashboard::Stop() {
  {
    std::lock_guard lock(impl_->stop_mu);
    impl_->stop = true;
  }
  impl_->stop_cv.notify_all();
  impl_->server.Shutdown();
  if (impl_->http_thread.joinable()) impl_->http_thread.join();
  if (impl_->poll_thread.joinable()) impl_->poll_thread.join();
}

}  // namespace pz::dashboard
