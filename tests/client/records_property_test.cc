// Property test of the records commands (issue 37): random record sets that nobody here made, run
// through `piezoid fit`, `export FIT.json`, `compensate --replay` and `--reference` (in-process,
// the commands' own code: manifest → reader → fit → checks → fit.json → export / compensate) and
// the records diagnosis (`diagnose --records --quick` on every fourth set;
// diagnose::DiagnoseRecords with a tiny search and the report writers of `diagnose --records` on
// the others), for every family of records::FamilyNames() with random effects of
// records::EffectNames(). Each command must give a result (no NaN or infinity in what it prints or
// writes; diagnosis.json reads back through its codec) or a pz::InputError with a message: never a
// signal, another exception or a hang (a watchdog aborts a set that runs longer than
// PIEZOID_PROPERTY_CASE_SECONDS, default 120, naming it).
//
// The sets draw rests before, inside and after the scored windows; windows at the record's edges,
// one sample long, at the 20-sample minimum (shorter than a delay), past the record's end;
// withheld records longer and shorter than the training ones and driven beyond their range;
// constant (held) and clipped drive segments; clipped and quantised responses; sample rates from
// 40 Hz to 5 kHz in s or ms; offsets fit / rest / fixed; settling windows.
//
// The default run is a fixed seed and 128 sets (about 4 s of CPU). More:
//   PIEZOID_PROPERTY_CASES=500 PIEZOID_PROPERTY_SEED=7
//   build/tests/client/client_records_property_test
// A failure names the set's seed; PIEZOID_PROPERTY_VERBOSE=1 prints every set and what its fit
// gave; PIEZOID_PROPERTY_KEEP=1 keeps the sets' folders (the test's
// temporary folder is printed) to run the failing command by hand.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <numbers>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "client/commands.h"
#include "diagnose/diagnose.h"
#include "diagnosis.pb.h"
#include "io/diagnosis_json.h"
#include "io/records.h"
#include "records/excitation.h"
#include "records/families.h"
#include "records/model.h"
#include "records/registry.h"
#include "reports/record_windows.h"
#include "reports/diagnose_report.h"
#include "tests/testing/cli.h"

namespace pz::client {
namespace {

namespace fs = std::filesystem;

long EnvLong(const char* name, long fallback) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') return fallback;
  char* end = nullptr;
  const long x = std::strtol(v, &end, 10);
  return end != v && *end == '\0' && x > 0 ? x : fallback;
}

/// Draws of a fixed sequence on every platform (std's distributions are not).
class Draw {
 public:
  explicit Draw(uint64_t seed) : g_(seed) {}
  double U01() { return static_cast<double>(g_() >> 11) * 0x1.0p-53; }
  double U(double a, double b) { return a + (b - a) * U01(); }
  size_t I(size_t n) { return static_cast<size_t>(g_() % n); }  ///< in [0, n)
  bool P(double p) { return U01() < p; }
  double Normal() {
    return std::sqrt(-2 * std::log(1 - U01())) * std::cos(2 * std::numbers::pi * U01());
  }

 private:
  std::mt19937_64 g_;
};

std::string Num(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

struct DrawnRecord {
  std::string name, role, file;
  std::vector<double> t, u, y;
  std::string t_start, t_end, offset, frequency;
};

struct DrawnSet {
  uint64_t seed = 0;
  std::string family;
  std::vector<std::string> effects;
  double settle_s = 0;
  std::string time_column = "t_s";
  std::string description;  ///< what was drawn, for a failure's message
  std::vector<DrawnRecord> records;
};

/// A record: a rest at u0, then a sine / triangle / multisine / steps between lo and hi with an
/// optional hold and clip; the response a play (backlash) of the drive, a slow creep, noise,
/// optionally clipped and quantised.
DrawnRecord DrawRecord(Draw& d, std::ostringstream& desc, size_t n, size_t rest, double fs,
                       double lo, double hi, double u0, bool ms, double y_scale, bool hazard) {
  DrawnRecord r;
  const double dt = 1 / fs;
  const size_t body = n > rest ? n - rest : 0;
  const double cycles = d.U(0.5, 4);
  const int wave = static_cast<int>(d.I(4));
  const double phase = d.U(0, 2 * std::numbers::pi);
  desc << n << " samples, rest " << rest << ", wave " << wave;
  for (size_t k = 0; k < n; ++k) {
    double u = u0;
    if (k >= rest && body > 0) {
      const double x = 2 * std::numbers::pi * cycles * static_cast<double>(k - rest) /
                           static_cast<double>(body) +
                       phase;
      double s = 0;
      switch (wave) {
        case 0:
          s = std::sin(x);
          break;
        case 1:
          s = 2 / std::numbers::pi * std::asin(std::sin(x));
          break;
        case 2:
          s = 0.6 * std::sin(x) + 0.4 * std::sin(3.7 * x + 1);
          break;
        default:
          s = std::sin(x) >= 0 ? 1 : -1;
          break;
      }
      u = 0.5 * (lo + hi) + 0.5 * (hi - lo) * s;
    }
    r.u.push_back(u);
  }
  if (body > 4 && d.P(0.3)) {  // a hold: the drive constant over a stretch
    const size_t a = rest + d.I(body / 2), b = std::min(n, a + 1 + d.I(body / 2));
    for (size_t k = a; k < b; ++k) r.u[k] = r.u[a];
    desc << ", hold " << a << "-" << b;
  }
  if (d.P(0.25)) {  // a clipped drive: flat tops
    const double c = lo + d.U(0.5, 0.95) * (hi - lo);
    for (double& u : r.u) u = std::min(u, c);
    desc << ", drive clipped at " << c;
  }
  const double width = d.U(0.02, 0.2) * (hi - lo + 1e-9), gain = y_scale * (d.P(0.2) ? -1 : 1);
  const double noise = d.P(0.2) ? 0 : d.U(1e-4, 0.02) * std::abs(gain) * (hi - lo + 1);
  double play = r.u[0];
  for (size_t k = 0; k < n; ++k) {
    play = std::clamp(play, r.u[k] - width, r.u[k] + width);
    const double t = static_cast<double>(k) * dt;
    r.y.push_back(gain * play + 0.01 * std::abs(gain) * (hi - lo) * std::log1p(t) +
                  noise * d.Normal());
  }
  if (d.P(0.2)) {  // a sensor at its limit
    const auto [mn, mx] = std::minmax_element(r.y.begin(), r.y.end());
    const double c = *mn + d.U(0.6, 0.95) * (*mx - *mn);
    for (double& y : r.y) y = std::min(y, c);
    desc << ", response clipped";
  }
  if (d.P(0.03)) {  // a sensor that reads nothing
    std::fill(r.y.begin(), r.y.end(), r.y.front());
    desc << ", constant response";
  }
  if (d.P(0.2)) {  // a quantised sensor
    const double q = 0.01 * std::abs(gain) * (hi - lo + 1);
    for (double& y : r.y) y = q * std::round(y / q);
    desc << ", quantised";
  }
  const double t0 = d.P(0.3) ? d.U(-2, 5) : 0;  // the file's own time need not start at 0
  for (size_t k = 0; k < n; ++k) r.t.push_back((t0 + static_cast<double>(k) * dt) * (ms ? 1e3 : 1));
  // The window, in the file's own seconds: one the reader takes, or (`hazard`) one it refuses.
  auto at = [&](size_t k) { return Num(t0 + static_cast<double>(k) * dt); };
  const size_t kind = hazard ? 6 + d.I(2) : d.I(6);
  switch (kind) {
    case 0:
      break;  // the whole record
    case 1:   // starts inside the rest (the crash of issue 37)
      r.t_start = at(rest > 0 ? d.I(std::min(rest, n - 19)) : 0);
      desc << ", window from inside the rest";
      break;
    case 2:  // at the record's edges
      r.t_start = at(0);
      r.t_end = at(n - 1);
      desc << ", window at the edges";
      break;
    case 3: {  // the minimum: 20 samples, anywhere (shorter than a delay of the range)
      const size_t a = d.I(n - 19);
      r.t_start = at(a);
      r.t_end = at(a + 19);
      desc << ", 20-sample window from " << a;
      break;
    }
    case 4:  // after the rest, to the end, or only its end given
      if (d.P(0.5)) {
        r.t_start = at(std::min(n - 20, rest + d.I(10)));
      } else {
        r.t_end = at(std::max<size_t>(19, n - 1 - d.I(n / 2)));
      }
      desc << ", window after the rest";
      break;
    case 5: {  // anywhere, 20 samples or more
      const size_t a = d.I(n - 19), b = a + 19 + d.I(n - 19 - a);
      r.t_start = at(a);
      r.t_end = at(b);
      desc << ", window " << a << "-" << b;
      break;
    }
    case 6: {  // one sample or two (refused)
      const size_t a = d.I(n);
      r.t_start = at(a);
      r.t_end = at(std::min(n - 1, a + d.I(2)));
      desc << ", one-sample window (hazard)";
      break;
    }
    default:  // ends after the record (refused)
      r.t_end = Num(t0 + static_cast<double>(n + d.I(50)) * dt);
      desc << ", window past the end (hazard)";
      break;
  }
  const size_t off = d.I(6);  // 'rest' needs 10 samples of rest: refused with fewer (a hazard)
  r.offset = off == 0 && (rest >= 10 || hazard) ? "rest"
             : off == 1                         ? Num(d.U(-1, 1))
             : off == 2                         ? "fit"
                                                : "";
  if (d.P(0.3)) r.frequency = Num(cycles * fs / static_cast<double>(std::max<size_t>(body, 1)));
  desc << ", offset '" << r.offset << "'";
  return r;
}

DrawnSet DrawSet(uint64_t seed, size_t index) {
  Draw d(seed);
  DrawnSet s;
  s.seed = seed;
  const auto& families = records::FamilyNames();
  s.family = families[index % families.size()];
  const auto& effects = records::EffectNames();
  for (size_t e = d.I(3); e > 0; --e) {
    const std::string& name = effects[d.I(effects.size())];
    if (std::find(s.effects.begin(), s.effects.end(), name) == s.effects.end())
      s.effects.push_back(name);
  }
  static const double kRates[] = {40, 200, 500, 1000, 5000};
  const double fs = kRates[d.I(5)];
  const bool ms = d.P(0.3);
  if (ms) s.time_column = "t_ms";
  const double lo = d.P(0.5) ? 0 : d.U(-50, 10), hi = lo + (d.P(0.03) ? 0 : d.U(5, 120));
  const double y_scale = d.U(0.05, 2);
  if (d.P(0.1)) s.settle_s = d.U(0, 0.1);
  std::ostringstream desc;
  desc << "seed " << seed << ": " << s.family;
  for (const auto& e : s.effects) desc << " + " << e;
  desc << ", " << fs << " Hz" << (ms ? " (ms)" : "") << ", drive " << lo << " … " << hi;
  if (s.settle_s > 0) desc << ", settle " << s.settle_s << " s";
  const size_t train = 1 + d.I(2), withheld = d.I(3);
  // One set in five carries a record the reader refuses (a window of one sample or past the end,
  // offset 'rest' without a rest): the reader's errors, not the fit's, are its outcome.
  const size_t hazard = d.P(0.2) ? d.I(train + withheld) : train + withheld;
  const size_t n_train = 60 + d.I(340);
  for (size_t i = 0; i < train + withheld; ++i) {
    const bool is_train = i < train;
    // Withheld: shorter or longer than training, sometimes beyond its drive range.
    const size_t n = is_train ? n_train : d.P(0.5) ? 20 + d.I(60) : n_train + d.I(400);
    const double ext = !is_train && d.P(0.4) ? d.U(0.2, 1.0) * (hi - lo) : 0;
    const size_t rest = d.P(0.2)    ? 0
                        : d.P(0.15) ? n
                                    : d.I(std::max<size_t>(n / 2, 1));  // none, all, some
    desc << "\n  " << (is_train ? "train" : "withheld") << " " << i << ": ";
    if (ext > 0) desc << "beyond by " << ext << ", ";
    DrawnRecord r = DrawRecord(d, desc, n, rest, fs, lo - ext, hi + ext,
                               d.P(0.7) ? lo - ext : hi + ext, ms, y_scale, i == hazard);
    r.name = "r" + std::to_string(i);
    r.role = is_train ? "train" : d.P(0.5) ? "validate" : "test";
    r.file = r.name + ".csv";
    s.records.push_back(std::move(r));
  }
  s.description = desc.str();
  return s;
}

void WriteSet(const DrawnSet& s, const fs::path& dir) {
  fs::create_directories(dir);
  std::ofstream m(dir / "manifest.csv");
  m << "record,file,role,t_start_s,t_end_s,offset,frequency_Hz,time_column\n";
  for (const DrawnRecord& r : s.records) {
    m << r.name << "," << r.file << "," << r.role << "," << r.t_start << "," << r.t_end << ","
      << r.offset << "," << r.frequency << "," << s.time_column << "\n";
    std::ofstream f(dir / r.file);
    f << s.time_column << ",voltage_V,displacement_um\n";
    for (size_t k = 0; k < r.t.size(); ++k)
      f << Num(r.t[k]) << "," << Num(r.u[k]) << "," << Num(r.y[k]) << "\n";
  }
}

/// A reference for `compensate --reference`: a training record's response at the model's step.
void WriteReference(const DrawnSet& s, const fs::path& file) {
  const DrawnRecord& r = s.records.front();
  const double scale = s.time_column == "t_ms" ? 1e-3 : 1;
  std::ofstream f(file);
  f << "t_s,displacement_um\n";
  for (size_t k = 0; k < r.t.size(); ++k) f << Num(r.t[k] * scale) << "," << Num(r.y[k]) << "\n";
}

std::string ReadAll(const fs::path& file) {
  std::ifstream f(file, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// A "nan" or "inf" printed as a number (not inside a word).
bool HasNonFinite(const std::string& text) {
  static const std::regex kBad(
      "(^|[^A-Za-z_])[-+]?(nan|NaN|NAN|inf|Inf|INF|infinity|Infinity)([^A-Za-z_]|$)");
  return std::regex_search(text, kBad);
}

/// Aborts the process, naming the set, when one set runs too long (a hang).
class Watchdog {
 public:
  explicit Watchdog(std::chrono::seconds limit) : limit_(limit), thread_([this] { Loop(); }) {}
  ~Watchdog() {
    {
      std::lock_guard<std::mutex> l(mu_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  void Start(const std::string& what) {
    std::lock_guard<std::mutex> l(mu_);
    what_ = what;
    deadline_ = std::chrono::steady_clock::now() + limit_;
    ++generation_;
    cv_.notify_all();
  }

 private:
  void Loop() {
    std::unique_lock<std::mutex> l(mu_);
    while (!stop_) {
      const uint64_t g = generation_;
      if (g == 0) {
        cv_.wait(l);
        continue;
      }
      if (cv_.wait_until(l, deadline_, [&] { return stop_ || generation_ != g; })) continue;
      std::fprintf(stderr, "records_property_test: a set ran over %lld s (a hang): %s\n",
                   static_cast<long long>(limit_.count()), what_.c_str());
      std::abort();
    }
  }
  std::chrono::seconds limit_;
  std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false;
  uint64_t generation_ = 0;
  std::string what_;
  std::chrono::steady_clock::time_point deadline_;
  std::thread thread_;
};

/// One command's outcome: "" when it gave a result or a named error, else what went wrong.
struct Outcome {
  bool ok = false;      ///< the command finished with exit code 0
  std::string error;    ///< the InputError's message
  std::string failure;  ///< a broken property
  std::string out;      ///< what it printed
};

Outcome Run(const std::vector<std::string>& args) {
  Outcome o;
  ::testing::internal::CaptureStdout();
  try {
    const int code = testing::RunCommands(
        {RegisterFit, RegisterCompensate, RegisterExport, RegisterDiagnose}, args);
    o.ok = code == 0;
    if (!o.ok) o.failure = "exit code " + std::to_string(code) + " without an InputError";
  } catch (const InputError& e) {
    o.error = e.what();
    if (o.error.empty()) o.failure = "an InputError without a message";
  } catch (const std::exception& e) {
    o.failure = std::string("an exception that is not an InputError: ") + e.what();
  } catch (...) {
    o.failure = "an exception that is not a std::exception";
  }
  o.out = ::testing::internal::GetCapturedStdout();
  if (o.ok && HasNonFinite(o.out)) o.failure = "printed a NaN or infinity:\n" + o.out;
  return o;
}

std::string Joined(const std::vector<std::string>& args) {
  std::string s = "piezoid";
  for (const auto& a : args) s += " " + a;
  return s;
}

/// Counts of what the sets gave, printed at the end (a run whose every set is refused tests
/// little).
struct Tally {
  int sets = 0, fits = 0, fit_errors = 0, exports = 0, replays = 0, references = 0, diagnoses = 0,
      diagnose_errors = 0;
};

void Check(const DrawnSet& s, const fs::path& dir, bool cli_diagnose, Tally& tally) {
  const std::string what = s.description;
  const fs::path set_dir = dir / "set", out = dir / "fit";
  WriteSet(s, set_dir);
  std::vector<std::string> fit = {"fit",
                                  "--records",
                                  set_dir.string(),
                                  "--family",
                                  s.family,
                                  "--out",
                                  out.string(),
                                  "--algorithm",
                                  "pso",
                                  "--repetitions",
                                  "1",
                                  "--particles",
                                  "6",
                                  "--iterations",
                                  "4",
                                  "--lm-iterations",
                                  "4",
                                  "--threads",
                                  "1",
                                  "--no-figures",
                                  "--quiet",
                                  "--pi-operators",
                                  "4"};
  std::string effects;
  for (const auto& e : s.effects) effects += (effects.empty() ? "" : ",") + e;
  if (!effects.empty()) fit.insert(fit.end(), {"--effects", effects});
  if (s.settle_s > 0) fit.insert(fit.end(), {"--settle-s", Num(s.settle_s)});
  const Outcome f = Run(fit);
  ASSERT_EQ(f.failure, "") << Joined(fit) << "\n" << what;
  ++tally.sets;
  if (EnvLong("PIEZOID_PROPERTY_VERBOSE", 0) > 0)
    std::printf("%s\n  fit: %s\n", what.c_str(), f.ok ? "ok" : f.error.substr(0, 300).c_str());
  if (!f.ok) {
    ++tally.fit_errors;
    return;
  }
  ++tally.fits;
  for (const char* file : {"fit.json", "report.md"}) {
    const std::string text = ReadAll(out / file);
    ASSERT_FALSE(text.empty()) << file << "\n" << what;
    EXPECT_FALSE(HasNonFinite(text)) << file << " holds a NaN or infinity\n"
                                     << what << "\n"
                                     << text;
  }
  const std::string fit_json = (out / "fit.json").string();
  const std::vector<std::string> exp = {"export", fit_json, "--out", (out / "model.h").string()};
  const Outcome e = Run(exp);
  ASSERT_EQ(e.failure, "") << Joined(exp) << "\n" << what;
  if (e.ok) {
    ++tally.exports;
    EXPECT_FALSE(HasNonFinite(ReadAll(out / "model.h"))) << "model.h\n" << what;
  }
  std::vector<std::string> replay = {"compensate", "--model", fit_json, "--replay",
                                     set_dir.string()};
  const Outcome r = Run(replay);
  ASSERT_EQ(r.failure, "") << Joined(replay) << "\n" << what;
  tally.replays += r.ok;
  WriteReference(s, dir / "reference.csv");
  std::vector<std::string> ref = {"compensate",
                                  "--model",
                                  fit_json,
                                  "--reference",
                                  (dir / "reference.csv").string(),
                                  "--out",
                                  (dir / "drive.csv").string()};
  const Outcome c = Run(ref);
  ASSERT_EQ(c.failure, "") << Joined(ref) << "\n" << what;
  if (c.ok) {
    ++tally.references;
    EXPECT_FALSE(HasNonFinite(ReadAll(dir / "drive.csv"))) << "drive.csv\n" << what;
  }
  // The diagnosis: its command on some sets, its library with a tiny search and the command's
  // report writers on the others.
  const std::string candidate = records::EffectNames()[s.seed % records::EffectNames().size()];
  if (cli_diagnose) {
    std::vector<std::string> diag = {"diagnose",       "--records",
                                     set_dir.string(), "--family",
                                     s.family,         "--quick",
                                     "--candidates",   candidate,
                                     "--threads",      "1",
                                     "--no-plots",     "--quiet",
                                     "--out",          (dir / "diagnose").string()};
    if (s.settle_s > 0) diag.insert(diag.end(), {"--settle-s", Num(s.settle_s)});
    const Outcome g = Run(diag);
    ASSERT_EQ(g.failure, "") << Joined(diag) << "\n" << what;
    tally.diagnoses += g.ok;
    tally.diagnose_errors += !g.ok;
    if (g.ok) {
      EXPECT_FALSE(HasNonFinite(ReadAll(dir / "diagnose" / "report.md"))) << "report.md\n" << what;
    }
    return;
  }
  try {
    const io::RecordSet set =
        reports::LoadRecordSetWithWindows(set_dir.string(), {}, {}, {}, s.settle_s);
    diagnose::RecordDiagnoseOptions o;
    o.family = s.family;
    o.candidates = {records::ParseEffect(candidate)};
    o.fit.threads = 1;
    o.fit.uncertainty = false;
    o.fit.search.repetitions = 1;
    o.fit.search.pso.particles = 6;
    o.fit.search.pso.iterations = 4;
    o.fit.lm.max_iterations = 4;
    o.fit.family_options.pi_operators = 4;
    const diagnose::RecordDiagnosis dg = diagnose::DiagnoseRecords(set, o);
    const records::TrainingDriveProposal proposal =
        records::ProposeTrainingDrive(set, dg.excitation);
    std::ostringstream md, json;
    reports::WriteDiagnosisMarkdown(md, set, dg, proposal, {.settle_s = s.settle_s});
    reports::WriteDiagnosisJson(json, set, dg, proposal);
    EXPECT_FALSE(HasNonFinite(md.str())) << "diagnosis report\n" << what << "\n" << md.str();
    EXPECT_FALSE(HasNonFinite(json.str())) << "diagnosis.json\n" << what << "\n" << json.str();
    proto::Diagnosis back;  // reads back through its codec, to the same bytes
    EXPECT_NO_THROW(io::ReadDiagnosisFile("diagnosis.json", json.str(), &back)) << what;
    EXPECT_EQ(io::WriteDiagnosisFile(back), json.str()) << what;
    EXPECT_EQ(back.verdict(), dg.verdict) << what;
    ++tally.diagnoses;
  } catch (const InputError& x) {
    EXPECT_STRNE(x.what(), "") << what;
    ++tally.diagnose_errors;
  } catch (const std::exception& x) {
    ADD_FAILURE() << "the diagnosis threw an exception that is not an InputError: " << x.what()
                  << "\n"
                  << what;
  }
}

TEST(RecordsProperty, EveryFamilyGivesAResultOrANamedErrorOnRandomSets) {
  const long cases = EnvLong("PIEZOID_PROPERTY_CASES", 128);
  const uint64_t seed = static_cast<uint64_t>(EnvLong("PIEZOID_PROPERTY_SEED", 37));
  const bool keep = EnvLong("PIEZOID_PROPERTY_KEEP", 0) > 0;
  const fs::path root =
      fs::temp_directory_path() / ("pz_records_property_" + std::to_string(::getpid()));
  if (keep) std::printf("sets kept in %s\n", root.string().c_str());
  Watchdog watchdog(std::chrono::seconds(EnvLong("PIEZOID_PROPERTY_CASE_SECONDS", 120)));
  Tally tally;
  for (long i = 0; i < cases; ++i) {
    const uint64_t s = seed * 1000003 + static_cast<uint64_t>(i);
    const DrawnSet set = DrawSet(s, static_cast<size_t>(i));
    watchdog.Start(set.description);
    if (EnvLong("PIEZOID_PROPERTY_VERBOSE", 0) > 0)
      std::fprintf(stderr, "set %ld: %s\n", i, set.description.c_str());
    const fs::path dir = root / std::to_string(i);
    Check(set, dir, i % 4 == 3, tally);
    if (!keep) fs::remove_all(dir);
    if (::testing::Test::HasFatalFailure()) break;
  }
  if (!keep) fs::remove_all(root);
  std::printf(
      "%d sets: %d fitted (%d refused), %d exported, %d replayed, %d compensated, %d diagnosed (%d "
      "refused)\n",
      tally.sets, tally.fits, tally.fit_errors, tally.exports, tally.replays, tally.references,
      tally.diagnoses, tally.diagnose_errors);
  // A draw that gets every set refused would test the readers only.
  EXPECT_GT(tally.fits, 0);
}

}  // namespace
}  // namespace pz::client
