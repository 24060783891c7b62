#include "reports/committee_report.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "committee.pb.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "records/registry.h"
#include "reports/plots.h"
#include "reports/record_windows.h"

namespace pz::reports {
using namespace complete;  // the committee's types and figures formatting

// ---- Report --------------------------------------------------------------------------------

namespace {

// A markdown table: one row per model, one column per band.
template <typename Value>
void BandTable(std::ostream& o, const std::string& title, const FrequencyBands& bands,
               const std::vector<const IdentifiedModel*>& rows, Value value,
               const std::vector<int>& mark = {}) {
  o << "**" << title << "**\n\n| model / optimiser |";
  for (int b = 0; b < bands.size(); ++b) o << " " << bands.Label(b) << " |";
  o << "\n|---|";
  for (int b = 0; b < bands.size(); ++b) o << "---:|";
  o << "\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    o << "| " << rows[i]->Name() << " |";
    for (int b = 0; b < bands.size(); ++b) {
      const bool m = !mark.empty() && mark[b] == static_cast<int>(i);
      o << " " << (m ? "**" : "") << value(*rows[i], b) << (m ? "**" : "") << " |";
    }
    o << "\n";
  }
  o << "\n";
}

void ParamTable(std::ostream& o, const std::vector<const IdentifiedModel*>& models,
                const FrequencyBands& bands, const std::string& family) {
  std::vector<std::string> names;
  for (const IdentifiedModel* m : models)
    if (m->family == family) {
      for (const auto& p : m->model->params()) names.push_back(p.name);
      for (const auto& w : m->model->family().weight_names()) names.push_back(w);
      break;
    }
  o << "| scope | optimiser |";
  for (const auto& n : names) o << " " << n << " |";
  o << " best cost | evaluations | wall [s] | evaluations/s | stop (best repetition) |\n|---|---|";
  for (size_t i = 0; i < names.size(); ++i) o << "---:|";
  o << "---:|---:|---:|---:|---|\n";
  for (const IdentifiedModel* m : models) {
    if (m->family != family) continue;
    o << "| " << (m->band < 0 ? std::string("complete") : bands.Label(m->band)) << " | "
      << opt::SearchAlgorithmName(m->algorithm) << " |";
    for (double p : m->params) o << " " << FormatFigure(p, 4) << " |";
    for (double w : m->weights) o << " " << FormatFigure(w, 4) << " |";
    o << " " << FormatFigure(m->search.best_cost, 4) << " | " << m->search.evaluations << " | "
      << FormatFigure(m->search.wall_time_s) << " | "
      << FormatFigure(m->search.evaluations / std::max(m->search.wall_time_s, 1e-9)) << " | "
      << m->search.stop_reason << " |\n";
  }
  o << "\n";
}

void MetricTables(std::ostream& o, const std::string& prefix, const FrequencyBands& bands,
                  const std::vector<const IdentifiedModel*>& rows, bool own_band_only,
                  const std::vector<int>& mark) {
  auto at = [&](const IdentifiedModel& m, int b) -> const BandMetrics* {
    if (own_band_only) return m.band == b ? &m.per_band[b] : nullptr;
    return &m.per_band[b];
  };
  auto cell = [&](auto get) {
    return [&, get](const IdentifiedModel& m, int b) -> std::string {
      const BandMetrics* bm = at(m, b);
      return bm ? FormatFigure(get(*bm)) : "";
    };
  };
  BandTable(o, prefix + ": IAE, training [µm·s]", bands, rows,
            cell([](const BandMetrics& x) { return x.train.iae; }), mark);
  BandTable(o, prefix + ": max error, training [µm]", bands, rows,
            cell([](const BandMetrics& x) { return x.train.max_abs; }), mark);
  BandTable(o, prefix + ": RMSE, training [µm]", bands, rows,
            cell([](const BandMetrics& x) { return x.train.rmse; }), mark);
  BandTable(o, prefix + ": RMSE, testing [µm]", bands, rows,
            cell([](const BandMetrics& x) { return x.test.rmse; }), mark);
  BandTable(o, prefix + ": max error, testing [µm]", bands, rows,
            cell([](const BandMetrics& x) { return x.test.max_abs; }), mark);
  BandTable(o, prefix + ": test/train ratio of the max error", bands, rows,
            cell([](const BandMetrics& x) { return x.test.max_abs / x.train.max_abs; }), mark);
  BandTable(o, prefix + ": test/train ratio of the RMSE", bands, rows,
            cell([](const BandMetrics& x) { return x.test.rmse / x.train.rmse; }), mark);
}

/// The report's sentences on the initial state at rest of the committee's families that take one
/// (--initial-state; each family's own: backlash-like's auto is centred), "" when none does.
std::string MemorySentence(const CommitteeResult& r) {
  std::string out;
  for (const std::string& f : r.options.families) {
    if (!records::TakesInitialState(f)) continue;
    const IdentifiedModel* m = nullptr;
    for (const auto& c : r.complete) m = !m && c.family == f ? &c : m;
    for (const auto& band : r.band_models)
      for (const auto& c : band) m = !m && c.family == f ? &c : m;
    if (m)
      out += (out.empty() ? "" : " ") +
             InitialStateSentence(m->model->family().initial_state(), "The " + f + " model starts");
  }
  return out;
}

/// The settings: records, bands, criterion, searches, memory at rest, the selection rule.
void WriteSettings(std::ostream& o, const CommitteeResult& r) {
  const io::RecordSet& set = r.set;
  const CommitteeOptions& opt = r.options;
  const FrequencyBands& bands = opt.bands;
  const int nb = bands.size();
  o << "# Committee machine on " << set.source.filename().string() << "\n\n";
  o << "Records: " << set.records.size() << " (" << set.WithRole(model::CaseRole::kTrain).size()
    << " training, " << set.WithRole(model::CaseRole::kTest).size() << " testing). Bands:";
  for (int b = 0; b < nb; ++b) o << " " << bands.Label(b) << (b + 1 < nb ? "," : ".");
  o << " Criterion " << records::CriterionName(opt.criterion) << " over t ∈ [" << opt.t0_s << ", "
    << opt.t1_s << "] s (clipped to each record's last sample), summed over the training records. "
    << opt.search.repetitions << " repetitions per search (seeds " << opt.search.pso.seed
    << ", … for PSO; " << opt.search.ga_real.seed << ", … for the real GA), best kept. PSO "
    << opt.search.pso.particles << " particles × " << opt.search.pso.iterations
    << " iterations (stall " << opt.search.pso.stall_iterations << "); real GA "
    << opt.search.ga_real.population << " × " << opt.search.ga_real.generations
    << " generations (stall " << opt.search.ga_real.stall_generations << "); binary GA "
    << opt.search.ga_binary.ga.population_size << " × " << opt.search.ga_binary.ga.max_generations
    << ", " << opt.search.ga_binary.bits_per_parameter << " bits/parameter. Bouc–Wen filter "
    << opt.family_options.substeps << " sub-step(s) per sample. " << r.threads
    << " evaluation thread(s).\n\n";
  if (const std::string s = MemorySentence(r); !s.empty()) o << s << "\n\n";
  o << "Selection per band: A = ½ (RMSE_train + RMSE_test) over the window, pooled over the band's "
       "records of each role; lowest A. Committee output: "
    << (opt.averaging ? "averaging (triangular memberships over the band centres)"
                      : "hard switch on the record's excitation frequency")
    << ".\n\n";
}

/// The complete models' tables (one parameter set over all bands), if any were fitted.
void WriteCompleteModels(std::ostream& o, const CommitteeResult& r) {
  const CommitteeOptions& opt = r.options;
  const FrequencyBands& bands = opt.bands;
  std::vector<const IdentifiedModel*> complete;
  for (const auto& m : r.complete) complete.push_back(&m);
  if (!complete.empty()) {
    o << "## Complete models (one parameter set over all bands; cf. the paper's Tables 1–10)\n\n";
    for (const std::string& f : opt.families) ParamTable(o, complete, bands, f);
    MetricTables(o, "Complete", bands, complete, false, {});
    o << "| complete model | test RMSE, all test records [µm] | test max error [µm] |\n"
         "|---|---:|---:|\n";
    for (const auto* m : complete)
      o << "| " << m->Name() << (m == complete[r.best_complete] ? " (best)" : "") << " | "
        << FormatFigure(m->all_test.rmse) << " | " << FormatFigure(m->all_test.max_abs) << " |\n";
    o << "\n";
  }
}

/// The committee's sub-models (one parameter set per band): parameters and per-band metrics.
void WriteSubModels(std::ostream& o, const CommitteeResult& r) {
  const CommitteeOptions& opt = r.options;
  const FrequencyBands& bands = opt.bands;
  const int nb = bands.size();
  o << "## Committee sub-models (one parameter set per band; cf. the paper's Tables 11–16)\n\n";
  std::vector<const IdentifiedModel*> all_band;
  for (const auto& v : r.band_models)
    for (const auto& m : v) all_band.push_back(&m);
  for (const std::string& f : opt.families) ParamTable(o, all_band, bands, f);
  // One row per family/optimiser, the cell of band b from band b's sub-model.
  const size_t per = r.band_models.empty() ? 0 : r.band_models[0].size();
  std::vector<const IdentifiedModel*> rows;
  std::vector<std::vector<const IdentifiedModel*>> cells(per);
  for (size_t i = 0; i < per; ++i) {
    rows.push_back(&r.band_models[0][i]);
    for (int b = 0; b < nb; ++b) cells[i].push_back(&r.band_models[b][i]);
  }
  auto sub = [&](auto get) {
    return [&, get](const IdentifiedModel& m, int b) -> std::string {
      const size_t i = static_cast<size_t>(&m - &r.band_models[0][0]);
      return FormatFigure(get(cells[i][b]->per_band[b]));
    };
  };
  const std::vector<int>& mark = r.selected;
  BandTable(o, "Committee: IAE, training [µm·s]", bands, rows,
            sub([](const BandMetrics& x) { return x.train.iae; }), mark);
  BandTable(o, "Committee: max error, training [µm]", bands, rows,
            sub([](const BandMetrics& x) { return x.train.max_abs; }), mark);
  BandTable(o, "Committee: RMSE, training [µm]", bands, rows,
            sub([](const BandMetrics& x) { return x.train.rmse; }), mark);
  BandTable(o, "Committee: RMSE, testing [µm]", bands, rows,
            sub([](const BandMetrics& x) { return x.test.rmse; }), mark);
  BandTable(o, "Committee: max error, testing [µm]", bands, rows,
            sub([](const BandMetrics& x) { return x.test.max_abs; }), mark);
  BandTable(o, "Committee: test/train ratio of the max error", bands, rows,
            sub([](const BandMetrics& x) { return x.test.max_abs / x.train.max_abs; }), mark);
  BandTable(o, "Committee: test/train ratio of the RMSE", bands, rows,
            sub([](const BandMetrics& x) { return x.test.rmse / x.train.rmse; }), mark);
  BandTable(o,
            "Committee: selection aggregate A = ½ (RMSE_train + RMSE_test) [µm] (selected in bold)",
            bands, rows,
            sub([](const BandMetrics& x) { return 0.5 * (x.train.rmse + x.test.rmse); }), mark);
}

/// The selection per band and the committee against the best complete model.
void WriteSelection(std::ostream& o, const CommitteeResult& r) {
  const CommitteeOptions& opt = r.options;
  const FrequencyBands& bands = opt.bands;
  const int nb = bands.size();
  o << "## Selection and the committee against the complete model\n\n";
  o << "| band | selected | A [µm] | committee test RMSE [µm] | committee test max [µm] |";
  if (r.best_complete >= 0)
    o << " best complete test RMSE [µm] | best complete test max [µm] | RMSE reduction |";
  o << "\n|---|---|---:|---:|---:|";
  if (r.best_complete >= 0) o << "---:|---:|---:|";
  o << "\n";
  for (int b = 0; b < nb; ++b) {
    const BandMetrics& c = r.committee_per_band[b];
    o << "| " << bands.Label(b) << " | " << r.band_models[b][r.selected[b]].Name() << " | "
      << FormatFigure(r.aggregate[b]) << " | " << FormatFigure(c.test.rmse) << " | "
      << FormatFigure(c.test.max_abs) << " |";
    if (r.best_complete >= 0) {
      const BandMetrics& x = r.complete[r.best_complete].per_band[b];
      o << " " << FormatFigure(x.test.rmse) << " | " << FormatFigure(x.test.max_abs) << " | "
        << FormatPercent(1 - c.test.rmse / x.test.rmse) << " |";
    }
    o << "\n";
  }
  o << "\nAll test records: committee RMSE " << FormatFigure(r.committee_test.rmse)
    << " µm, max error " << FormatFigure(r.committee_test.max_abs) << " µm";
  if (r.best_complete >= 0) {
    const RoleMetrics& c = r.complete[r.best_complete].all_test;
    o << "; best complete model (" << r.complete[r.best_complete].Name() << ") RMSE "
      << FormatFigure(c.rmse) << " µm, max error " << FormatFigure(c.max_abs)
      << " µm. **Error reduction of the "
      << "committee: " << FormatPercent(r.rmse_reduction) << " in RMSE, "
      << FormatPercent(r.max_reduction) << " in max error.**";
  }
}

/// Wall time and evaluations per scope.
void WriteTiming(std::ostream& o, const CommitteeResult& r) {
  const CommitteeOptions& opt = r.options;
  const FrequencyBands& bands = opt.bands;
  const int nb = bands.size();
  o << "\n\n## Timing\n\n| scope | wall [s] | evaluations | evaluations/s "
       "|\n|---|---:|---:|---:|\n";
  auto evals = [](const std::vector<IdentifiedModel>& v) {
    int64_t e = 0;
    for (const auto& m : v) e += m.search.evaluations;
    return e;
  };
  if (!r.complete.empty()) {
    const int64_t e = evals(r.complete);
    o << "| complete | " << FormatFigure(r.complete_wall_s) << " | " << e << " | "
      << FormatFigure(e / std::max(r.complete_wall_s, 1e-9)) << " |\n";
  }
  for (int b = 0; b < nb; ++b) {
    const int64_t e = evals(r.band_models[b]);
    o << "| " << bands.Label(b) << " | " << FormatFigure(r.band_wall_s[b]) << " | " << e << " | "
      << FormatFigure(e / std::max(r.band_wall_s[b], 1e-9)) << " |\n";
  }
  o << "| total | " << FormatFigure(r.wall_s) << " | " << r.evaluations << " | "
    << FormatFigure(r.evaluations / std::max(r.wall_s, 1e-9)) << " |\n";
}

}  // namespace

void WriteCommitteeReport(std::ostream& o, const CommitteeResult& r) {
  WriteSettings(o, r);
  WriteCompleteModels(o, r);
  WriteSubModels(o, r);
  WriteSelection(o, r);
  WriteTiming(o, r);
}

// ---- JSON ----------------------------------------------------------------------------------
// committee.json: the study as its message (proto/committee.proto), printed by io/proto_json.h.

namespace {

void ErrorsOf(const RoleMetrics& m, proto::CommitteeErrors* o) {
  o->set_records(m.records);
  o->set_samples(static_cast<int64_t>(m.samples));
  o->set_iae_um_s(m.iae);
  o->set_rmse_um(m.rmse);
  o->set_max_abs_um(m.max_abs);
}

void BandErrorsOf(const std::string& band, const BandMetrics& m, proto::CommitteeBandErrors* o) {
  o->set_band(band);
  ErrorsOf(m.train, o->mutable_train());
  ErrorsOf(m.test, o->mutable_test());
}

void ModelOf(const IdentifiedModel& m, const FrequencyBands& bands, proto::CommitteeModel* o) {
  o->set_family(m.family);
  if (records::TakesInitialState(m.family))
    o->set_initial_state(model::InitialStateName(m.model->family().initial_state()));
  o->set_optimiser(opt::SearchAlgorithmName(m.algorithm));
  o->set_scope(m.band < 0 ? "complete" : bands.Label(m.band));
  auto& p = *o->mutable_parameters();
  const auto& params = m.model->params();
  for (size_t i = 0; i < params.size(); ++i) p[params[i].name] = m.params[i];
  const auto weights = m.model->family().weight_names();
  for (size_t i = 0; i < weights.size() && i < m.weights.size(); ++i) p[weights[i]] = m.weights[i];
  o->set_best_cost(m.search.best_cost);
  o->set_evaluations(m.search.evaluations);
  o->set_wall_time_s(m.search.wall_time_s);
  o->set_stop_reason(m.search.stop_reason);
  o->set_best_repetition(m.search.best_repetition);
  o->mutable_repetition_costs()->Assign(m.search.repetition_costs.begin(),
                                        m.search.repetition_costs.end());
  for (int b = 0; b < bands.size(); ++b)
    if (m.band < 0 || m.band == b) BandErrorsOf(bands.Label(b), m.per_band[b], o->add_per_band());
  ErrorsOf(m.all_test, o->mutable_all_test());
}

}  // namespace

void CommitteeOf(const CommitteeResult& r, proto::CommitteeFile* out) {
  const CommitteeOptions& opt = r.options;
  proto::CommitteeFile f;
  f.set_records_dir(r.set.source.filename().string());
  f.mutable_band_edges_hz()->Assign(opt.bands.edges.begin(), opt.bands.edges.end());
  f.set_criterion(records::CriterionName(opt.criterion));
  f.set_initial_state(model::InitialStateName(opt.family_options.initial_state));
  f.add_window_s(opt.t0_s);
  f.add_window_s(opt.t1_s);
  f.set_repetitions(opt.search.repetitions);
  f.set_committee(opt.averaging ? "averaging" : "hard switch");
  f.set_selection_aggregate("0.5 * (rmse_train + rmse_test)");
  for (const auto& m : r.complete) ModelOf(m, opt.bands, f.add_complete_models());
  for (int b = 0; b < opt.bands.size(); ++b) {
    proto::CommitteeBand& g = *f.add_bands();
    g.set_band(opt.bands.Label(b));
    for (const auto& m : r.band_models[b]) ModelOf(m, opt.bands, g.add_models());
    g.set_selected(r.band_models[b][r.selected[b]].Name());
    g.set_aggregate_um(r.aggregate[b]);
    ErrorsOf(r.committee_per_band[b].train, g.mutable_committee_train());
    ErrorsOf(r.committee_per_band[b].test, g.mutable_committee_test());
    g.set_wall_time_s(r.band_wall_s[b]);
  }
  ErrorsOf(r.committee_test, f.mutable_committee_test());
  ErrorsOf(r.committee_train, f.mutable_committee_train());
  if (r.best_complete >= 0) {
    f.set_best_complete(r.complete[r.best_complete].Name());
    ErrorsOf(r.complete[r.best_complete].all_test, f.mutable_best_complete_test());
    f.set_rmse_reduction(r.rmse_reduction);
    f.set_max_error_reduction(r.max_reduction);
  }
  f.set_evaluations(r.evaluations);
  f.set_wall_time_s(r.wall_s);
  f.set_threads(r.threads);
  *out = std::move(f);
}

std::string CommitteeJson(const CommitteeResult& r) {
  proto::CommitteeFile f;
  CommitteeOf(r, &f);
  return io::PrintJson(f, "committee.json");
}

// ---- Figures -------------------------------------------------------------------------------

std::vector<std::string> WriteCommitteeFigures(const std::string& dir, const CommitteeResult& r,
                                               std::vector<std::string>* warnings) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  std::vector<fs::path> scripts;
  const IdentifiedModel* complete = r.best_complete >= 0 ? &r.complete[r.best_complete] : nullptr;
  for (const io::Record& rec : r.set.records) {
    if (rec.role != model::CaseRole::kTest) continue;
    const int b = r.options.bands.BandOf(rec.frequency_hz);
    const auto cm = PredictCommittee(r, rec);
    std::vector<double> full;
    if (complete) full = PredictModel(*complete, rec);
    // The last whole drive cycle of the record's window.
    const size_t n = rec.end_scored;
    const size_t per = std::max<size_t>(
        2, static_cast<size_t>(std::lround(rec.sample_rate_hz() / rec.frequency_hz)));
    const size_t first = n > per + 1 ? n - per - 1 : 0;
    const std::string stem =
        "loop_band" + std::to_string(b + 1) + "_f" + io::FormatNumber(rec.frequency_hz);
    io::WriteFileWith(fs::path(dir) / (stem + ".csv"), [&](std::ostream& os) {
      os << "voltage_V,measured_um,committee_um" << (complete ? ",complete_um" : "") << "\n";
      for (size_t k = first; k < n; ++k) {
        os << io::FormatNumber(rec.u[k]) << "," << io::FormatNumber(rec.y[k]) << ","
           << io::FormatNumber(cm[k]);
        if (complete) os << "," << io::FormatNumber(full[k]);
        os << "\n";
      }
    });
    Plot p;
    p.name = stem;
    p.title = "Band " + r.options.bands.Label(b) + ": " + rec.Label() + " at " +
              io::FormatNumber(rec.frequency_hz) + " Hz, last cycle";
    p.xlabel = "voltage [V]";
    p.ylabel = "displacement [µm]";
    p.series.push_back({stem + ".csv", 1, 2, "measured", "points pt 7 ps 0.4"});
    p.series.push_back({stem + ".csv", 1, 3,
                        "committee (" + r.band_models[b][r.selected[b]].Name() + ")", "lines"});
    if (complete)
      p.series.push_back({stem + ".csv", 1, 4, "complete (" + complete->Name() + ")", "lines"});
    scripts.push_back(WritePlotScript(dir, p));
  }
  if (GnuplotAvailable()) {
    RenderPlots(dir, scripts, warnings);
  } else if (warnings) {
    warnings->push_back("gnuplot not found: render the figures with `gnuplot <name>.gp` in " + dir);
  }
  std::vector<std::string> out;
  for (const auto& s : scripts) out.push_back(s.string());
  return out;
}

}  // namespace pz::reports
