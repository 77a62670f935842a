#pragma once

#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace qswarm {

// What the law and plant registries share: a spec found by its name or an alias, and the list of
// names for messages. Spec has `name` and `aliases`.

template <class Spec>
std::string seam_names(const std::vector<Spec>& all) {
  std::string out;
  for (const Spec& s : all) out += (out.empty() ? "" : ", ") + s.name;
  return out;
}

// Throws std::invalid_argument "KIND 'NAME': expected one of ...".
template <class Spec>
const Spec& find_in_seam(const std::vector<Spec>& all, const std::string& name,
                         const std::string& kind) {
  for (const Spec& s : all) {
    if (s.name == name) return s;
    for (const std::string& a : s.aliases)
      if (a == name) return s;
  }
  throw std::invalid_argument(kind + " '" + name + "': expected one of " + seam_names(all));
}

// Whether a spec's name and aliases are non-empty and not yet in `names` (then added), or why not.
template <class Spec>
std::string seam_names_problem(const Spec& s, std::set<std::string>& names) {
  if (s.name.empty()) return "no name";
  if (!names.insert(s.name).second) return "its name is taken";
  for (const std::string& n : s.aliases)
    if (n.empty() || !names.insert(n).second) return "alias '" + n + "' is empty or taken";
  return "";
}

}  // namespace qswarm
