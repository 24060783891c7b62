#include "records/excitation.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <utility>

#include "model/status.h"
#include "opt/random.h"

namespace pz::records {
namespace {

using model::CaseRole;

std::string Num(double x, int prec = 3) {
  std::ostringstream s;
  s.precision(prec);
  s << x;
  return s.str();
}

/// Turning points of u[first, end): a retreat of more than `h` from the running extreme.
std::vector<double> Turns(const io::Record& r, double h) {
  std::vector<double> turns;
  if (r.scored() < 2) return turns;
  double ext = r.u[r.first_scored];
  int dir = 0;  // +1 rising, −1 falling, 0 not yet known
  double lo = ext, hi = ext;
  for (size_t k = r.first_scored + 1; k < r.end_scored; ++k) {
    const double u = r.u[k];
    if (dir == 0) {
      lo = std::min(lo, u);
      hi = std::max(hi, u);
      if (hi - lo > h) {
        dir = u >= hi ? 1 : -1;
        ext = dir > 0 ? hi : lo;
      }
    } else if (dir > 0) {
      if (u > ext)
        ext = u;
      else if (ext - u > h) {
        turns.push_back(ext);
        dir = -1;
        ext = u;
      }
    } else {
      if (u < ext)
        ext = u;
      else if (u - ext > h) {
        turns.push_back(ext);
        dir = 1;
        ext = u;
      }
    }
  }
  return turns;
}

/// Four-point rainflow: closed loops (weight 1), then the residue as half cycles.
std::vector<ReversalCycle> Rainflow(const std::vector<double>& turns) {
  std::vector<ReversalCycle> cycles;
  std::vector<double> s;
  for (double t : turns) {
    s.push_back(t);
    while (s.size() >= 4) {
      const size_t n = s.size();
      const double a = s[n - 4], b = s[n - 3], c = s[n - 2], d = s[n - 1];
      const double inner = std::abs(b - c);
      if (inner > std::abs(a - b) || inner > std::abs(c - d)) break;
      cycles.push_back({std::max(b, c), std::min(b, c), 1});
      s.erase(s.end() - 3, s.end() - 1);
    }
  }
  for (size_t i = 1; i < s.size(); ++i)
    cycles.push_back({std::max(s[i - 1], s[i]), std::min(s[i - 1], s[i]), 0.5});
  return cycles;
}

double Percentile95(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t k =
      std::min(v.size() - 1, static_cast<size_t>(0.95 * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

/// The bin of x ∈ [0, 1] among `bins`; clamped in double before the cast (x far outside [0, 1] on a
/// degenerate range, or NaN, goes to an end bin: the fuzzer's 4.9e121 overflowed an int).
int Bin(double x, int bins) {
  const double b = std::floor(x * bins);
  if (!(b > 0)) return 0;
  return b >= bins - 1 ? bins - 1 : static_cast<int>(b);
}

/// "10–40 %, 90–100 %" for the bins set in `on`.
std::string BinRanges(const std::vector<bool>& on) {
  const int n = static_cast<int>(on.size());
  std::string out;
  for (int i = 0; i < n;) {
    if (!on[static_cast<size_t>(i)]) {
      ++i;
      continue;
    }
    int j = i;
    while (j + 1 < n && on[static_cast<size_t>(j + 1)]) ++j;
    out += (out.empty() ? "" : ", ") + std::to_string(100 * i / n) + "–" +
           std::to_string(100 * (j + 1) / n) + " %";
    i = j + 1;
  }
  return out.empty() ? "none" : out;
}

/// The peak |du/dt| of each complete half cycle of the record's scored window with its duration
/// [s]: between two turns (a retreat of more than `threshold` from the running extreme); the
/// partial first and last are left out.
void HalfCyclePeakRates(const io::Record& r, double threshold,
                        std::vector<std::pair<double, double>>& peaks) {
  if (r.scored() < 2) return;
  double ext = r.u[r.first_scored], lo = ext, hi = ext, peak = 0;
  int dir = 0;           // +1 rising, −1 falling, 0 not yet known
  bool started = false;  // the half cycle in progress began at a turn (the first one did not)
  size_t begin = r.first_scored;
  for (size_t k = r.first_scored; k + 1 < r.end_scored; ++k) {
    const double v = r.u[k + 1], rate = std::abs(v - r.u[k]) / r.dt;
    if (dir == 0) {  // until the drive has moved by the threshold from its lowest or highest so far
      lo = std::min(lo, v);
      hi = std::max(hi, v);
      if (v - lo > threshold || hi - v > threshold) dir = v - lo > threshold ? 1 : -1;
      ext = v;
      peak = std::max(peak, rate);
    } else if (dir * (v - ext) >= 0) {  // on in the direction of motion
      ext = v;
      peak = std::max(peak, rate);
    } else if (dir * (ext - v) > threshold) {  // a turn at ext
      if (started) peaks.push_back({peak, static_cast<double>(k - begin) * r.dt});
      started = true;
      begin = k;
      dir = -dir;
      ext = v;
      peak = rate;
    }
  }
}

/// The excitation of records (together), with levels and depths on the training range [lo, lo +
/// range].
DriveExcitation Describe(const std::string& name, const std::vector<const io::Record*>& recs,
                         double lo, double range, const ExcitationOptions& o) {
  DriveExcitation d;
  d.name = name;
  d.records = recs.size();
  d.u_min = recs.front()->u[recs.front()->first_scored];
  d.u_max = d.u_min;
  d.depth_weight.assign(static_cast<size_t>(o.bins), 0.0);
  d.level_weight.assign(static_cast<size_t>(o.bins), 0.0);
  std::vector<double> rates;
  std::vector<std::pair<double, double>> peaks;  // (peak rate, duration)
  for (const io::Record* r : recs) {
    HalfCyclePeakRates(*r, o.turn_threshold * range, peaks);
    const size_t first_rate = rates.size();
    size_t hold_start = r->first_scored;
    for (size_t k = r->first_scored; k < r->end_scored; ++k) {
      d.u_min = std::min(d.u_min, r->u[k]);
      d.u_max = std::max(d.u_max, r->u[k]);
      if (k + 1 < r->end_scored) rates.push_back(std::abs(r->u[k + 1] - r->u[k]) / r->dt);
      if (std::abs(r->u[k] - r->u[hold_start]) > o.hold_level * range) hold_start = k;
      d.longest_hold_s = std::max(d.longest_hold_s, static_cast<double>(k - hold_start) * r->dt);
    }
    const double p95 = Percentile95(
        std::vector<double>(rates.begin() + static_cast<std::ptrdiff_t>(first_rate), rates.end()));
    d.rate_p95_lo = r == recs.front() ? p95 : std::min(d.rate_p95_lo, p95);
    d.rate_p95_hi = r == recs.front() ? p95 : std::max(d.rate_p95_hi, p95);
    d.duration_s += static_cast<double>(r->scored()) * r->dt;
    const std::vector<double> turns = Turns(*r, o.turn_threshold * range);
    d.turns += turns.size();
    for (double t : turns) d.level_weight[static_cast<size_t>(Bin((t - lo) / range, o.bins))] += 1;
    for (const ReversalCycle& c : Rainflow(turns)) {
      d.cycles.push_back(c);
      d.depth_weight[static_cast<size_t>(Bin((c.upper - c.lower) / range, o.bins))] += c.weight;
    }
  }
  d.rate_p95 = Percentile95(rates);
  for (double v : rates) d.rate_max = std::max(d.rate_max, v);
  d.half_cycles = peaks.size();
  if (!peaks.empty()) {  // percentiles over time: each half cycle weighted by its duration
    std::sort(peaks.begin(), peaks.end());
    double total = 0;
    for (const auto& p : peaks) total += p.second;
    const auto at = [&](double q) {
      double sum = 0;
      for (const auto& p : peaks)
        if ((sum += p.second) >= q * total) return p.first;
      return peaks.back().first;
    };
    d.rate_peak_lo = at(0.1);
    d.rate_peak_hi = at(0.9);
  }
  return d;
}

/// The cells (upper bin, lower bin) of the plane that the training's cycles cover, with their
/// neighbours.
std::vector<bool> CoveredCells(const DriveExcitation& t, double lo, double range, int bins) {
  std::vector<bool> cov(static_cast<size_t>(bins * bins), false);
  for (const ReversalCycle& c : t.cycles) {
    const int i = Bin((c.upper - lo) / range, bins), j = Bin((c.lower - lo) / range, bins);
    for (int a = std::max(0, i - 1); a <= std::min(bins - 1, i + 1); ++a)
      for (int b = std::max(0, j - 1); b <= std::min(bins - 1, j + 1); ++b)
        cov[static_cast<size_t>(a * bins + b)] = true;
  }
  return cov;
}

std::vector<bool> Present(const std::vector<double>& w) {
  std::vector<bool> on;
  for (double x : w) on.push_back(x > 0);
  return on;
}

}  // namespace

bool NeedsRateCoverage(model::EffectKind effect) {
  return effect == model::EffectKind::Named("rate-dependence");
}

std::string RateCoverageError(const io::RecordSet& set, std::span<const model::EffectKind> effects,
                              const ExcitationOptions& options) {
  const auto it = std::find_if(effects.begin(), effects.end(), NeedsRateCoverage);
  if (it == effects.end()) return "";
  const ExcitationReport rep = AnalyseExcitation(set, options);
  const DriveExcitation& t = rep.training;
  if (t.rate_span() >= kMinRateSpan) return "";
  std::ostringstream s;
  s << "effect '" << it->name()
    << "' needs training records that cover rates: the peak drive rate of their half "
    << "cycles must span a factor " << Num(kMinRateSpan) << " at least, and the " << t.half_cycles
    << " complete half cycles of the training records peak at " << Num(t.rate_peak_lo) << " … "
    << Num(t.rate_peak_hi) << " " << set.drive_unit << "/s (" << Num(t.rate_span(), 3)
    << "×): at one rate a rate-dependent lag is not told from the loop's shape. Train on records "
       "at several rates "
       "(sines at 0.5, 2 and 8 Hz, or a chirp), or leave the effect out";
  return s.str();
}

std::string ExcitationOptions::Validate() const {
  if (!(turn_threshold > 0 && turn_threshold < 0.5))
    return FieldError("turn_threshold", turn_threshold, "must be in (0, 0.5)");
  if (bins < 2 || bins > 100) return FieldError("bins", bins, "must be in [2, 100]");
  if (!(range_margin >= 0)) return FieldError("range_margin", range_margin, "must be >= 0");
  if (!(uncovered_share > 0 && uncovered_share <= 1))
    return FieldError("uncovered_share", uncovered_share, "must be in (0, 1]");
  if (!(rate_faster > 1) || !(rate_slower > 1))
    return FieldError("rate_faster", rate_faster, "and rate_slower must be > 1");
  if (!(hold_level > 0 && hold_level < 0.5))
    return FieldError("hold_level", hold_level, "must be in (0, 0.5)");
  if (!(min_hold_s > 0)) return FieldError("min_hold_s", min_hold_s, "must be > 0");
  return "";
}

const char* ExcitationNeedName(ExcitationNeed::Kind k) {
  switch (k) {
    case ExcitationNeed::Kind::kRange:
      return "range";
    case ExcitationNeed::Kind::kReversals:
      return "reversals";
    case ExcitationNeed::Kind::kRate:
      return "rate";
    case ExcitationNeed::Kind::kHold:
      return "hold";
  }
  return "?";
}

bool ExcitationReport::HasGap() const {
  return std::any_of(withheld.begin(), withheld.end(),
                     [](const WithheldExcitation& w) { return !w.needs.empty(); });
}

namespace {

/// The training excitation's summary, one line per aspect: the drive, the reversals, the rates,
/// the rate span and the duration against the creep times.
std::vector<std::string> TrainingLines(const DriveExcitation& t, const std::string& unit,
                                       const ExcitationOptions& o) {
  std::vector<std::string> lines;
  {
    std::ostringstream s;
    s << "drive " << Num(t.u_min, 4) << " … " << Num(t.u_max, 4) << " " << unit << " over "
      << Num(t.duration_s) << " s in " << t.records << " training record(s)";
    lines.push_back(s.str());
  }
  {
    std::ostringstream s;
    s << t.turns << " reversals, turning at " << BinRanges(Present(t.level_weight))
      << " of the range; reversal depths (rainflow, share of the range): ";
    std::string depths;
    for (int b = o.bins - 1; b >= 0; --b) {
      const double w = t.depth_weight[static_cast<size_t>(b)];
      if (w > 0)
        depths += (depths.empty() ? "" : ", ") + std::to_string(100 * b / o.bins) + "–" +
                  std::to_string(100 * (b + 1) / o.bins) + " %: " + Num(w) + " cycles";
    }
    s << (depths.empty() ? "none" : depths);
    lines.push_back(s.str());
  }
  lines.push_back("rates: |du/dt| up to " + Num(t.rate_max) + " " + unit + "/s (95th percentile " +
                  (t.records > 1 ? Num(t.rate_p95_lo) + " … " + Num(t.rate_p95_hi) + " " + unit +
                                       "/s over the records)"
                                 : Num(t.rate_p95) + " " + unit + "/s)"));
  {
    std::ostringstream s;
    s << "rate span: " << t.half_cycles << " complete half cycles peaking at "
      << Num(t.rate_peak_lo) << " … " << Num(t.rate_peak_hi) << " " << unit
      << "/s (10th–90th percentile over time, " << Num(t.rate_span(), 3) << "×)";
    if (t.rate_span() < kMinRateSpan)
      s << ": one rate only — rate dependence cannot be told from the loop's shape; record at "
           "rates "
        << Num(kMinRateSpan) << "× apart at least (e.g. sines at 0.5, 2 and 8 Hz)";
    lines.push_back(s.str());
  }
  {
    std::ostringstream s;
    const double period =
        t.turns >= 2 ? 2 * t.duration_s / static_cast<double>(t.turns) : t.duration_s;
    s << "duration against the creep times: " << Num(t.duration_s)
      << " s of excitation, longest hold " << Num(t.longest_hold_s) << " s";
    if (t.longest_hold_s < o.min_hold_s) {
      s << ": relaxations slower than the drive's period (" << Num(period)
        << " s) show only as a drift over the record";
    } else {
      s << ": relaxations up to ≈ " << Num(t.longest_hold_s) << " s show in the holds";
    }
    lines.push_back(s.str());
  }
  return lines;
}

}  // namespace

ExcitationReport AnalyseExcitation(const io::RecordSet& set, const ExcitationOptions& o) {
  if (const std::string e = o.Validate(); !e.empty()) throw InputError("excitation options: " + e);
  std::vector<const io::Record*> train;
  for (const io::Record& r : set.records)
    if (r.role == CaseRole::kTrain && r.scored() > 0) train.push_back(&r);
  if (train.empty())
    throw InputError(set.source.string() +
                     ": no training record (role train) to analyse the excitation of");
  double lo = train.front()->u[train.front()->first_scored], hi = lo;
  for (const io::Record* r : train)
    for (size_t k = r->first_scored; k < r->end_scored; ++k) {
      lo = std::min(lo, r->u[k]);
      hi = std::max(hi, r->u[k]);
    }
  if (!(hi > lo)) {
    throw InputError(set.source.string() + ": the training drive is constant (" + Num(lo) + " " +
                     set.drive_unit + " over every scored sample): it excites nothing to identify");
  }
  const double range = hi - lo;
  const std::string unit = set.drive_unit;
  ExcitationReport rep;
  rep.drive_unit = unit;
  rep.training = Describe("training", train, lo, range, o);
  const DriveExcitation& t = rep.training;
  rep.training_lines = TrainingLines(t, unit, o);
  const std::vector<bool> covered = CoveredCells(t, lo, range, o.bins);
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    if (r.role == CaseRole::kTrain || r.scored() == 0) continue;
    WithheldExcitation w;
    w.record = i;
    w.drive = Describe(r.name, {&r}, lo, range, o);
    const DriveExcitation& d = w.drive;
    const double beyond = std::max(d.u_max - hi, lo - d.u_min) / range;
    if (beyond > o.range_margin) {
      w.needs.push_back({ExcitationNeed::Kind::kRange, beyond,
                         "drive beyond the training range by " + Num(100 * beyond, 2) + " % (" +
                             Num(d.u_min, 4) + " … " + Num(d.u_max, 4) + " " + unit +
                             "; training " + Num(lo, 4) + " … " + Num(hi, 4) + " " + unit + ")"});
    }
    double total = 0, outside = 0;
    std::vector<bool> out_levels(static_cast<size_t>(o.bins), false),
        out_depths(static_cast<size_t>(o.bins), false);
    for (const ReversalCycle& c : d.cycles) {
      total += c.weight;
      const int a = Bin((c.upper - lo) / range, o.bins), b = Bin((c.lower - lo) / range, o.bins);
      if (covered[static_cast<size_t>(a * o.bins + b)]) continue;
      outside += c.weight;
      out_levels[static_cast<size_t>(a)] = out_levels[static_cast<size_t>(b)] = true;
      out_depths[static_cast<size_t>(Bin((c.upper - c.lower) / range, o.bins))] = true;
    }
    w.uncovered_share = total > 0 ? outside / total : 0;
    if (outside >= 1 && w.uncovered_share >= o.uncovered_share) {
      w.needs.push_back(
          {ExcitationNeed::Kind::kReversals, w.uncovered_share,
           Num(100 * w.uncovered_share, 2) +
               " % of its reversal cycles turn where training has none: turns at " +
               BinRanges(out_levels) + " of the range, depths " + BinRanges(out_depths) +
               "; training turns only at " + BinRanges(Present(t.level_weight)) + " (depths " +
               BinRanges(Present(t.depth_weight)) + "): its minor loops are extrapolated"});
    }
    if (t.rate_p95_hi > 0 && d.rate_p95 > o.rate_faster * t.rate_p95_hi) {
      const double k = d.rate_p95 / t.rate_p95_hi;
      w.needs.push_back({ExcitationNeed::Kind::kRate, k,
                         "rates " + Num(k, 2) +
                             "× faster than training (95th percentile of |du/dt| " +
                             Num(d.rate_p95) + " " + unit + "/s; training up to " +
                             Num(t.rate_p95_hi) + " " + unit + "/s)"});
    } else if (d.rate_p95 * o.rate_slower < t.rate_p95_lo) {
      const double k = d.rate_p95 > 0 ? t.rate_p95_lo / d.rate_p95 : INFINITY;
      w.needs.push_back({ExcitationNeed::Kind::kRate, 1 / k,
                         "rates " + (std::isfinite(k) ? Num(k, 2) + "×" : std::string("far")) +
                             " slower than training (95th percentile of |du/dt| " +
                             Num(d.rate_p95) + " " + unit + "/s; training down to " +
                             Num(t.rate_p95_lo) + " " + unit +
                             "/s): slow creep and rate dependence are extrapolated"});
    }
    if (d.longest_hold_s >= o.min_hold_s && d.longest_hold_s > 2 * t.longest_hold_s) {
      w.needs.push_back({ExcitationNeed::Kind::kHold, d.longest_hold_s,
                         "holds of " + Num(d.longest_hold_s) + " s; training's longest hold " +
                             Num(t.longest_hold_s) + " s: creep over " + Num(d.longest_hold_s) +
                             " s is extrapolated"});
    }
    rep.withheld.push_back(std::move(w));
  }
  return rep;
}

std::string ExcitationGapNote(const io::RecordSet& set, const ExcitationReport& rep,
                              const std::vector<double>& ratio, double significance) {
  std::string needing, within;
  double worst_needing = 0, worst_within = 0;
  for (const WithheldExcitation& w : rep.withheld) {
    const double x = w.record < ratio.size() ? ratio[w.record] : 0;
    std::string needs;
    for (const ExcitationNeed& n : w.needs)
      needs += (needs.empty() ? "" : ", ") + std::string(ExcitationNeedName(n.kind));
    const std::string item =
        set.records[w.record].name + " " + Num(x) + "×" + (needs.empty() ? "" : " (" + needs + ")");
    if (w.needs.empty()) {
      within += (within.empty() ? "" : ", ") + item;
      worst_within = std::max(worst_within, x);
    } else {
      needing += (needing.empty() ? "" : ", ") + item;
      worst_needing = std::max(worst_needing, x);
    }
  }
  if (needing.empty() || worst_needing <= significance) return "";
  std::string s = "Excitation gap: withheld record(s) " + needing +
                  " the floor need excitation the training records lack, so their error is partly "
                  "extrapolation";
  if (within.empty()) {
    s += "; no withheld record lies within the training excitation, so the data cannot tell an "
         "excitation gap from "
         "missing physics: train on the proposed drive (excitation_drive.csv) and diagnose again";
  } else if (worst_within <= significance) {
    s += ", while the record(s) within the training excitation (" + within +
         ") are within the significance threshold: the gap is an excitation gap rather than "
         "missing physics; train on "
         "the proposed drive (excitation_drive.csv)";
  } else {
    s += "; the record(s) within the training excitation (" + within +
         ") have a significant gap too: physics is missing as well";
  }
  return s + ".";
}

namespace {
// Bounds of a proposed training drive, whatever the records (an outlier in a slow record sets a
// range the p95 rate crosses in hours; a fast sample rate multiplies the samples).
constexpr double kMaxSineS = 600;      // the decaying sine's 12 cycles [s]
constexpr double kMaxMoveS = 10;       // one half-cosine move [s]
constexpr double kMaxSamples = 4.0e6;  // 32 MB of drive
}  // namespace

TrainingDriveProposal ProposeTrainingDrive(const io::RecordSet& set, const ExcitationReport& rep,
                                           uint64_t seed) {
  const DriveExcitation& t = rep.training;
  double lo = t.u_min, hi = t.u_max, rate = t.rate_p95, fs = 0;
  for (const WithheldExcitation& w : rep.withheld) {
    lo = std::min(lo, w.drive.u_min);
    hi = std::max(hi, w.drive.u_max);
    rate = std::max(rate, w.drive.rate_p95);
  }
  double rest_level = 0;
  for (const io::Record& r : set.records) {
    if (r.role != CaseRole::kTrain) continue;
    if (fs == 0) rest_level = r.u.front();  // the first training record's rest
    fs = std::max(fs, r.sample_rate_hz());
  }
  const double range = hi - lo, mid = (lo + hi) / 2, amp = range / 2;
  if (!(range > 0) || !(fs > 0))
    throw InputError("proposed drive: the records have no drive range or sample rate");
  if (!(rate > 0)) rate = range;  // one range per second
  // A sine of amplitude `amp` whose 95th-percentile rate is `rate`: 2π f A ≈ rate, its 12 cycles
  // within kMaxSineS (a range set by an outlier over a slow record would ask for hours).
  const int cycles = 12;
  double f = std::max(std::min(fs / 20, rate / (2 * std::numbers::pi * amp)), cycles / kMaxSineS);
  const double hold_s = std::clamp(t.duration_s / 8, 2.0, 10.0);
  // The longest the plan can take: rest, the first move, the sine, 60 + 9 moves, 9 holds. Over
  // kMaxSamples at the records' rate, the proposal is sampled more slowly (and says so).
  const double plan_s = 1 + kMaxMoveS + cycles / f + 69 * kMaxMoveS + 9 * hold_s;
  const double fs_records = fs;
  const bool slower = fs * plan_s > kMaxSamples;
  if (slower) {
    fs = kMaxSamples / plan_s;
    f = std::min(f, fs / 20);  // still 20 samples a period (its 240 samples stay within the bound)
  }
  TrainingDriveProposal p;
  p.records_fs_hz = fs_records;
  p.fs_hz = fs;
  const double dt = 1 / fs;
  auto hold = [&](double level, double seconds) {
    const size_t n = static_cast<size_t>(std::llround(seconds * fs));
    p.u.insert(p.u.end(), n, level);
  };
  // Half-cosine move to `level` at `rate` (at least 0.05 s).
  auto move = [&](double level) {
    const double from = p.u.empty() ? level : p.u.back();
    const double seconds =
        std::clamp(std::abs(level - from) / (rate * 2 / std::numbers::pi), 0.05, kMaxMoveS);
    const size_t n = std::max<size_t>(1, static_cast<size_t>(std::llround(seconds * fs)));
    for (size_t k = 1; k <= n; ++k)
      p.u.push_back(from + (level - from) *
                               (1 - std::cos(std::numbers::pi * static_cast<double>(k) / n)) / 2);
  };
  p.rest_s = 1;
  rest_level = std::clamp(rest_level, lo, hi);
  hold(rest_level, p.rest_s);
  move(lo);
  // 1. A decaying-amplitude sine from the lower end: nested minor loops around the middle.
  const size_t nd = static_cast<size_t>(std::llround(cycles / f * fs));
  for (size_t k = 1; k <= nd; ++k) {
    const double tau = static_cast<double>(k) * dt, a = amp * (1 - static_cast<double>(k) / nd);
    p.u.push_back(mid - a * std::cos(2 * std::numbers::pi * f * tau));
  }
  p.segments.push_back("a decaying-amplitude sine " + Num(mid, 4) + " ± " + Num(amp, 4) + " → 0 " +
                       rep.drive_unit + " at " + Num(f) + " Hz, " + std::to_string(cycles) +
                       " cycles: nested minor loops of every depth");
  // 2. A random reversal sequence over the range: turning points in every cell of the plane.
  opt::Rng rng(seed * 2862933555777941757ull + 3037000493ull);
  const int reversals = 60;
  for (int i = 0; i < reversals; ++i) {
    double next = p.u.back();
    while (std::abs(next - p.u.back()) < 0.05 * range) next = lo + range * rng.Uniform01();
    move(next);
  }
  p.segments.push_back("a random reversal sequence: " + std::to_string(reversals) +
                       " turning points uniform in " + Num(lo, 4) + " … " + Num(hi, 4) + " " +
                       rep.drive_unit + " (seed " + std::to_string(seed) +
                       "): minor loops at every level");
  // 3. A staircase of holds: creep over seconds.
  for (double share : {0.0, 0.25, 0.5, 0.75, 1.0, 0.75, 0.5, 0.25, 0.0}) {
    move(lo + share * range);
    hold(lo + share * range, hold_s);
  }
  p.segments.push_back(
      "a staircase of holds at 0, 25, 50, 75, 100, 75, 50, 25, 0 % of the range, " + Num(hold_s) +
      " s each: creep from 0.05 s to " + Num(hold_s) + " s");
  std::ostringstream d;
  d << "a proposed training drive of " << Num(static_cast<double>(p.u.size()) * dt) << " s at "
    << Num(fs, 5) << " Hz (after a " << Num(p.rest_s) << " s rest at " << Num(rest_level, 4) << " "
    << rep.drive_unit << "): ";
  if (slower) {
    d << "sampled at " << Num(fs, 5) << " Hz rather than the records' " << Num(p.records_fs_hz, 5)
      << " Hz, which would take over " << Num(kMaxSamples) << " samples (resample it for the "
      << "generator); ";
  }
  for (size_t i = 0; i < p.segments.size(); ++i) d << (i ? "; then " : "") << p.segments[i];
  p.description = d.str();
  return p;
}

}  // namespace pz::records
