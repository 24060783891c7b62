#include "diagnose/problem.h"

#include <algorithm>
#include <cmath>

#include "io/bench_data.h"
#include "model/saturation.h"

namespace pz::diagnose {

// ---- cases
// ---------------------------------------------------------------------------------------

namespace {

DiagCase MakeCase(int number, const model::Sinusoid& drive, std::vector<double> measured,
                  bool training) {
  model::FinCase f = model::MakeFinCase(number, drive, std::move(measured), training);
  records::CaseNoise noise = records::EstimateCaseNoise(
      f.measured_deg, std::max(1, static_cast<int>(std::lround(drive.cycles))));
  return DiagCase{std::move(f), std::move(noise)};
}

}  // namespace

std::vector<DiagCase> CasesFromCaseSet(const io::CaseSet& set) {
  std::vector<DiagCase> cases;
  int train = 0;
  for (const io::BenchCase& bc : set.cases) {
    const bool training = bc.role == io::CaseRole::kTrain;
    train += training;
    cases.push_back(MakeCase(bc.number, bc.Drive(), bc.angle_deg, training));
  }
  if (train == 0)
    throw InputError(set.dir.string() + ": no training case (role train) to identify on");
  if (train == static_cast<int>(cases.size()))
    throw InputError(set.dir.string() + ": no withheld case (role validate/test) to score on");
  return cases;
}

// ---- layout
}  // namespace pz::diagnose
