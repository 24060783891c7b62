// libFuzzer target: the fit.json loader (reports/fit_file.h LoadFitText over io/fit_model.h) and
// what `piezoid export FIT.json` and `piezoid compensate` do with a model it accepts: the step
// kernels built (records::Stepper), the C header written (controller/export_header.h), the model
// run forward and inverse over a short drive sweep between its drive limits. The whole input is the
// fit.json text. Every outcome must be a model or a pz::InputError with a message; anything else
// (a signal, a sanitizer report, another exception) is a finding. The outputs are not checked for
// NaN: a fitted oscillator can be unstable on a drive (`compensate` says so where it meets one).
// Build and run: fuzz/run.sh (clang, -fsanitize=fuzzer,address,undefined).
#include <google/protobuf/stubs/logging.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "controller/export_header.h"
#include "model/status.h"
#include "records/stepper.h"
#include "reports/fit_file.h"

namespace {

[[noreturn]] void Fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_fit_model: %s\n", what.c_str());
  std::abort();
}

void Run(const pz::records::ModelSpec& m) {
  pz::records::Stepper fwd(m);
  (void)pz::controller::ExportHeader(fwd, "pz_fuzz", "fuzz");
  constexpr int kSteps = 24;
  auto drive = [&](int k) {  // a triangle between the limits
    const double x = k < kSteps / 2 ? 2.0 * k / kSteps : 2.0 - 2.0 * k / kSteps;
    return m.drive_min + x * (m.drive_max - m.drive_min);
  };
  double y[kSteps];
  y[0] = fwd.Init(drive(0));
  for (int k = 1; k < kSteps; ++k) y[k] = fwd.Step(drive(k));
  pz::records::Stepper inv(m);
  inv.Init(drive(0));
  inv.InversePrimeFrom(y);
  for (int k = 1; k < kSteps; ++k) (void)inv.InverseStep(y[k]);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  google::protobuf::SetLogHandler(
      nullptr);  // the JSON parser's complaints: the answers are checked
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const pz::records::ModelSpec m = pz::reports::LoadFitText("fit.json", text);
    Run(m);
  } catch (const pz::InputError& e) {
    if (std::string_view(e.what()).empty()) Fail("an InputError without a message");
  }
  return 0;
}
