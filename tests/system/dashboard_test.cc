// `piezoid dashboard` in a real headless Chromium (Debian's `chromium`): a master, two workers and
// a running job; the page is loaded twice a few seconds apart and its fitness curve and worker
// table must have moved on (the page writes what it drew into data-* attributes of <body>, read
// from Chromium's --dump-dom). Also: an ended hgann job's report through the dashboard, a local
// report folder, the access token (401 without it, 200 with ?token= or a Bearer header), the
// refusals of a dashboard beyond loopback without a token, and bad requests answered with what was
// wrong. With PIEZOID_SCREENSHOT_DIR set, the test leaves screenshots of the page and the report
// there (docs/dashboard*.png are made so).
#include <cstdlib>
#include <regex>

#include "svcclient/job_file.h"
#include "tests/system/service_harness.h"

// Last: <resolv.h>, which httplib.h includes, defines a macro `_res` that Eigen's headers use as a
// name.
#include <httplib.h>

namespace pz::testing {
namespace {

const fs::path kExamples = fs::path(PIEZOID_DATA_DIR) / ".." / "examples";

std::string Chromium() {
  for (const char* c : {"chromium", "chromium-browser"}) {
    const std::string probe = std::string("command -v ") + c + " >/dev/null 2>&1";
    if (std::system(probe.c_str()) == 0) return c;
  }
  return {};
}

/// Runs headless Chromium on `url` for `budget_ms` of virtual time; its --dump-dom output, or a
/// screenshot into `screenshot` when given.
std::string Browse(const fs::path& dir, const std::string& url, int budget_ms,
                   const fs::path& screenshot = {}) {
  static int n = 0;
  const fs::path profile = dir / ("chromium-profile-" + std::to_string(++n));
  const fs::path out = dir / ("dom-" + std::to_string(n) + ".html");
  std::string cmd = Chromium() +
                    " --headless=new --no-sandbox --disable-gpu --no-first-run --hide-scrollbars"
                    " --user-data-dir='" +
                    profile.string() +
                    "' --window-size=1400,1000 --virtual-time-budget=" + std::to_string(budget_ms);
  cmd += screenshot.empty() ? " --dump-dom" : " --screenshot='" + screenshot.string() + "'";
  cmd += " '" + url + "' >'" + out.string() + "' 2>'" + (dir / "chromium.log").string() + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream f(out);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// data-NAME="value" of the dumped <body>, or -1.
long long BodyNumber(const std::string& dom, const std::string& name) {
  std::smatch m;
  if (std::regex_search(dom, m, std::regex("data-" + name + "=\"(-?[0-9]+)\"")))
    return std::stoll(m[1]);
  return -1;
}

class Dashboard {
 public:
  Dashboard(Cluster& c, std::vector<std::string> extra, const std::string& name = "dashboard") {
    url_file_ = c.dir() / (name + ".url");
    std::vector<std::string> args = {"dashboard",        "--master",    c.client_endpoint(),
                                     "--listen",         "127.0.0.1:0", "--url-file",
                                     url_file_.string(), "--poll-ms",   "300"};
    args.insert(args.end(), extra.begin(), extra.end());
    process_ = std::make_unique<Process>(BuildDir() / "client" / "piezoid", args,
                                         c.dir() / (name + ".log"));
    for (int i = 0; i < 1000 && url_.empty(); ++i) {
      std::ifstream f(url_file_);
      std::getline(f, url_);
      if (url_.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  const std::string& url() const { return url_; }
  /// host:port for httplib::Client.
  std::string host_port() const { return url_.substr(7, url_.size() - 8); }

 private:
  fs::path url_file_;
  std::string url_;
  std::unique_ptr<Process> process_;
};

bool WaitGeneration(svcclient::ServiceClient& c, const std::string& job, uint64_t generation,
                    bool final = false) {
  for (int i = 0; i < 1200; ++i) {
    service::JobInfo info;
    if (c.GetStatus(job, &info).ok() &&
        (final ? service::IsFinal(info.state)
               : info.generation >= generation || service::IsFinal(info.state)))
      return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

TEST(Dashboard, TheCurveAndTheWorkerTableUpdateInARealBrowser) {
  if (Chromium().empty()) GTEST_SKIP() << "chromium is not installed (scripts/deps.sh installs it)";
  Cluster cluster("dashboard");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  svcclient::ServiceClient c = cluster.Client();
  // A job that runs for a while: 20 new individuals a generation, 3 ms each, 2 workers.
  job::JobSpec spec;
  std::vector<job::FieldViolation> v;
  ASSERT_TRUE(svcclient::LoadJobSpecFile(kExamples / "synthetic_job.json", &spec, &v).ok());
  std::get<job::SyntheticProblem>(spec.problem).sleep_ms = 3;
  spec.ga->generations = 5000;
  svcclient::SubmitResult job;
  ASSERT_TRUE(c.Submit(spec, &job).ok());
  ASSERT_TRUE(WaitGeneration(c, job.job_id, 5));

  Dashboard d(cluster, {});
  ASSERT_FALSE(d.url().empty()) << "the dashboard did not write its URL; see " << cluster.dir();
  const std::string first = Browse(cluster.dir(), d.url(), 2500);
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const std::string second = Browse(cluster.dir(), d.url(), 2500);
  if (const char* shots = std::getenv("PIEZOID_SCREENSHOT_DIR"))
    Browse(cluster.dir(), d.url(), 2500, fs::path(shots) / "dashboard.png");

  for (const std::string* dom : {&first, &second}) {
    EXPECT_GE(BodyNumber(*dom, "polls"), 2) << "the page did not poll repeatedly:\n"
                                            << dom->substr(0, 2000);
    EXPECT_EQ(BodyNumber(*dom, "workers"), 2);
    EXPECT_EQ(BodyNumber(*dom, "worker-threads"), 2);
    EXPECT_NE(dom->find("data-curve-job=\"" + job.job_id + "\""), std::string::npos);
    EXPECT_NE(dom->find("data-job=\"" + job.job_id + "\""), std::string::npos) << "no job row";
    EXPECT_NE(dom->find(">running<"), std::string::npos);
  }
  // Between the two loads the job went on: more points on the curve, more tasks done by the
  // workers.
  EXPECT_GT(BodyNumber(first, "curve-points"), 5);
  EXPECT_GT(BodyNumber(second, "curve-points"), BodyNumber(first, "curve-points"));
  EXPECT_GT(BodyNumber(second, "curve-last-generation"),
            BodyNumber(first, "curve-last-generation"));
  EXPECT_GT(BodyNumber(second, "worker-tasks-done"), BodyNumber(first, "worker-tasks-done"));

  // The JSON the page reads: the median next to the best, never a penalty-dominated mean only.
  httplib::Client http(d.host_port());
  // A report is written on its first request (piezoid fetch's): on a loaded 2-core machine that
  // took longer than cpp-httplib's 5 s default read timeout.
  http.set_read_timeout(60, 0);
  auto curve = http.Get("/api/curve?job=" + job.job_id + "&from=2");
  ASSERT_TRUE(curve);
  EXPECT_EQ(curve->status, 200);
  EXPECT_NE(curve->body.find("\"median_cost\""), std::string::npos);
  EXPECT_EQ(curve->body.find("\"generation\":\"0\""), std::string::npos)
      << "from=2 must skip generations 0, 1";
  // Bad requests say what was wrong.
  auto bad = http.Get("/api/curve?job=" + job.job_id + "&from=x");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_NE(bad->body.find("from = 'x'"), std::string::npos) << bad->body;
  auto unknown = http.Get("/api/curve?job=j0000000000000000");
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->status, 404);
  auto running = http.Get("/jobs/" + job.job_id + "/report/");
  ASSERT_TRUE(running);
  EXPECT_EQ(running->status, 409);
  EXPECT_NE(running->body.find("still running"), std::string::npos);
  auto escape = http.Get("/reports/x/../../etc/passwd");
  ASSERT_TRUE(escape);
  EXPECT_EQ(escape->status, 404);
  auto post = http.Post("/api/state", "", "text/plain");
  ASSERT_TRUE(post);
  EXPECT_NE(post->status, 200) << "read-only: no POST";

  // An ended hgann job: its report (piezoid fetch's) through the dashboard; then a local report
  // folder.
  ASSERT_TRUE(c.Cancel(job.job_id).ok());
  job::JobSpec quick;
  ASSERT_TRUE(svcclient::LoadJobSpecFile(kExamples / "hgann_quick.json", &quick, &v).ok());
  svcclient::SubmitResult hg;
  ASSERT_TRUE(c.Submit(quick, &hg).ok());
  ASSERT_TRUE(WaitGeneration(c, hg.job_id, 0, /*final=*/true));
  auto report = http.Get("/jobs/" + hg.job_id + "/report/report.md");
  ASSERT_TRUE(report);
  ASSERT_EQ(report->status, 200) << report->body;
  EXPECT_NE(report->body.find("# HGANN identification"), std::string::npos);
  auto files = http.Get("/jobs/" + hg.job_id + "/report/files.json");
  ASSERT_TRUE(files);
  EXPECT_NE(files->body.find("\"network.pb\""), std::string::npos) << files->body;
  const std::string report_page =
      Browse(cluster.dir(), d.url() + "jobs/" + hg.job_id + "/report/", 3000);
  EXPECT_NE(report_page.find("data-rendered=\"yes\""), std::string::npos)
      << "report.md was not rendered";
  EXPECT_NE(report_page.find("<h1"), std::string::npos);

  if (const char* shots = std::getenv("PIEZOID_SCREENSHOT_DIR"))
    Browse(cluster.dir(), d.url() + "jobs/" + hg.job_id + "/report/", 3000,
           fs::path(shots) / "dashboard-report.png");
}

TEST(Dashboard, TokenReportsAndRefusals) {
  Cluster cluster("dashboard-token");
  const fs::path token = cluster.dir() / "token";
  std::ofstream(token) << "0123456789abcdef0123\n";
  const fs::path reports = cluster.dir() / "reports";
  fs::create_directories(reports / "stack-fit" / "figures");
  std::ofstream(reports / "stack-fit" / "report.md")
      << "# fit of a stack\n\n![loop](figures/loop.svg)\n";
  std::ofstream(reports / "stack-fit" / "figures" / "loop.svg")
      << "<svg xmlns='http://www.w3.org/2000/svg'/>";
  fs::create_directories(reports / "not-a-report");  // no report.md: not listed

  Dashboard d(cluster, {"--token-file", token.string(), "--reports", reports.string()}, "guarded");
  ASSERT_FALSE(d.url().empty()) << "see " << cluster.dir();
  httplib::Client http(d.host_port());
  auto denied = http.Get("/api/state");
  ASSERT_TRUE(denied);
  EXPECT_EQ(denied->status, 401);
  EXPECT_NE(denied->body.find("?token="), std::string::npos) << denied->body;
  EXPECT_EQ(http.Get("/api/state?token=wrong-token-0000000")->status, 401);
  std::string state;
  for (int i = 0; i < 100; ++i) {  // the first poll may still be under way
    auto ok = http.Get("/api/state?token=0123456789abcdef0123");
    ASSERT_TRUE(ok);
    if (ok->status == 200) {
      state = ok->body;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_NE(state.find("\"reports\":[\"stack-fit\"]"), std::string::npos) << state;
  httplib::Headers bearer = {{"Authorization", "Bearer 0123456789abcdef0123"}};
  auto fig = http.Get("/reports/stack-fit/figures/loop.svg", bearer);
  ASSERT_TRUE(fig);
  EXPECT_EQ(fig->status, 200);
  EXPECT_EQ(fig->get_header_value("Content-Type"), "image/svg+xml");
  EXPECT_EQ(http.Get("/reports/not-a-report/", bearer)->status, 404);
  EXPECT_EQ(http.Get("/reports/stack-fit/missing.md", bearer)->status, 404);

  // Refusals: beyond loopback without a token, a short token, a bad --listen.
  std::string out, err;
  EXPECT_EQ(RunCli({"dashboard", "--master", cluster.client_endpoint(), "--listen", "0.0.0.0:0"},
                   &out, &err),
            2);
  EXPECT_NE(err.find("--listen 0.0.0.0: beyond loopback the dashboard needs an access token"),
            std::string::npos)
      << err;
  const fs::path short_token = cluster.dir() / "short";
  std::ofstream(short_token) << "abc\n";
  EXPECT_EQ(RunCli({"dashboard", "--listen", "127.0.0.1:0", "--token-file", short_token.string()},
                   &out, &err),
            2);
  EXPECT_NE(err.find("--token-file: the token has 3 characters"), std::string::npos) << err;
  EXPECT_EQ(RunCli({"dashboard", "--listen", "127.0.0.1:http"}, &out, &err), 2);
  EXPECT_NE(err.find("--listen '127.0.0.1:http': the port must be a number"), std::string::npos)
      << err;
  // A CURVE master: the dashboard needs its own token too.
  const fs::path keys = cluster.dir() / "keys";
  ASSERT_EQ(RunCli({"keygen", "--out", keys.string(), "--name", "viewer"}, &out, &err), 0) << err;
  ASSERT_EQ(RunCli({"keygen", "--out", keys.string(), "--name", "master"}, &out, &err), 0) << err;
  EXPECT_EQ(
      RunCli({"dashboard", "--listen", "127.0.0.1:0", "--curve-secret",
              (keys / "viewer.key").string(), "--master-public", (keys / "master.pub").string()},
             &out, &err),
      2);
  EXPECT_NE(err.find("the master uses CURVE: the dashboard needs its own access token"),
            std::string::npos)
      << err;
}

}  // namespace
}  // namespace pz::testing
