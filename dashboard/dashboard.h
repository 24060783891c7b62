// `piezoid dashboard`: a read-only web page of a master's jobs, their fitness curves (best and
// median cost per generation), its workers and their failures, and the jobs' reports. It is a
// client of the master like the others (List, Workers and Fetch with log_only, over ZeroMQ, CURVE
// if configured); an embedded HTTP server (cpp-httplib) serves the page, its scripts (Debian's
// Chart.js and marked, embedded at build time: nothing is fetched at run time) and the JSON it
// polls (proto/dashboard.proto through protobuf's JSON printer).
//
//   GET /                           the page
//   GET /static/{dashboard.js,chart.min.js,marked.min.js}
//   GET /api/state                  DashboardState: master, jobs, workers, departures, reports
//   GET /api/curve?job=ID&from=G    DashboardCurve: the job's generation records from G on
//   GET /jobs/ID/report/            an ended job's report (piezoid fetch's, built on first request)
//   GET /reports/NAME/              a local report folder (--reports DIR/NAME with a report.md)
//
// Bound to 127.0.0.1 unless told otherwise. With a token every request needs it (?token=T, or the
// header "Authorization: Bearer T"); a token is required when the dashboard listens beyond loopback
// or talks to a CURVE master.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "model/status.h"
#include "svcclient/service_client.h"

namespace pz::dashboard {

struct DashboardOptions {
  std::string host = "127.0.0.1";     ///< address to listen on
  int port = 0;                       ///< 0: any free port (see Dashboard::url())
  std::string token;                  ///< access token; empty: none (loopback, plain master only)
  int poll_ms = 1000;                 ///< how often the master is polled [ms], ≥ 100
  std::filesystem::path reports_dir;  ///< optional: folders with a report.md, served read-only
  std::filesystem::path cache_dir;    ///< where job reports are built; empty: a temporary folder
  bool plots = true;                  ///< job reports with figures (gnuplot)
  svcclient::ServiceClientOptions client;  ///< the master's client endpoint (and CURVE keys)
};

class Dashboard {
 public:
  explicit Dashboard(DashboardOptions options);
  ~Dashboard();
  Dashboard(const Dashboard&) = delete;
  Dashboard& operator=(const Dashboard&) = delete;

  /// Checks the options (the error names the option), binds the HTTP port, starts polling.
  Status Start();
  /// "http://HOST:PORT/" once started.
  std::string url() const;
  /// Blocks until Stop() (from another thread or a signal handler's thread).
  void Wait();
  void Stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pz::dashboard
