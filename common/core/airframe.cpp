#include "common/core/airframe.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace qswarm {
namespace {

void require(bool ok, const std::string& field, double value, const char* expected) {
  if (ok) return;
  std::ostringstream msg;
  msg << "airframe." << field << " = " << value << ": expected " << expected;
  throw std::invalid_argument(msg.str());
}

void require_positive(const std::string& field, double value) {
  require(std::isfinite(value) && value > 0.0, field, value, "a finite value > 0");
}

void require_non_negative(const std::string& field, double value) {
  require(std::isfinite(value) && value >= 0.0, field, value, "a finite value >= 0");
}

}  // namespace

void Airframe::validate() const {
  require_positive("mass_kg", mass_kg);
  for (int i = 0; i < 3; ++i) {
    require_positive("inertia_kgm2[" + std::to_string(i) + "]", inertia_kgm2[i]);
    require_non_negative("C_D[" + std::to_string(i) + "]", C_D[i]);
    require_non_negative("C_tau[" + std::to_string(i) + "]", C_tau[i]);
  }
  require_non_negative("rotor_inertia_kgm2", rotor_inertia_kgm2);
  require_positive("arm_m", arm_m);
  require_positive("K_r", K_r);
  require_non_negative("K_d", K_d);
  require_positive("gravity_mps2", gravity_mps2);
  require_non_negative("rotor_min_radps", rotor_min_radps);
  require(std::isfinite(rotor_max_radps) && rotor_max_radps > rotor_min_radps, "rotor_max_radps",
          rotor_max_radps, "a finite value > rotor_min_radps");
  require(max_thrust_N() > weight_N(), "rotor_max_radps", rotor_max_radps,
          "enough rotor speed to lift the airframe (4 K_r omega_max^2 > m g)");
  require(4.0 * K_r * rotor_min_radps * rotor_min_radps < weight_N(), "rotor_min_radps",
          rotor_min_radps, "a minimum rotor speed whose thrust is below the weight");
}

double Airframe::hover_rotor_speed_radps() const { return std::sqrt(weight_N() / (4.0 * K_r)); }

}  // namespace qswarm
