#include "common/core/seam_params.hpp"

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace qswarm {

namespace {

std::string number(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

}  // namespace

std::map<std::string, double> resolve_seam_params(const std::vector<SeamParam>& params,
                                                  const std::map<std::string, double>& given,
                                                  const std::string& field,
                                                  const std::string& owner) {
  std::map<std::string, double> out;
  for (const auto& [name, value] : given) {
    std::string where = "field '";
    where.append(field).append("[\"").append(name).append("\"]' of ").append(owner);
    const SeamParam* p = nullptr;
    for (const SeamParam& q : params)
      if (q.name == name) p = &q;
    if (p == nullptr) {
      std::string known;
      for (const SeamParam& q : params) known += (known.empty() ? "" : ", ") + q.name;
      throw std::invalid_argument(where + ": no such parameter (it takes " +
                                  (known.empty() ? std::string("none") : known) + ")");
    }
    if (!std::isfinite(value) || value < p->min || value > p->max ||
        (p->integer && std::floor(value) != value)) {
      throw std::invalid_argument(where + ": expected " + (p->integer ? "a whole number " : "") +
                                  "in [" + number(p->min) + ", " + number(p->max) + "], got " +
                                  number(value));
    }
    out[name] = value;
  }
  for (const SeamParam& p : params) out.emplace(p.name, p.fallback);
  return out;
}

std::string seam_params_problem(const std::vector<SeamParam>& params) {
  std::set<std::string> names;
  for (const SeamParam& p : params) {
    if (p.name.empty() || !names.insert(p.name).second) return "a parameter without a unique name";
    if (!(p.min <= p.fallback && p.fallback <= p.max))
      return p.name + "'s fallback is out of range";
  }
  return "";
}

std::uint32_t seam_tag(const std::string& name) {
  std::uint32_t h = 2166136261u;  // FNV-1a
  for (const char c : name) {
    h ^= static_cast<unsigned char>(c);
    h *= 16777619u;
  }
  return h == 0 ? 1 : h;
}

}  // namespace qswarm
