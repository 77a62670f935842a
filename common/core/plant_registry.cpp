#include "common/core/plant.hpp"

#include <set>
#include <stdexcept>

#include "common/core/seam_lookup.hpp"

namespace qswarm {

namespace plants {
#define QSWARM_PLANT(fn) PlantSpec fn();
#include "common/plants/plants.inc"
#undef QSWARM_PLANT
}  // namespace plants

namespace {

// A plant that breaks the seam's rules is a programming error found at the first lookup.
void check_spec(const PlantSpec& s, std::set<std::string>& names) {
  const auto bad = [&](const std::string& why) {
    throw std::logic_error("plant '" + s.name + "': " + why);
  };
  if (!s.make) bad("no factory");
  if (const std::string why = seam_names_problem(s, names); !why.empty()) bad(why);
  if (const std::string why = seam_params_problem(s.params); !why.empty()) bad(why);
  if (!(s.min_physics_hz >= 0.0)) bad("a negative min_physics_hz");
}

}  // namespace

const std::vector<PlantSpec>& registered_plants() {
  static const std::vector<PlantSpec> all = [] {
    std::vector<PlantSpec> v;
#define QSWARM_PLANT(fn) v.push_back(plants::fn());
#include "common/plants/plants.inc"
#undef QSWARM_PLANT
    std::set<std::string> names;
    for (const PlantSpec& s : v) check_spec(s, names);
    return v;
  }();
  return all;
}

std::string plant_names() { return seam_names(registered_plants()); }

const PlantSpec& find_plant(const std::string& name) {
  return find_in_seam(registered_plants(), name, "plant");
}

std::map<std::string, double> resolve_plant_params(const PlantSpec& spec,
                                                   const std::map<std::string, double>& given) {
  return resolve_seam_params(spec.params, given, "plant_params", "plant " + spec.name);
}

std::unique_ptr<Plant> make_plant(const PlantConfig& cfg, PlantStart start) {
  const PlantSpec& spec = find_plant(cfg.name);
  start.params = resolve_plant_params(spec, cfg.params);
  return spec.make(start);
}

}  // namespace qswarm
