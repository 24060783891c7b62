#include "reports/identify_report.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include "hgann/extrapolation.h"
#include "hgann/output_move.h"
#include "io/trace_io.h"
#include "model/chromosome.h"
#include "model/metrics.h"
#include "model/saturation.h"
#include "reports/plots.h"

namespace pz::reports {
namespace fs = std::filesystem;
using hgann::IdentifyResult;
using hgann::PaperTable8Pi;

namespace {

std::string Fmt(double x, int prec = 4) {
  if (std::isnan(x)) return "—";
  std::ostringstream os;
  os << std::setprecision(prec) << x;
  return os.str();
}

// Grid of a per-case value over amplitude (rows) × frequency (columns), markdown.
std::string Grid(const io::CaseSet& set,
                 const std::function<std::string(const io::BenchCase&)>& cell) {
  std::set<double> vs, fs_;
  for (const auto& c : set.cases) {
    vs.insert(c.amplitude_v);
    fs_.insert(c.frequency_hz);
  }
  std::ostringstream os;
  os << "| V \\ f |";
  for (double f : fs_) os << " " << Fmt(f) << " Hz |";
  os << "\n|---|";
  for (size_t i = 0; i < fs_.size(); ++i) os << "---|";
  os << "\n";
  for (double v : vs) {
    os << "| " << Fmt(v) << " V |";
    for (double f : fs_) {
      const io::BenchCase* found = nullptr;
      for (const auto& c : set.cases)
        if (c.amplitude_v == v && c.frequency_hz == f) found = &c;
      os << " " << (found ? cell(*found) : std::string("")) << " |";
    }
    os << "\n";
  }
  return os.str();
}

const hgann::HgannCaseResult& ResultOf(const IdentifyResult& r, int number) {
  for (const auto& c : r.cases)
    if (c.number == number) return c;
  PZ_CHECK_MSG(false, "no result for case " + std::to_string(number));
  return r.cases.front();
}

/// What the per-case tables add up to (for the report and the regression of μ).
struct CaseTotals {
  std::vector<double> v_all, f_all, mu_all;  ///< every case's V, f and identified μ
  double train_sum = 0, all_sum = 0;         ///< Σ PI over the training cases, over all cases
  int beaten = 0, compared = 0;              ///< cases below the paper's PI, cases it has a PI for
};

/// progress.csv: one line per generation.
void WriteProgressCsv(const fs::path& out, const IdentifyResult& result,
                      std::vector<fs::path>& written) {
  std::ofstream f(out / "progress.csv");
  f << "generation,best_cost,median_cost,mean_cost,worst_cost,stall,evaluations,evaluations_total,"
       "failures,penalized,"
       "errors,wall_time_s,best_network"
    << IslandCsvHeader(result.log) << "\n";
  f << std::setprecision(17);
  for (const auto& g : result.log)
    f << g.generation << "," << g.best_cost << "," << g.median_cost << "," << g.mean_cost << ","
      << g.worst_cost << "," << g.stall << "," << g.evaluations << "," << g.evaluations_total << ","
      << g.failures << "," << g.penalized << "," << g.errors << "," << g.wall_time_s << ",\""
      << g.best_description << "\"" << IslandCsvCells(g) << "\n";
  written.push_back(out / "progress.csv");
}

/// validation.csv, parameters.csv and every case's trace (traces/caseN.csv).
CaseTotals WriteCaseTables(const fs::path& out, const io::CaseSet& set,
                           const hgann::HgannFitness& fitness, const IdentifyResult& result,
                           std::vector<fs::path>& written) {
  auto add = [&](const fs::path& p) { written.push_back(p); };
  CaseTotals t;
  auto& [v_all, f_all, mu_all, train_sum, all_sum, beaten, compared] = t;
  std::ofstream val(out / "validation.csv"), par(out / "parameters.csv");
  val << "case,amplitude_V,frequency_Hz,role,pi_deg2,rmse_deg,max_abs_deg,paper_pi_deg2,status\n";
  par << "case,amplitude_V,frequency_Hz,role,mu,delta,alpha,beta,gamma,a1,a2,b1,b2\n";
  val << std::setprecision(10);
  par << std::setprecision(10);
  for (const auto& bc : set.cases) {
    const auto& r = ResultOf(result, bc.number);
    const auto trace =
        fitness.Trace(result.best.network, fitness.config().cases[&bc - set.cases.data()]);
    const auto m = trace.summary.ok() ? model::CompareSeries(bc.angle_deg, trace.angle_deg)
                                      : model::ErrorMetrics{};
    const double paper = PaperTable8Pi(bc.amplitude_v, bc.frequency_hz);
    val << bc.number << "," << bc.amplitude_v << "," << bc.frequency_hz << ","
        << io::CaseRoleName(bc.role) << "," << r.pi << "," << m.rmse << "," << m.max_abs << ","
        << (std::isnan(paper) ? std::string("") : Fmt(paper, 6)) << ","
        << model::SimStatusName(r.summary.status) << "\n";
    const auto& q = r.params;
    par << bc.number << "," << bc.amplitude_v << "," << bc.frequency_hz << ","
        << io::CaseRoleName(bc.role) << "," << q.mu << "," << q.delta << "," << q.alpha << ","
        << q.beta << "," << q.gamma << "," << q.a1 << "," << q.a2 << "," << q.b1 << "," << q.b2
        << "\n";
    all_sum += r.pi;
    if (bc.role == io::CaseRole::kTrain) train_sum += r.pi;
    if (!std::isnan(paper)) {
      ++compared;
      beaten += r.pi < paper;
    }
    v_all.push_back(bc.amplitude_v);
    f_all.push_back(bc.frequency_hz);
    mu_all.push_back(q.mu);
    // Trace for plots: t, u, measured, model, theta.
    const std::string tf = "traces/case" + std::to_string(bc.number) + ".csv";
    if (trace.summary.ok()) {
      std::vector<io::NamedColumn> cols = {{"t_s", trace.t},
                                           {"voltage_V", trace.u},
                                           {"measured_deg", bc.angle_deg},
                                           {"model_deg", trace.angle_deg},
                                           {"theta_linear_deg", trace.theta_deg},
                                           {"z_N", trace.z}};
      io::WriteColumnsCsvFile(out / tf, cols);
      add(out / tf);
    }
  }
  add(out / "validation.csv");
  add(out / "parameters.csv");
  return t;
}

/// The regression of μ on V and f (paper eq. 7), as a sentence.
std::string MuRegression(const CaseTotals& t) {
  const std::vector<double>&v_all = t.v_all, &f_all = t.f_all, &mu_all = t.mu_all;
  std::string mu_regression;
  double mn = *std::min_element(mu_all.begin(), mu_all.end());
  double mx = *std::max_element(mu_all.begin(), mu_all.end());
  if (mx - mn <= 1e-12 * std::max(1.0, std::abs(mx))) {
    mu_regression =
        "μ = " + Fmt(mn, 6) + " 1/s in every case: no trend over V and f (R² undefined).";
  } else {
    try {
      const auto fit = model::FitPlane(v_all, f_all, mu_all);
      std::ostringstream os;
      os << "μ = " << Fmt(fit.v.coef, 4) << " V " << (fit.f.coef < 0 ? "− " : "+ ")
         << Fmt(std::abs(fit.f.coef), 5) << " f " << (fit.intercept.coef < 0 ? "− " : "+ ")
         << Fmt(std::abs(fit.intercept.coef), 6) << "  (R² " << Fmt(fit.r2, 3) << "; p-values V "
         << Fmt(fit.v.p_value, 2) << ", f " << Fmt(fit.f.p_value, 2) << ", intercept "
         << Fmt(fit.intercept.p_value, 2) << "; n = " << fit.n
         << "). Paper eq. 7: μ = 0.020 V − 36.525 f + 102.361 (R² 0.988).";
      mu_regression = os.str();
    } catch (const InputError& e) {
      mu_regression = std::string("μ regression not possible: ") + e.what();
    }
  }
  return mu_regression;
}

/// The figures' gnuplot scripts and, with options.plots, their renderings; the number rendered.
int WriteFigures(const IdentifyOptions& options, const fs::path& out, const io::CaseSet& set,
                 size_t islands, std::vector<fs::path>& written,
                 std::vector<std::string>* plot_errors_out) {
  auto add = [&](const fs::path& p) { written.push_back(p); };
  auto& plot_errors = *plot_errors_out;
  int rendered = 0;
  std::vector<fs::path> scripts;
  Plot p{"fitness",
         "HGANN fitness progress (CF = Σ PI over the training cases)",
         "generation",
         "cost [deg²]",
         true,
         {{"progress.csv", 1, 2, "best", "lines"}, {"progress.csv", 1, 3, "mean", "lines"}}};
  // With islands, one line per island's best (progress.csv's island_<k>_best, from column 18).
  for (size_t k = 0; k < islands; ++k)
    p.series.push_back(
        {"progress.csv", 1, 18 + static_cast<int>(k), "island " + std::to_string(k), "lines"});
  scripts.push_back(WritePlotScript(out, p));
  for (const auto& bc : set.cases) {
    const std::string tf = "traces/case" + std::to_string(bc.number) + ".csv";
    if (!fs::exists(out / tf)) continue;
    const std::string label = "case " + std::to_string(bc.number) + " (" + Fmt(bc.amplitude_v) +
                              " V, " + Fmt(bc.frequency_hz) + " Hz, " + io::CaseRoleName(bc.role) +
                              ")";
    scripts.push_back(WritePlotScript(
        out, Plot{"case" + std::to_string(bc.number) + "_angle",
                  "Fin angle, " + label,
                  "t [s]",
                  "fin angle [deg]",
                  false,
                  {{tf, 1, 3, "measured", "lines"}, {tf, 1, 4, "model", "lines"}}}));
    scripts.push_back(WritePlotScript(
        out, Plot{"case" + std::to_string(bc.number) + "_loop",
                  "Hysteresis loop, " + label,
                  "voltage [V]",
                  "fin angle [deg]",
                  false,
                  {{tf, 2, 3, "measured", "lines"}, {tf, 2, 4, "model", "lines"}}}));
  }
  for (const auto& s : scripts) add(s);
  if (options.plots) {
    if (GnuplotAvailable()) {
      rendered = RenderPlots(out, scripts, &plot_errors);
      for (const auto& s : scripts) {
        auto png = s;
        png.replace_extension(".png");
        if (fs::exists(png)) add(png);
      }
    } else {
      plot_errors.push_back(
          "gnuplot not found: figures not rendered (install gnuplot-nox, then run gnuplot on each "
          ".gp in " +
          out.string() + ")");
    }
  }
  return rendered;
}

// "α at its upper bound 0.01 N/V, a1 at its lower bound 0 deg" for the parameters the network holds
// at a bound of their range on every training case; "" when none.
std::string AtBoundList(const hgann::HgannFitness& fitness, const model::Network& network) {
  static constexpr const char* kSymbols[model::kNetworkOutputs] = {"μ", "δ",  "α", "β",
                                                                   "γ", "a1", "a2"};
  const auto side = fitness.ParametersAtBound(network);
  std::string out;
  for (int k = 0; k < model::kNetworkOutputs; ++k) {
    if (side[k] == 0) continue;
    const auto& r = fitness.config().ranges[k];
    out += (out.empty() ? "" : ", ") + std::string(kSymbols[k]) +
           (side[k] > 0 ? " at its upper bound " : " at its lower bound ") +
           Fmt(side[k] > 0 ? r.upper : r.lower, 4) + " " + model::OutputUnit(k);
  }
  return out;
}

/// The network against per-case fits (issue 36): every case fitted alone (hgann::FitCases), and
/// where the network's parameter departs from that estimate by more than 2 σ. A parameter whose
/// σ is infinite or above a quarter of its range is not pinned down by the case alone: no claim.
struct PerCaseCheck {
  std::string markdown;  ///< the report's section
  std::string terminal;  ///< one line per departure
  std::vector<hgann::CaseEstimate> estimates;
};

/// The profile test of a departure beyond 2 σ (σ is the linearisation's, which understates the
/// α–β–γ–backlash valley): parameter k held at the network's value (and the loose ones at theirs,
/// as in the estimate), the case refitted from the network's parameters (LM only lowers the PI
/// from there; from the case's own estimate it stuck on backlash kinks). The network's value
/// departs only if that leaves the case's PI above its own by more than 4 residual variances
/// (Δχ² > 4: 2 σ of the profile) and by more than its own PI: the per-case fit absorbs correlated
/// noise and model error that the residuals' lag-1 correction does not see (the nominal bench's
/// truth, quantised into a network, is within 1.9 × every case's own PI and was flagged in 9
/// places by Δχ² alone).
bool ProfileDeparts(const hgann::HgannFitness& fitness, int index, const hgann::CaseEstimate& e,
                    int k, const std::array<double, model::kNetworkOutputs>& net,
                    const std::array<bool, model::kNetworkOutputs>& loose,
                    const hgann::TrendSeedOptions& options) {
  std::array<double, model::kNetworkOutputs> hold, start;
  for (int m = 0; m < model::kNetworkOutputs; ++m) {
    const auto& range = fitness.config().ranges[m];
    const double width = range.upper - range.lower;
    start[m] = width > 0 ? (net[m] - range.lower) / width : 0.0;
    hold[m] = (m == k || loose[m]) ? start[m] : std::nan("");
  }
  const hgann::CaseEstimate p =
      hgann::FitCases(fitness, {index}, options, nullptr, &hold, &start).front();
  return !p.ok || p.pi - e.pi > std::max(4 * e.residual_var, e.pi);
}

/// Every case fitted alone; a parameter that half the cases or more leave free (μ against δ: one
/// frequency sees the damping as one number) is held at the network's own value in each case and
/// the case refitted: the other estimates then answer "what does this case want, given the
/// network's μ". `loose` says which were held.
std::vector<hgann::CaseEstimate> PerCaseEstimates(const hgann::HgannFitness& fitness,
                                                  const IdentifyResult& result,
                                                  const hgann::TrendSeedOptions& so,
                                                  std::array<bool, model::kNetworkOutputs>* loose) {
  std::vector<int> all;
  for (size_t i = 0; i < fitness.config().cases.size(); ++i) all.push_back(static_cast<int>(i));
  std::vector<hgann::CaseEstimate> estimates = hgann::FitCases(fitness, all, so);
  loose->fill(false);
  for (int k = 0; k < model::kNetworkOutputs; ++k) {
    const auto& range = fitness.config().ranges[k];
    int n = 0, free = 0;
    for (const hgann::CaseEstimate& e : estimates) {
      if (!e.ok) continue;
      ++n;
      free += !(std::isfinite(e.sigma[k]) && e.sigma[k] <= 0.25 * (range.upper - range.lower));
    }
    (*loose)[k] = n > 0 && 2 * free >= n;
  }
  if (std::none_of(loose->begin(), loose->end(), [](bool b) { return b; })) return estimates;
  for (size_t i = 0; i < all.size(); ++i) {
    const auto& r = ResultOf(result, fitness.config().cases[i].number).params;
    const auto net =
        model::NetworkParameters{r.mu, r.delta, r.alpha, r.beta, r.gamma, r.a1, r.a2}.ToArray();
    std::array<double, model::kNetworkOutputs> hold;
    for (int k = 0; k < model::kNetworkOutputs; ++k) {
      const auto& range = fitness.config().ranges[k];
      const double width = range.upper - range.lower;
      hold[k] = (*loose)[k] && width > 0 ? (net[k] - range.lower) / width : std::nan("");
    }
    estimates[i] = hgann::FitCases(fitness, {all[i]}, so, nullptr, &hold).front();
  }
  return estimates;
}

PerCaseCheck CheckAgainstPerCaseFits(const IdentifyOptions& options, const io::CaseSet& set,
                                     const hgann::HgannFitness& fitness,
                                     const IdentifyResult& result) {
  static constexpr const char* kSymbols[model::kNetworkOutputs] = {"μ", "δ",  "α", "β",
                                                                   "γ", "a1", "a2"};
  PerCaseCheck out;
  hgann::TrendSeedOptions so;
  so.threads = std::max(1, options.threads > 0 ? options.threads : 2);
  std::array<bool, model::kNetworkOutputs> loose{};
  out.estimates = PerCaseEstimates(fitness, result, so, &loose);
  std::ostringstream md, term, missed;
  md << "## The network against per-case fits\n\n"
     << "Each case fitted alone (the seven parameters, its b1 and b2; Levenberg–Marquardt from "
     << so.case_starts
     << " starts; a parameter that most cases leave free is held at the network's "
     << "value in each case, shown `(held)`): its PI and each parameter as `network / per-case ± "
        "σ`. **Bold**: the "
     << "network departs from the case's own estimate by more than 2 σ and the case, refitted "
        "with the parameter held at the network's value, gains more PI than 4 residual variances "
        "(the profile's 2 σ: the linear σ understates the α–β–γ–backlash valley) and than its own "
        "PI (the profile's PI above twice the case's); `(free)`: "
        "the case alone does not "
     << "pin the parameter down (σ infinite or above a quarter of its range), so no claim is "
        "made.\n\n"
     << "| case | role | PI network / per-case [deg²] |";
  for (const char* s : kSymbols) md << " " << s << " |";
  md << "\n|---|---|---|";
  for (int k = 0; k < model::kNetworkOutputs; ++k) md << "---|";
  md << "\n";
  int departures = 0;
  std::map<int, std::vector<int>> by_param;  // parameter → cases departing
  for (size_t i = 0; i < out.estimates.size(); ++i) {
    const hgann::CaseEstimate& e = out.estimates[i];
    const auto& bc = set.cases[i];
    const auto& r = ResultOf(result, bc.number);
    const bool training = bc.role == io::CaseRole::kTrain;
    md << "| " << bc.number << " | " << io::CaseRoleName(bc.role) << " | " << Fmt(r.pi, 3) << " / "
       << (e.ok ? Fmt(e.pi, 3) : "failed") << " |";
    const auto net =
        model::NetworkParameters{r.params.mu,    r.params.delta, r.params.alpha, r.params.beta,
                                 r.params.gamma, r.params.a1,    r.params.a2}
            .ToArray();
    for (int k = 0; k < model::kNetworkOutputs; ++k) {
      const auto& range = fitness.config().ranges[k];
      const double width = range.upper - range.lower;
      if (!e.ok) {
        md << " " << Fmt(net[k], 3) << " / — |";
        continue;
      }
      const bool free = !std::isfinite(e.sigma[k]) || e.sigma[k] > 0.25 * width;
      if (loose[k]) {
        md << " " << Fmt(net[k], 3) << " (held) |";
        continue;
      }
      bool departs = !free && std::abs(net[k] - e.value[k]) > 2 * e.sigma[k];
      if (departs) departs = ProfileDeparts(fitness, static_cast<int>(i), e, k, net, loose, so);
      const std::string cell = Fmt(net[k], 3) + " / " + Fmt(e.value[k], 3) +
                               (free ? " (free)" : " ± " + Fmt(e.sigma[k], 2));
      md << " " << (departs ? "**" + cell + "**" : cell) << " |";
      if (departs) {
        ++departures;
        by_param[k].push_back(bc.number);
        term << "  case " << bc.number << (training ? " (training)" : " (withheld)") << ": "
             << kSymbols[k] << " network " << Fmt(net[k], 4) << ", per-case " << Fmt(e.value[k], 4)
             << " ± " << Fmt(e.sigma[k], 2) << " " << model::OutputUnit(k) << "\n";
      }
    }
    md << "\n";
    // A case the network misses as a whole (its PI above twice the case's own and by more than 4
    // residual variances) that no parameter explains alone: they trade along the valley.
    if (e.ok && r.pi - e.pi > std::max(4 * e.residual_var, e.pi) &&
        std::none_of(by_param.begin(), by_param.end(), [&](const auto& kv) {
          return std::find(kv.second.begin(), kv.second.end(), bc.number) != kv.second.end();
        })) {
      missed << (missed.tellp() > 0 ? "; " : "") << "case " << bc.number << ": " << Fmt(r.pi, 3)
             << " against its own " << Fmt(e.pi, 3) << " deg²";
      term << "  case " << bc.number << (training ? " (training)" : " (withheld)") << ": PI "
           << Fmt(r.pi, 3) << " deg², its own fit's " << Fmt(e.pi, 3)
           << " (no one parameter explains it)\n";
    }
  }
  md << "\n";
  if (missed.tellp() > 0)
    md << "Missed as a whole (the network's PI above twice the case's own, but no parameter "
          "departs alone: they trade along the α–β–γ–backlash valley): "
       << missed.str() << ".\n\n";
  if (departures == 0 && missed.tellp() == 0) {
    md << "The network agrees with every per-case estimate that its case pins down (within 2 "
          "σ).\n\n";
  } else if (departures > 0) {
    md << departures << " departures beyond 2 σ. ";
    for (const auto& [k, cases] : by_param) {
      md << kSymbols[k] << " in case" << (cases.size() > 1 ? "s" : "");
      for (size_t m = 0; m < cases.size(); ++m) md << (m ? ", " : " ") << cases[m];
      md << "; ";
    }
    md << "where the per-case PI is well below the network's, the case's own data want another "
          "value: a trend "
          "the network misses (or, for parameters that trade against each other, such as α, β and "
          "γ, the "
          "case's estimate is one point of a valley the network crosses elsewhere — compare the "
          "PIs).\n\n";
  }
  out.markdown = md.str();
  out.terminal =
      term.tellp() == 0
          ? std::string()
          : "the network departs from a per-case fit by more than 2 σ (report.md):\n" + term.str();
  return out;
}

/// Where the network extrapolates (hgann/extrapolation.h): every withheld case outside the training
/// cases' hull in (V, f) and its outputs beyond the range the training cases support; with trend
/// seeds, every withheld case whose outputs the training cases do not settle (the shapes that fit
/// their per-case estimates alike part there). Markdown and the terminal's lines.
std::pair<std::string, std::string> ExtrapolationSection(
    const io::CaseSet& set, const hgann::HgannFitness& fitness, const IdentifyResult& result,
    const std::vector<hgann::CaseEstimate>& estimates) {
  static constexpr const char* kSymbols[model::kNetworkOutputs] = {"μ", "δ",  "α", "β",
                                                                   "γ", "a1", "a2"};
  const auto found = hgann::FindExtrapolations(fitness.config(), result.cases, estimates);
  std::ostringstream md, term;
  md << "## Where the network extrapolates\n\n"
     << "Withheld cases outside the training cases' hull in (V, f) (no training case brackets "
        "them: what the network says there is set by its shape), with the outputs beyond the "
        "range the training cases support (the network's values at the training cases and their "
        "per-case estimates ± 2 σ, widened by 1 % of the parameter's range)"
     << (result.seeds ? "; and every withheld case where the shapes that fit the training cases' "
                        "per-case estimates alike (χ² + 2 p within 2 of the chosen one's; with the "
                        "network's own value) part by more than 1 % of a parameter's range and "
                        "2 σ of the case's own fit, and where the end of that range farthest from "
                        "the network's value moves the case's prediction by twice its own PI or "
                        "more (were it the truth, the network's PI would be 3 × the floor): there "
                        "the training cases do not settle the value, and the network's is one "
                        "guess of several (μ, δ, a1, a2: α, β and γ trade along a valley, where "
                        "their per-case estimates scatter even when the truth is constant)"
                      : "")
     << ".\n\n"
     << "| case | V [V] | f [Hz] | outside the hull | beyond the training cases' range | not "
        "settled by the training cases (range of the shapes that fit them alike) |\n"
     << "|---|---|---|---|---|---|\n";
  int rows = 0;
  for (size_t i = 0; i < set.cases.size(); ++i) {
    const auto& bc = set.cases[i];
    if (bc.role == io::CaseRole::kTrain) continue;
    const auto it = std::find_if(found.begin(), found.end(),
                                 [&](const auto& e) { return e.number == bc.number; });
    const auto& q = ResultOf(result, bc.number).params;
    const auto net =
        model::NetworkParameters{q.mu, q.delta, q.alpha, q.beta, q.gamma, q.a1, q.a2}.ToArray();
    // How far the case's prediction moves with output k alone at `value` (Σ of squares, deg²).
    const auto moved = [&](int k, double value) {
      const hgann::HgannCase& c = fitness.config().cases[i];
      std::vector<double> a(c.measured_deg.size()), b(c.measured_deg.size());
      auto p = net;
      p[k] = value;
      if (!fitness.SimulateCase(model::NetworkParameters::FromArray(net), c, a) ||
          !fitness.SimulateCase(model::NetworkParameters::FromArray(p), c, b))
        return std::nan("");
      double d = 0;
      for (size_t m = 0; m < a.size(); ++m) d += (a[m] - b[m]) * (a[m] - b[m]);
      return d;
    };
    const std::vector<int> open =
        result.seeds
            ? hgann::UnsettledOutputs(fitness.config(), *result.seeds, i, net,
                                      i < estimates.size() ? &estimates[i] : nullptr, moved)
            : std::vector<int>{};
    if (it == found.end() && open.empty()) continue;
    ++rows;
    std::string beyond, unsettled;
    if (it != found.end())
      for (int k : it->outputs)
        beyond += (beyond.empty() ? "" : "; ") + std::string(kSymbols[k]) + " " +
                  Fmt(it->value[k], 3) + " (training " + Fmt(it->lo[k], 3) + " … " +
                  Fmt(it->hi[k], 3) + " " + model::OutputUnit(k) + ")";
    for (int k : open)
      unsettled += (unsettled.empty() ? "" : "; ") + std::string(kSymbols[k]) + " " +
                   Fmt(net[k], 3) + " (" +
                   Fmt(std::min(net[k], result.seeds->supported_lo[i][k]), 3) + " … " +
                   Fmt(std::max(net[k], result.seeds->supported_hi[i][k]), 3) + " " +
                   model::OutputUnit(k) + ")";
    const std::string outside = it != found.end() ? "yes" : "no";
    md << "| " << bc.number << " | " << Fmt(bc.amplitude_v) << " | " << Fmt(bc.frequency_hz)
       << " | " << outside << " | "
       << (it == found.end() ? "—"
           : beyond.empty()  ? "none"
                             : beyond)
       << " | " << (unsettled.empty() ? "—" : unsettled) << " |\n";
    term << "  case " << bc.number << " (" << Fmt(bc.amplitude_v) << " V, " << Fmt(bc.frequency_hz)
         << " Hz" << (it != found.end() ? ", outside the hull" : "")
         << "): " << (beyond.empty() ? "" : "beyond the training range " + beyond + "; ")
         << (unsettled.empty()
                 ? (beyond.empty() ? "outputs within the training cases' range and settled by them"
                                   : "settled")
                 : "not settled " + unsettled)
         << "\n";
  }
  if (rows == 0) {
    md.str("");
    md << "## Where the network extrapolates\n\nEvery withheld case lies inside the training "
          "cases' hull in (V, f)"
       << (result.seeds ? ", and the shapes that fit the training cases alike agree at each" : "")
       << ".\n\n";
    return {md.str(), ""};
  }
  md << "\n";
  return {md.str(),
          "where the network extrapolates or the training cases leave an output open "
          "(report.md):\n" +
              term.str()};
}

/// The committee of laws that fit the training cases alike (hgann::LawCommittee): which
/// withheld cases they leave open, with the range of their parameters there, and the next case to
/// measure. Markdown and the terminal's lines.
std::pair<std::string, std::string> CommitteeSection(const io::CaseSet& set,
                                                     const hgann::LawCommittee& c) {
  std::ostringstream md, term;
  if (c.floor.size() != set.cases.size()) return {"", ""};
  md << "### What the training cases leave open, and the next case (query by committee)\n\n"
     << "A committee of " << c.members
     << " laws that fit the training cases alike (the law with a V·f term, one posterior σ either "
        "way along each direction the prior settles; the law moved along each direction of its "
        "basis that moves no training case; the other shapes in f that fit alike; the network "
        "kept: hgann/operating_law.h). A withheld case is "
        "open where a member moves its predicted angle by 2 floors or more (floor: the residual "
        "variance a sample × its samples): were that member the truth, the law's PI there would "
        "be about 3 × the floor.\n\n"
     << "| case | V [V] | f [Hz] | open | largest member's Σ (Δy)² [floors] | the kept network's "
        "[floors] | μ [1/s] | δ [s] | a1 [deg] | a2 [deg] |\n|---|---|---|---|---|---|---|---|---|"
        "---|\n";
  std::string open;
  for (size_t i = 0; i < set.cases.size(); ++i) {
    const auto& bc = set.cases[i];
    if (bc.role == io::CaseRole::kTrain) continue;
    md << "| " << bc.number << " | " << Fmt(bc.amplitude_v) << " | " << Fmt(bc.frequency_hz)
       << " | " << (c.open[i] ? "**open**" : "settled") << " | "
       << Fmt(c.disagreement[i] / c.floor[i], 3) << " | "
       << Fmt(c.kept_disagreement[i] / c.floor[i], 3) << " |";
    for (int k : {0, 1, 5, 6})
      md << " " << Fmt(c.lo[i][k], 3) << " … " << Fmt(c.hi[i][k], 3) << " |";
    md << "\n";
    if (c.open[i])
      open += (open.empty() ? "" : ", ") + std::to_string(bc.number) + " (" +
              Fmt(c.disagreement[i] / c.floor[i], 2) + " floors)";
  }
  std::string next;
  for (size_t r = 0; r < c.next.size() && r < 2; ++r) {
    const auto& cand = c.candidates[c.next[r].first];
    const std::string name = cand.case_index >= 0
                                 ? "case " + std::to_string(set.cases[cand.case_index].number) + " "
                                 : std::string("your point ");
    next += (r ? "; then " : "") + name + "(" + Fmt(cand.amplitude_v) + " V, " +
            Fmt(cand.frequency_hz) + " Hz: " + Fmt(c.next[r].second, 3) + " floors left open)";
  }
  const bool user = !c.candidates.empty() && c.candidates.front().case_index < 0;
  md << "\n- open: " << (open.empty() ? "none" : open) << "\n"
     << "- next case to measure (query by committee: the candidate whose measurement would rule "
        "out the members that leave the rest open; what stays open, summed over the other "
        "withheld cases; candidates: "
     << (user ? "your list of feasible points" : "the withheld cases")
     << "): " << (next.empty() ? "none" : next) << "\n\n";
  term << "withheld cases the training cases leave open (committee of laws that fit alike): "
       << (open.empty() ? "none" : open) << "\n"
       << "next case to measure (query by committee): " << (next.empty() ? "none" : next) << "\n";
  return {md.str(), term.str()};
}

/// The operating-point law fitted on all training cases at once (hgann/operating_law.h): its
/// terms, its prior, which parameters the data settle and which the prior, and each withheld
/// case's parameters' 1-σ under the law's posterior. Markdown and the terminal's lines.
std::pair<std::string, std::string> LawSection(const io::CaseSet& set,
                                               const hgann::HgannFitness& fitness,
                                               const IdentifyResult& result, int threads) {
  static constexpr const char* kSymbols[model::kNetworkOutputs] = {"μ", "δ",  "α", "β",
                                                                   "γ", "a1", "a2"};
  if (!result.seeds || !result.seeds->law.ok) return {"", ""};
  const hgann::OperatingLaw& law = result.seeds->law;
  const std::string prior = hgann::PriorSettledNames(law);
  std::string data;
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    if (law.data_settled[k]) data += (data.empty() ? "" : ", ") + std::string(kSymbols[k]);
  // Each parameter's terms beyond its level (OperatingLaw::active).
  static constexpr const char* kTerms[hgann::OperatingLaw::kMaxTerms] = {
      "", "V", "ln f", "V·f", "V curvature", "f curvature"};
  std::string terms;
  for (int k = 0; k < model::kNetworkOutputs; ++k) {
    std::string own;
    for (int t = 1; t < hgann::OperatingLaw::kMaxTerms; ++t)
      if (law.active[k][t]) own += (own.empty() ? "" : " + ") + std::string(kTerms[t]);
    terms += (k ? "; " : "") + std::string(kSymbols[k]) + ": ";
    terms += own.empty() ? "constant" : own;
  }
  terms += law.interaction ? " (the training cases determine a V·f interaction)"
                           : " (no V·f interaction: the training cases cannot show one)";
  // The shapes in f tried (OperatingLaw::kFPowers), the kept one's first.
  const auto shape_name = [](double power) {
    return power == 0 ? std::string("ln f") : power == 1 ? std::string("f") : "f^" + Fmt(power, 2);
  };
  std::string shapes;
  for (const auto& s : law.shapes)
    shapes += (shapes.empty() ? "" : ", ") + shape_name(s.f_power) + " " + Fmt(s.map_cost, 5);
  terms += "; shape in f: " + shape_name(law.f_power) + ", the one of the lowest MAP cost of " +
           shapes + " deg² (ln f stands for the shape in the terms)";
  std::ostringstream md, term;
  md << "## Operating-point law (all training cases at once)\n\n"
     << "One of generation 0's seeds (hgann/operating_law.h), each parameter a law of V and ln f "
        "with the terms its per-case estimates support (Akaike) — "
     << terms
     << " — fitted on every training case's data together by Levenberg–Marquardt on the "
        "fitness's own cost, with a Gaussian prior: each slope ~ N(0, (0.5 of the range)²) — "
        "the smoothest law unless the data pay for a slope — and each level ~ N(middle of the "
        "range, (0.5 of "
        "the range)²), so that a level the data leave open is not put at a bound; the prior "
        "weighted by the residuals' σ² = "
     << Fmt(law.sigma2, 3) << " deg² a sample (per-case fits, autocorrelation included). Cost "
     << Fmt(law.cost, 5) << " deg² (Σ PI over the training cases " << Fmt(law.data_cost, 5)
     << "), polished from " << law.start << ".\n\n"
     << "- settled by the data (every coefficient's posterior variance below "
     << Fmt(hgann::OperatingLaw::kPriorShare * 100, 3)
     << " % of its prior's): " << (data.empty() ? "none" : data) << "\n"
     << "- settled by the prior: " << (prior.empty() ? "none" : prior) << "\n\n"
     << "| case | role | V [V] | f [Hz] |";
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    md << " " << kSymbols[k] << " ± 1σ [" << model::OutputUnit(k) << "] |";
  md << "\n|---|---|---|---|---|---|---|---|---|---|---|\n";
  const model::Network& net = law.network;
  for (size_t i = 0; i < set.cases.size() && i < law.sigma_at_case.size(); ++i) {
    const auto& bc = set.cases[i];
    const auto p = net.Predict(bc.amplitude_v, bc.frequency_hz).ToArray();
    md << "| " << bc.number << " | " << io::CaseRoleName(bc.role) << " | " << Fmt(bc.amplitude_v)
       << " | " << Fmt(bc.frequency_hz) << " |";
    for (int k = 0; k < model::kNetworkOutputs; ++k)
      md << " " << Fmt(p[k], 3) << " ± " << Fmt(law.sigma_at_case[i][k], 2) << " |";
    md << "\n";
  }
  md << "\n";
  term << "operating-point law: " << terms
       << "; settled by the data: " << (data.empty() ? "none" : data)
       << "; by the prior: " << (prior.empty() ? "none" : prior) << " (cost " << Fmt(law.cost, 5)
       << " deg²; report.md)\n";
  return {md.str(), term.str()};
}

constexpr const char* kAtBoundMeaning =
    "on every training case: set by the range, not by the data, which may want it past the bound. "
    "Widen a "
    "range (a job spec's `ranges`) only as far as the physics allows: on the nominal bench, the ≈ "
    "2.3 deg² "
    "plateau where many runs stop has β at the top of its range and, mostly, α and γ near theirs, "
    "and wider "
    "ranges only moved the runs to the new tops (docs/performance.md, \"Islands\"); there, more "
    "islands or "
    "seeds are the way out.";

/// The islands' settings (migration, broadcast, mutation, restarts) and how often they migrated
/// and restarted, in report.md's GA line.
void WriteIslands(std::ostream& md, const opt::GaOptions& ga,
                  const std::vector<opt::GenerationSummary>& log) {
  md << " × " << ga.islands << " islands (";
  if (ga.migration_interval > 0) {
    md << ga.migrants << " migrants every " << ga.migration_interval << " generations, "
       << opt::TopologyName(ga.topology);
    if (ga.migration_margin > 0)
      md << ", from sources better by more than " << ga.migration_margin * 100 << " %";
  } else {
    md << "independent: multi-start";
  }
  if (ga.broadcast_interval > 0)
    md << "; a broadcast every " << ga.broadcast_interval
       << " generations from islands better by more than " << ga.broadcast_margin * 100 << " %";
  md << "; mutation by island";
  for (int k = 0; k < ga.islands; ++k) md << " " << ga.MutationProbability(k);
  if (ga.island_stall_generations > 0)
    md << "; an island is restarted after " << ga.island_stall_generations
       << " generations of stall";
  int migrations = 0, restarts = 0;
  for (const auto& g : log) {
    migrations += g.migrated;
    for (const auto& i : g.islands) restarts += i.restarted;
  }
  md << "; " << migrations << " migrations, " << restarts << " restarts)";
}

/// report.md.
std::string ReportMarkdown(const IdentifyOptions& options, const io::CaseSet& set,
                           const hgann::HgannFitness& fitness, const IdentifyResult& result,
                           const CaseTotals& t, const std::string& mu_regression,
                           const std::string& at_bound, const std::string& per_case) {
  const double train_sum = t.train_sum, all_sum = t.all_sum;
  const int beaten = t.beaten, compared = t.compared;
  std::ostringstream md;
  const auto& s = result.summary;
  int64_t penalized = 0, errors = 0;
  std::map<std::string, int64_t> reasons;
  for (const auto& g : result.log) {
    penalized += g.penalized;
    errors += g.errors;
    for (const auto& [k, n] : g.failure_reasons) reasons[k] += n;
  }
  md << "# HGANN identification of " << set.dir.string() << "\n\n"
     << "- best network: " << result.best.network.Describe() << "\n"
     << "- fitness CF = Σ PI over the training cases: " << Fmt(s.best_fitness.cost, 6)
     << " deg² (found in generation " << s.best_generation
     << (options.ga.islands > 1 ? ", island " + std::to_string(s.best_island) : std::string())
     << ")\n"
     << "- stopped: " << opt::GaTerminationName(s.termination) << " after " << s.generations
     << " generations (" << s.message
     << (s.termination == opt::GaTermination::kStall && options.ga.stall_relative > 0
             ? "; the rule: " + std::to_string(options.ga.stall_generations) +
                   " generations in which none lowers the best by more than a relative " +
                   Fmt(options.ga.stall_relative, 2) +
                   " — what the GA added to generation 0's "
                   "seeds in them, if anything, is below that"
             : std::string())
     << ")\n"
     << "- evaluations: " << s.evaluations << ", of which penalised " << penalized << " and errors "
     << errors;
  if (!reasons.empty()) {
    md << " (";
    bool first = true;
    for (const auto& [k, n] : reasons) {
      md << (first ? "" : ", ") << k << ": " << n;
      first = false;
    }
    md << ")";
  }
  md << "\n- GA: population " << options.ga.population_size;
  if (options.ga.islands > 1) WriteIslands(md, options.ga, result.log);
  if (const int moves = hgann::HgannOutputMoves(options.ga, options.spread_penalty); moves > 0)
    md << ", " << moves
       << " offspring per island and generation made by an output move (a step of the best "
       << "network's outputs in the parameter space)";
  md << ", seed " << options.ga.seed << ", ranges '" << options.ranges
     << "', spread penalty λ = " << options.spread_penalty << " deg² (final spread "
     << Fmt(fitness.OutputSpread(result.best.network), 3) << "), wall time "
     << Fmt(s.wall_time_s, 4) << " s"
     << (options.preset.empty() ? std::string() : "; preset '" + options.preset + "'") << "\n";
  if (result.seeds) {
    md << "- generation 0 seeded with " << result.seeds->genomes.size()
       << " networks fitted to per-case fits of the training cases (hgann/trend_seeds.h):";
    for (size_t i = 0; i < result.seeds->genomes.size(); ++i)
      md << (i ? "," : "") << " " << result.seeds->names[i] << " "
         << Fmt(result.seeds->costs[i], 5);
    md << " (cost, deg²; " << result.seeds->simulations << " case simulations, "
       << Fmt(result.seeds->wall_time_s, 3) << " s)\n";
  }
  md << "\n";
  if (options.ranges == "paper") {
    const auto& best = result.cases.front().params;
    md << "With the paper's Table 3 ranges (α, β, γ ≤ 0) every network with α ≠ 0 has an unbounded "
          "Bouc–Wen "
          "loop and is penalised ("
       << reasons["unbounded_hysteresis"]
       << " evaluations). The surviving networks "
          "put α exactly at the top of its range, α = "
       << Fmt(best.alpha, 3)
       << ": then z ≡ 0 and β, γ have no "
          "effect at all — which is why the paper found α = 0 in every case.\n\n";
  }
  md << "## Performance index per case (PI [deg²]; paper's Table 8 in brackets)\n\n"
     << Grid(set,
             [&](const io::BenchCase& c) {
               const double paper = PaperTable8Pi(c.amplitude_v, c.frequency_hz);
               return "case " + std::to_string(c.number) +
                      (c.role == io::CaseRole::kTrain ? "*" : "") + ": " +
                      Fmt(ResultOf(result, c.number).pi, 3) +
                      (std::isnan(paper) ? "" : " (" + Fmt(paper, 3) + ")");
             })
     << "\n\\* training case. Σ over training cases " << Fmt(train_sum, 5) << ", over all cases "
     << Fmt(all_sum, 5) << "; below the paper's value in " << beaten << " of " << compared
     << " cases.\n\n";
  md << "## Identified parameters per case (paper Tables 6, 7)\n\n"
     << "| case | role | V [V] | f [Hz] | μ [1/s] | δ [s] | α [N/V] | β [1/V] | γ [1/V] | a1 [deg] "
        "| a2 [deg] | b1 [deg] | b2 [deg] |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& bc : set.cases) {
    const auto& q = ResultOf(result, bc.number).params;
    md << "| " << bc.number << " | " << io::CaseRoleName(bc.role) << " | " << Fmt(bc.amplitude_v)
       << " | " << Fmt(bc.frequency_hz) << " | " << Fmt(q.mu, 5) << " | " << Fmt(q.delta, 4)
       << " | " << Fmt(q.alpha, 3) << " | " << Fmt(q.beta, 3) << " | " << Fmt(q.gamma, 3) << " | "
       << Fmt(q.a1, 3) << " | " << Fmt(q.a2, 3) << " | " << Fmt(q.b1, 3) << " | " << Fmt(q.b2, 3)
       << " |\n";
  }
  if (!at_bound.empty()) md << "\nHeld at a bound: " << at_bound << " " << kAtBoundMeaning << "\n";
  md << "\n" << per_case;
  auto param_grid = [&](const char* title, double model::BimorphParams::*field, int prec) {
    md << "\n### " << title << "\n\n"
       << Grid(set, [&](const io::BenchCase& c) {
            return Fmt(ResultOf(result, c.number).params.*field, prec);
          });
  };
  param_grid("δ over the grid (paper Table 9)", &model::BimorphParams::delta, 4);
  param_grid("μ over the grid (paper Table 10)", &model::BimorphParams::mu, 5);
  param_grid("a1 over the grid (paper Table 12)", &model::BimorphParams::a1, 3);
  param_grid("a2 over the grid (paper Table 13)", &model::BimorphParams::a2, 3);
  md << "\n## Regression of μ on V and f (paper eq. 7)\n\n"
     << mu_regression << "\n\n## Figures\n\n";
  md << "![fitness](fitness.png)\n\n";
  for (const auto& bc : set.cases)
    md << "![case " << bc.number << "](case" << bc.number << "_angle.png) ![loop " << bc.number
       << "](case" << bc.number << "_loop.png)\n";
  return md.str();
}

}  // namespace

std::string IslandCsvHeader(const std::vector<opt::GenerationSummary>& log) {
  if (log.empty() || log.front().islands.empty()) return "";
  std::string h = ",best_island,migrated,immigrants,restarted";
  for (size_t k = 0; k < log.front().islands.size(); ++k)
    h += ",island_" + std::to_string(k) + "_best";
  return h;
}

std::string IslandCsvCells(const opt::GenerationSummary& g) {
  if (g.islands.empty()) return "";
  int immigrants = 0, restarted = 0;
  for (const opt::IslandSummary& i : g.islands)
    immigrants += i.immigrants, restarted += i.restarted;
  std::ostringstream os;
  os << std::setprecision(17) << "," << g.best_island << "," << (g.migrated ? 1 : 0) << ","
     << immigrants << "," << restarted;
  for (const opt::IslandSummary& i : g.islands) os << "," << i.best_cost;
  return os.str();
}

std::string IslandsBrief(const opt::GenerationSummary& g) {
  if (g.islands.empty()) return "";
  double lo = g.islands.front().best_cost, hi = lo;
  for (const opt::IslandSummary& i : g.islands)
    lo = std::min(lo, i.best_cost), hi = std::max(hi, i.best_cost);
  char buf[128];
  std::snprintf(buf, sizeof buf, "  island %d/%zu (islands %.4g…%.4g)", g.best_island,
                g.islands.size(), lo, hi);
  return buf;
}

std::vector<fs::path> WriteIdentifyReport(const IdentifyOptions& options, const io::CaseSet& set,
                                          const hgann::HgannFitness& fitness,
                                          const IdentifyResult& result, std::ostream& term) {
  std::vector<fs::path> written;
  const fs::path out = options.out_dir;
  fs::create_directories(out / "traces");
  for (const char* name : {"network.pb", "network.json"}) {
    ThrowIfError(io::SaveNetwork(result.best, (out / name).string()));
    written.push_back(out / name);
  }
  WriteProgressCsv(out, result, written);
  const CaseTotals totals = WriteCaseTables(out, set, fitness, result, written);
  const std::string mu_regression = MuRegression(totals);
  const std::string at_bound = AtBoundList(fitness, result.best.network);
  const PerCaseCheck per_case = CheckAgainstPerCaseFits(options, set, fitness, result);
  const auto [extrapolation_md, extrapolation_term] =
      ExtrapolationSection(set, fitness, result, per_case.estimates);
  auto [law_md, law_term] =
      LawSection(set, fitness, result, std::max(1, options.threads > 0 ? options.threads : 2));
  // The committee's verdict (identify's, or the master's for a fetched job: the same), after the
  // law's section when there is one.
  if (result.committee) {
    const auto [committee_md, committee_term] = CommitteeSection(set, *result.committee);
    law_md += committee_md;
    law_term += committee_term;
  }
  std::vector<std::string> plot_errors;
  const size_t islands = result.log.empty() ? 0 : result.log.front().islands.size();
  const int rendered = WriteFigures(options, out, set, islands, written, &plot_errors);
  {
    std::ofstream f(out / "report.md");
    f << ReportMarkdown(options, set, fitness, result, totals, mu_regression, at_bound,
                        per_case.markdown + law_md + extrapolation_md);
    written.push_back(out / "report.md");
  }
  term << "\n"
       << result.summary.BriefReport() << "\n"
       << "best network " << result.best.network.Describe() << "\n\n"
       << "PI per case [deg²] (paper's Table 8 in brackets; * = training):\n"
       << Grid(set,
               [&](const io::BenchCase& c) {
                 const double paper = PaperTable8Pi(c.amplitude_v, c.frequency_hz);
                 return std::to_string(c.number) + (c.role == io::CaseRole::kTrain ? "*" : "") +
                        " " + Fmt(ResultOf(result, c.number).pi, 3) +
                        (std::isnan(paper) ? "" : " (" + Fmt(paper, 3) + ")");
               })
       << "below the paper in " << totals.beaten << " of " << totals.compared
       << " cases; Σ training " << Fmt(totals.train_sum, 5) << "\n"
       << mu_regression << "\n";
  if (!at_bound.empty())
    term << "held at a bound on every training case (set by the range, not the data; report.md): "
         << at_bound << "\n";
  term << per_case.terminal << law_term << extrapolation_term;
  for (const auto& e : plot_errors) term << "warning: " << e << "\n";
  term << "results in " << out.string()
       << " (report.md, network.pb/.json, progress.csv, validation.csv, "
       << "parameters.csv, " << rendered << " figures)\n";
  return written;
}

}  // namespace pz::reports
