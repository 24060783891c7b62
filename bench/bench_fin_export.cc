// Cost per sample of the fin header of `piezoid export --plant` (controller/export_fin_c.h),
// compiled by the build's C compiler (-std=c99 -O2, as a controller would) into a shared object
// that this benchmark loads; the calls go through function pointers (a nanosecond or two of the
// figures):
//   BM_FinParams                 NAME_params: the network, once per (amplitude, frequency)
//   BM_FinStep/rate              NAME_step on bench case 9's drive (750 V, 1 Hz) at 100 Hz and 1
//   kHz BM_FinStepJumps              NAME_step on a drive jumping ±600 V every sample (sub-steps, z
//   crossing 0) BM_FinInverseStep/rate       NAME_inverse_step (horizon 2) following that drive's
//   response; counter
//                                trials = steps of the forward recursion per inverse step
// The network: tests/data/networks/fin_nominal.json, identified on the nominal bench. Figures and
// the operation count: docs/performance.md, "Benchmarks of the parts".
#include <benchmark/benchmark.h>
#include <dlfcn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "controller/export_c.h"
#include "io/network_io.h"
#include "model/modal_simulator.h"

namespace pz::client {
namespace {

namespace fs = std::filesystem;

// An identified network: tests/data/networks/README.md.
io::SavedNetwork Network() {
  io::SavedNetwork s;
  if (!io::LoadNetwork(PIEZOID_TEST_DATA_DIR "/networks/fin_nominal.json", &s).ok())
    throw std::runtime_error("cannot load " PIEZOID_TEST_DATA_DIR "/networks/fin_nominal.json");
  return s;
}

constexpr const char* kGlue =
    "#include <stddef.h>\n#include \"fin.h\"\n"
    R"C(
size_t glue_size(void) { return sizeof(fin_state); }
int glue_params(double v, double f, double* p) { return fin_params(v, f, p); }
int glue_init(void* s, double v, double f, double u0) {
  double p[7];
  fin_params(v, f, p);
  return fin_init((fin_state*)s, p, 3.1640625, -3.076171875, u0); /* case 9 */
}
double glue_step(void* s, double u) { return fin_step((fin_state*)s, u); }
double glue_inverse(void* s, double y) { return fin_inverse_step((fin_state*)s, y); }
long glue_trials(const void* s) { return ((const fin_state*)s)->trials; }
long glue_modes(void) { return FIN_MODES; }
)C";

/// One compiled header (sample rate fs): the glue's entry points.
struct Compiled {
  size_t (*size)() = nullptr;
  int (*params)(double, double, double*) = nullptr;
  int (*init)(void*, double, double, double) = nullptr;
  double (*step)(void*, double) = nullptr;
  double (*inverse)(void*, double) = nullptr;
  long (*trials)(const void*) = nullptr;
  long (*modes)() = nullptr;
};

template <class F>
void Sym(void* lib, const char* name, F** f) {
  *f = reinterpret_cast<F*>(dlsym(lib, name));
  if (!*f) throw std::runtime_error(std::string("dlsym ") + name);
}

const Compiled& Header(double fs) {
  static std::vector<std::pair<double, Compiled>> cache;
  for (const auto& [rate, c] : cache)
    if (rate == fs) return c;
  const fs::path dir = fs::temp_directory_path() / ("pz-bench-fin-" + std::to_string(::getpid()) +
                                                    "-" + std::to_string(static_cast<long>(fs)));
  fs::create_directories(dir);
  const model::BimorphPlant plant;
  const model::ModalSimulator sim(plant);
  std::string h;
  controller::FinPlantExport options;
  options.sample_rate_hz = fs;
  if (!controller::NetworkAndFinToCHeader(Network(), sim, options, "fin", &h).ok())
    throw std::runtime_error("export");
  std::ofstream(dir / "fin.h") << h;
  std::ofstream(dir / "glue.c") << kGlue;
  const std::string cmd =
      "cd '" + dir.string() +
      "' && '" PIEZOID_C_COMPILER
      "' -std=c99 -O2 -Wall -Wextra -Werror -pedantic -fPIC -shared -o glue.so glue.c -lm";
  const int st = std::system(cmd.c_str());
  if (!WIFEXITED(st) || WEXITSTATUS(st) != 0) throw std::runtime_error(cmd);
  void* lib = dlopen((dir / "glue.so").c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!lib) throw std::runtime_error(dlerror());
  Compiled c;
  Sym(lib, "glue_size", &c.size);
  Sym(lib, "glue_params", &c.params);
  Sym(lib, "glue_init", &c.init);
  Sym(lib, "glue_step", &c.step);
  Sym(lib, "glue_inverse", &c.inverse);
  Sym(lib, "glue_trials", &c.trials);
  Sym(lib, "glue_modes", &c.modes);
  fs::remove_all(dir);  // the loaded object stays mapped
  cache.emplace_back(fs, c);
  return cache.back().second;
}

/// Bench case 9's drive, 750 V sin(2π t), one period at fs.
std::vector<double> Sine(double fs) {
  std::vector<double> u(static_cast<size_t>(std::lround(fs)));
  for (size_t k = 0; k < u.size(); ++k)
    u[k] = 750 * std::sin(2 * std::numbers::pi * static_cast<double>(k) / fs);
  return u;
}

void BM_FinParams(benchmark::State& state) {
  const Compiled& c = Header(100);
  double p[7];
  double v = 375;
  for (auto _ : state) {
    benchmark::DoNotOptimize(c.params(v, 0.5, p));
    v = v < 750 ? v + 1 : 375;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FinParams);

void BM_FinStep(benchmark::State& state) {
  const double fs = static_cast<double>(state.range(0));
  const Compiled& c = Header(fs);
  const std::vector<double> u = Sine(fs);
  std::vector<char> s(c.size());
  c.init(s.data(), 750, 1, 0);
  size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(c.step(s.data(), u[k]));
    k = k + 1 == u.size() ? 0 : k + 1;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["modes"] = static_cast<double>(c.modes());
}
BENCHMARK(BM_FinStep)->Arg(100)->Arg(1000);

void BM_FinStepJumps(benchmark::State& state) {
  const Compiled& c = Header(100);
  std::vector<char> s(c.size());
  c.init(s.data(), 750, 1, 0);
  double u = 600;
  for (auto _ : state) {
    benchmark::DoNotOptimize(c.step(s.data(), u));
    u = -u;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FinStepJumps);

void BM_FinInverseStep(benchmark::State& state) {
  const double fs = static_cast<double>(state.range(0));
  const Compiled& c = Header(fs);
  const std::vector<double> u = Sine(fs);
  std::vector<char> s(c.size());
  // The reference: the forward response over the second period (after the first's transient).
  c.init(s.data(), 750, 1, 0);
  std::vector<double> ref(u.size());
  for (size_t k = 0; k < 2 * u.size(); ++k) {
    const double y = c.step(s.data(), u[(k + 1) % u.size()]);
    if (k >= u.size()) ref[(k + 1) % u.size()] = y;
  }
  c.init(s.data(), 750, 1, 0);
  size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        c.inverse(s.data(), ref[(k + 2) % ref.size()]));  // one sample of preview
    k = k + 1 == ref.size() ? 0 : k + 1;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["trials"] =
      static_cast<double>(c.trials(s.data())) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_FinInverseStep)->Arg(100)->Arg(1000);

}  // namespace
}  // namespace pz::client

BENCHMARK_MAIN();
