#include "model/fin_case.h"

#include <utility>

namespace pz::model {

FinCase MakeFinCase(int number, const Sinusoid& drive, std::vector<double> measured_deg,
                    bool training, const std::optional<SaturationPair>& given,
                    const std::string& where) {
  const std::string at = where.empty() ? "case " + std::to_string(number) : where;
  if (measured_deg.size() != static_cast<size_t>(drive.NumSamples()))
    throw InputError(at + ": " + std::to_string(measured_deg.size()) + " samples, the drive has " +
                     std::to_string(drive.NumSamples()));
  SaturationPair sat;
  if (given) {
    sat = *given;
  } else {
    try {
      sat = SaturationFromExtremes(measured_deg);
    } catch (const InputError& e) {
      throw InputError(at + ": cannot fit the saturations b1, b2: " + e.what());
    }
  }
  FinCase c;
  c.number = number;
  c.drive = drive;
  c.measured_deg = std::move(measured_deg);
  c.b1 = sat.b1;
  c.b2 = sat.b2;
  c.training = training;
  return c;
}

}  // namespace pz::model
