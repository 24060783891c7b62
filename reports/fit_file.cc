#include "reports/fit_file.h"

#include <algorithm>
#include <cmath>

#include "fit.pb.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "records/extrapolation.h"
#include "records/registry.h"
#include "reports/excitation_report.h"
#include "reports/select_report.h"

namespace pz::reports {
namespace {

/// The model → its stored message (the one conversion this way).
proto::FitModel ToProto(const records::ModelSpec& s) {
  proto::FitModel f;
  f.set_family(s.family);
  f.set_substeps(s.substeps);
  f.set_pi_operators(s.pi_operators);
  auto* sc = f.mutable_scale();
  sc->set_u_min(s.scale.u_min);
  sc->set_u_max(s.scale.u_max);
  sc->set_u_half(s.scale.u_half);
  sc->set_y_half(s.scale.y_half);
  sc->set_gain(s.scale.gain);
  sc->set_polarity(s.scale.polarity);
  sc->set_f_dom_hz(s.scale.f_dom);
  sc->set_fs_hz(s.scale.fs);
  sc->set_duration_s(s.scale.duration);
  f.set_sample_period_s(s.dt);
  for (records::EffectKind e : s.effects) f.add_effects(records::EffectName(e));
  const auto model = s.Model();
  for (size_t i = 0; i < s.params.size(); ++i) {
    auto* p = f.add_params();
    p->set_name(model->params()[i].name);
    p->set_value(s.params[i]);
  }
  for (double w : s.weights) f.add_weights(w);
  f.set_polarity(s.polarity);
  f.set_offset(s.offset);
  f.set_drive_min(s.drive_min);
  f.set_drive_max(s.drive_max);
  f.set_drive_unit(s.drive_unit);
  f.set_response_unit(s.response_unit);
  f.set_initial_state(model::InitialStateName(s.initial_state));
  return f;
}

/// The stored message → the model, checked (the one conversion this way). Throws InputError
/// naming the field.
records::ModelSpec FromProto(const proto::FitModel& m) {
  records::ModelSpec s;
  s.family = m.family();
  s.substeps = m.substeps();
  s.pi_operators = m.pi_operators();
  const auto& sc = m.scale();
  s.scale = {.u_min = sc.u_min(),
             .u_max = sc.u_max(),
             .u_half = sc.u_half(),
             .y_half = sc.y_half(),
             .gain = sc.gain(),
             .polarity = sc.polarity(),
             .f_dom = sc.f_dom_hz(),
             .fs = sc.fs_hz(),
             // Files written before duration_s was stored: the default scale's 1 s (it set only
             // drift's range then).
             .duration = sc.duration_s() > 0 ? sc.duration_s() : 1.0};
  for (double v : {s.scale.u_min, s.scale.u_max, s.scale.u_half, s.scale.y_half, s.scale.f_dom,
                   s.scale.fs, s.scale.duration}) {
    if (!std::isfinite(v)) throw InputError("model.scale holds a value that is not finite");
  }
  if (!(s.scale.u_half > 0 && s.scale.y_half > 0 && s.scale.fs > 0 && s.scale.f_dom > 0)) {
    throw InputError("model.scale: u_half, y_half, f_dom_hz and fs_hz must be > 0");
  }
  s.dt = m.sample_period_s();
  records::FamilyNamed(s.family, "model.family");
  for (const auto& e : m.effects()) {
    try {
      s.effects.push_back(records::ParseEffect(e));
    } catch (const InputError& x) {
      throw InputError(std::string("model.effects: ") + x.what());
    }
  }
  // Empty (a fit.json written before the field, fitted centred): centred.
  s.initial_state = model::ParseInitialState(
      m.initial_state().empty() ? "centred" : m.initial_state(), "model.initial_state");
  const auto rm = s.Model();  // the family and its options, checked
  if (static_cast<size_t>(m.params_size()) != rm->params().size()) {
    throw InputError("model.params: " + std::to_string(m.params_size()) + " values for " +
                     rm->Describe() + ", " + std::to_string(rm->params().size()) + " expected");
  }
  for (int i = 0; i < m.params_size(); ++i) {
    const std::string& want = rm->params()[i].name;
    if (m.params(i).name() != want) {
      throw InputError("model.params[" + std::to_string(i) + "].name '" + m.params(i).name() +
                       "': expected '" + want + "' for " + rm->Describe());
    }
    s.params.push_back(m.params(i).value());
  }
  s.weights.assign(m.weights().begin(), m.weights().end());
  s.polarity = m.polarity();
  s.offset = m.offset();
  s.drive_min = m.drive_min();
  s.drive_max = m.drive_max();
  s.drive_unit = m.drive_unit();
  s.response_unit = m.response_unit();
  if (s.drive_unit.empty() || s.response_unit.empty())
    throw InputError("model.drive_unit / response_unit: empty");
  s.Validate();
  return s;
}

}  // namespace

records::ModelSpec FittedModelSpec(const io::RecordSet& set, const records::FitResult& r,
                                   int substeps, int pi_operators) {
  const records::RecordModel& m = *r.model;
  records::ModelSpec s;
  s.family = m.family().name();
  s.initial_state = m.family().initial_state();
  s.substeps = substeps;
  s.pi_operators = pi_operators;
  s.scale = m.scale();
  double offset = 0;
  int train = 0;
  for (size_t i = 0; i < set.records.size(); ++i) {
    if (set.records[i].role != model::CaseRole::kTrain) continue;
    offset += r.metrics[i].offset;
    if (train == 0) s.dt = set.records[i].dt;
    ++train;
  }
  s.effects = m.effects();
  s.params = r.params;
  s.weights = r.weights;
  s.polarity = s.scale.polarity;
  s.offset = train > 0 ? offset / train : 0.0;
  s.drive_min = s.scale.u_min;
  s.drive_max = s.scale.u_max;
  s.drive_unit = set.drive_unit;
  s.response_unit = set.response_unit;
  return s;
}

double TrainMeanOutput(const io::RecordSet& set) {
  double sum = 0;
  size_t n = 0;
  for (const io::Record& r : set.records) {
    if (r.role != model::CaseRole::kTrain) continue;
    for (size_t k = r.first_scored; k < r.end_scored; ++k) sum += r.y[k];
    n += r.end_scored - r.first_scored;
  }
  return n > 0 ? sum / static_cast<double>(n) : NAN;
}

namespace {

void AddErrors(const records::FitResult& r, proto::FitFile* f) {
  for (const records::RecordMetrics& e : r.metrics) {
    proto::FitRecordErrors& g = *f->add_records();
    g.set_name(e.name);
    g.set_role(model::CaseRoleName(e.role));
    g.set_samples(static_cast<int64_t>(e.samples));
    g.set_offset(e.offset);
    g.set_rmse(e.rmse);
    g.set_max_abs(e.max_abs);
    g.set_max_at_s(e.max_at_s);
    g.set_nrmse_pct(e.nrmse_pct);
  }
}

void AddRegularisation(const records::FitResult& r, proto::FitFile* f) {
  if (r.resolution.used) {
    f->mutable_resolution()->set_levels(r.resolution.value());
    f->mutable_resolution()->set_description(r.resolution.Describe());
  }
  if (r.regularisation.used) {
    proto::FitRegularisation& g = *f->mutable_regularisation();
    g.set_relative(r.regularisation.relative);
    g.set_lambda(r.regularisation.lambda);
    if (!r.regularisation.penalty_name.empty()) g.set_penalty(r.regularisation.penalty_name);
  }
  if (r.spectrum_regularisation.used) {
    proto::FitSpectrumRegularisation& g = *f->mutable_spectrum_regularisation();
    g.set_relative(r.spectrum_regularisation.relative);
    g.set_lambda(r.spectrum_regularisation.lambda);
    g.set_not_identified(r.SpectrumIdentification());
  }
}

void AddUncertainty(const records::FitResult& r,
                    const std::vector<records::ExtrapolationCheck>& extrapolation,
                    proto::FitFile* f) {
  for (const records::ExtrapolationCheck& c : extrapolation) {
    proto::FitExtrapolation& x = *f->add_extrapolation();
    x.set_record(c.record);
    x.set_flagged(c.flagged);
    x.set_drive_beyond(c.drive_beyond);
    x.set_drive_beyond_share(c.drive_beyond_share);
    x.set_terms(static_cast<int64_t>(c.terms));
    x.set_term_max(c.term_max);
    x.set_term_rms(c.term_rms);
  }
  for (const auto& e : r.uncertainty.params) {
    proto::FitUncertainty& g = *f->add_uncertainty();
    g.set_name(e.name);
    g.set_value(e.value);
    if (std::isfinite(e.std_error)) g.set_std_error(e.std_error);
    g.set_sensitivity(e.sensitivity);
    g.set_identifiability(opt::IdentifiabilityName(e.identifiability));
    if (!e.note.empty()) g.set_note(e.note);
  }
  for (double v : r.uncertainty.singular_values) f->add_singular_values(v);
}

void AddSearch(const records::FitResult& r, const std::string& summary, proto::FitSearch* x) {
  x->set_algorithm(opt::SearchAlgorithmName(r.algorithm));
  x->set_searched_parameters(static_cast<int64_t>(r.searched_parameters));
  x->set_sized(r.budget_sized);
  x->set_repetitions(r.budget.repetitions);
  x->set_spectrum_solved(r.spectrum_solved);
  if (r.spectrum_solved) x->set_solved_parameters(static_cast<int64_t>(r.solved_parameters));
  if (r.algorithm == opt::SearchAlgorithm::kPso) {
    x->set_particles(r.budget.particles);
    x->set_iterations(r.budget.iterations);
    x->set_stall(r.budget.stall);
    x->set_converged_spread(r.budget.converged_spread);
  } else if (r.algorithm == opt::SearchAlgorithm::kLine) {
    x->set_grid(r.line.grid);
    x->set_brackets(r.line.brackets);
    x->set_tolerance(r.line.tolerance);
  }
  x->set_search_evaluations(r.search.evaluations);
  x->set_stop_reason(r.stop_reason);
  x->set_polishes(r.polishes);
  x->set_best_polish_repetition(r.best_polish_repetition + 1);  // 1-based; 0 = none
  x->set_search_best_repetition(r.search.best_repetition + 1);
  x->set_lm_differences(r.lm_differences);
  x->set_summary(summary);
}

}  // namespace

std::string FitJson(const io::RecordSet& set, const records::FitResult& r,
                    const records::ExcitationReport& excitation,
                    const records::TrainingDriveProposal& proposal,
                    const std::vector<records::ExtrapolationCheck>& extrapolation,
                    const records::SelectionResult* selection, const FitRun& run) {
  proto::FitFile f;
  const int levels = r.resolution.used ? r.resolution.value() : run.pi_operators;
  *f.mutable_model() = ToProto(FittedModelSpec(set, r, run.substeps, levels));
  if (const double mean = TrainMeanOutput(set); std::isfinite(mean))
    f.mutable_model()->set_train_mean_output(mean);
  f.set_description(r.model->Describe());
  f.set_settle_s(run.settle_s);
  AddErrors(r, &f);
  AddRegularisation(r, &f);
  AddUncertainty(r, extrapolation, &f);
  f.set_train_mse(r.train_mse);
  f.set_evaluations(r.evaluations);
  AddSearch(r, run.search, f.mutable_search());
  ExcitationOf(set, excitation, proposal, run.drive_file, f.mutable_excitation());
  if (selection) SelectionOf(*selection, f.mutable_selection());
  return io::WriteFitFile(f);
}

std::string FitModelJson(const records::ModelSpec& m) {
  proto::FitModel p = ToProto(m);
  p.set_format_version(io::kFitFormatVersion);
  return io::PrintJson(p, "fit.json's model");
}

bool LooksLikeFitJson(const std::string& path) {
  try {
    return io::LooksLikeFitJson(io::ReadTextFile(path));
  } catch (const InputError&) {
    return false;
  }
}

records::ModelSpec LoadFit(const std::string& path, std::optional<double>* train_mean_output) {
  return LoadFitText(path, io::ReadTextFile(path), train_mean_output);
}

records::ModelSpec LoadFitText(const std::string& path, const std::string& text,
                               std::optional<double>* train_mean_output) {
  proto::FitModel m;
  io::ReadFitModel(path, text, &m);
  if (train_mean_output) {
    train_mean_output->reset();
    if (m.has_train_mean_output()) *train_mean_output = m.train_mean_output();
  }
  try {
    return FromProto(m);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
}

}  // namespace pz::reports
