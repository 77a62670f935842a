#include "common/core/plant.hpp"

#include <set>
#include <stdexcept>

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
  if (s.name.empty() || !s.make) bad("no name or no factory");
  if (!names.insert(s.name).second) bad("its name is taken");
  for (const std::string& n : s.aliases)
    if (n.empty() || !names.insert(n).second) bad("alias '" + n + "' is empty or taken");
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

std::string plant_names() {
  std::string out;
  for (const PlantSpec& s : registered_plants()) out += (out.empty() ? "" : ", ") + s.name;
  return out;
}

const PlantSpec& find_plant(const std::string& name) {
  for (const PlantSpec& s : registered_plants()) {
    if (s.name == name) return s;
    for (const std::string& a : s.aliases)
      if (a == name) return s;
  }
  throw std::invalid_argument("plant '" + name + "': expected one of " + plant_names());
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
