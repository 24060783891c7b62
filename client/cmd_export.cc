// `piezoid export PATH`: a fit.json of `piezoid fit` as a self-contained C99 header of its model
// (controller/export_header.h), or a network file of `identify` / `fetch` as a C function
// (controller/export_c.h), with --plant the bimorph fin plant beside it
// (controller/export_fin_c.h).
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "client/commands.h"
#include "client/service_flags.h"
#include "controller/export_c.h"
#include "controller/export_header.h"
#include "hgann/hgann_job.h"
#include "io/csv.h"
#include "model/modal_simulator.h"
#include "records/stepper.h"
#include "reports/fit_file.h"
#include "svcclient/job_file.h"

namespace pz::client {
namespace fs = std::filesystem;
namespace {

/// A fit.json (piezoid fit): the fitted model as a self-contained C99 header
/// (controller/export_header.h) written to `out` (stdout when empty), its functions named
/// `name_flag` (default: out's stem). Throws InputError on a bad fit.json.
int ExportFit(const std::string& fit_json, const std::string& out, const std::string& name_flag) {
  const records::ModelSpec m = reports::LoadFit(fit_json);
  records::Stepper st(m);
  std::string name = name_flag;
  if (name.empty()) {
    name = out.empty() ? "piezoid_model" : fs::path(out).stem().string();
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) name = "pz_" + name;
  }
  const std::string header =
      controller::ExportHeader(st, name, m.Model()->Describe() + " from " + fit_json);
  if (out.empty()) {
    std::cout << header;
    return kExitOk;
  }
  io::WriteFileWith(out, [&](std::ostream& os) { os << header; });
  std::cerr << "piezoid: wrote " << out << ": " << name << "_init, " << name << "_step, " << name
            << "_inverse_step (" << m.Model()->Describe() << ")\n";
  return kExitOk;
}

struct ExportOptions {
  std::string network, out, name = "piezoid_predict", job;
  bool plant = false;
  controller::FinPlantExport fin;
};

/// The beam of the job spec `file` (its hgann.geometry overrides), and its cases' saturations as a
/// note for the header.
int JobBeam(const std::string& file, model::BeamGeometry* geometry, std::string* note) {
  job::JobSpec spec;
  std::vector<job::FieldViolation> v;
  Status s = svcclient::LoadJobSpecFile(file, &spec, &v);
  if (!s.ok()) return ReportViolations("job spec " + file, v, s);
  const auto* h = std::get_if<job::HgannProblem>(&spec.problem);
  if (!h)
    return ReportStatus(InvalidArgument(FieldError("--job", file, "is not an hgann job spec")));
  hgann::HgannFitnessConfig config;
  if (s = hgann::HgannConfigFromProblem(*h, &config); !s.ok()) return ReportStatus(s);
  *geometry = config.geometry;
  std::ostringstream n;
  n << "The beam of job spec " << fs::path(file).filename().string()
    << "; its cases' saturations [deg]";
  for (const auto& c : config.cases)
    n << (&c == &config.cases.front() ? ": " : ", ") << "case " << c.number << " ("
      << c.drive.amplitude_v << " V, " << c.drive.frequency_hz << " Hz) b1 " << CDecimal(c.b1)
      << " b2 " << CDecimal(c.b2);
  *note = n.str() + ".";
  return kExitOk;
}

/// The file `piezoid export` reads for PATH: PATH itself, or for a folder the first of fit.json
/// (piezoid fit), network.pb (identify; fetch of an hgann job) and networks/best-1.pb (fetch).
std::string ExportSource(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return path;
  for (const char* name : {"fit.json", "network.pb", "networks/best-1.pb"}) {
    const fs::path p = fs::path(path) / name;
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  throw InputError(
      path +
      ": a folder without fit.json, network.pb or networks/best-1.pb (what piezoid fit, identify "
      "and fetch write)");
}

int ExportNetwork(const ExportOptions& o) {
  const std::string source = ExportSource(o.network);
  // A fit.json (piezoid fit): the record model's header.
  if (reports::LooksLikeFitJson(source))
    return ExportFit(source, o.out, o.name == "piezoid_predict" ? "" : o.name);
  io::SavedNetwork net;
  Status s = io::LoadNetwork(source, &net);
  if (!s.ok()) return ReportStatus(InvalidArgument(s.message()));
  std::string header;
  if (o.plant) {
    model::BeamGeometry geometry;  // the spec's beam, as the HGANN fitness's default …
    controller::FinPlantExport fin = o.fin;
    if (!o.job.empty()) {  // … or the job's
      if (int code = JobBeam(o.job, &geometry, &fin.note); code != kExitOk) return code;
    }
    const model::BimorphPlant plant(geometry);
    const model::ModalSimulator sim(plant);
    s = controller::NetworkAndFinToCHeader(net, sim, fin, o.name, &header);
  } else {
    s = controller::NetworkToCHeader(net, o.name, &header);
  }
  if (!s.ok()) return ReportStatus(s);
  if (o.out.empty()) {
    std::fwrite(header.data(), 1, header.size(), stdout);
    return kExitOk;
  }
  if (int code = WriteTextFile(o.out, header); code != kExitOk) return code;
  if (o.plant)
    std::fprintf(stderr,
                 "piezoid: wrote %s: %s_params, %s_init, %s_step, %s_inverse_step at %g Hz\n",
                 o.out.c_str(), o.name.c_str(), o.name.c_str(), o.name.c_str(), o.name.c_str(),
                 o.fin.sample_rate_hz);
  else
    std::fprintf(stderr, "piezoid: wrote %s: %s(amplitude_v, frequency_hz, p[7])\n", o.out.c_str(),
                 o.name.c_str());
  return kExitOk;
}

}  // namespace

void RegisterExport(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ExportOptions>();
  auto* c = app.add_subcommand("export",
                               "write a network file (.pb or .json) or a fit.json (piezoid fit) as "
                               "a standalone C header for a controller");
  c->add_option("network", o->network,
                "network file (from fetch or identify), fit.json of piezoid fit, or their folder "
                "(fit.json, network.pb or "
                "networks/best-1.pb in it)")
      ->required();
  c->add_option("--out,-o", o->out, "header file to write (default: stdout)");
  c->add_option("--name", o->name,
                "name of the C function (a C identifier; for a fit.json the prefix of its "
                "functions, default the header's file stem)")
      ->capture_default_str();
  auto* plant = c->add_flag("--plant", o->plant,
                            "add the bimorph-fin plant (spec beam) as a per-sample recursion: "
                            "NAME_init, NAME_step (drive -> angle), "
                            "NAME_inverse_step (angle -> drive)");
  c->add_option("--sample-rate", o->fin.sample_rate_hz,
                "the controller's sample rate [Hz] (with --plant)")
      ->needs(plant)
      ->capture_default_str();
  c->add_option("--drive-limit", o->fin.drive_limit_v,
                "|drive| limit [V] (with --plant; 0 = the largest training amplitude)")
      ->needs(plant)
      ->capture_default_str();
  c->add_option("--job", o->job,
                "the HGANN job spec (.json) the network was identified with: its beam "
                "(hgann.geometry) and, in a "
                "comment, its cases' saturations (with --plant; default: the spec's beam)")
      ->needs(plant);
  c->add_option("--inverse-horizon", o->fin.inverse_horizon,
                "samples over which NAME_inverse_step reaches the desired angle (with --plant; 1 = "
                "exact one-step "
                "inversion, unstable on this plant)")
      ->needs(plant)
      ->capture_default_str();
  c->callback([o, &exit_code] { exit_code = ExportNetwork(*o); });
}

}  // namespace pz::client
