#include "common/core/law_registry.hpp"

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace qswarm {

namespace laws {
#define QSWARM_LAW(fn) LawSpec fn();
#include "common/laws/laws.inc"
#undef QSWARM_LAW
}  // namespace laws

namespace {

std::string number(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

// A law that breaks the seam's own rules is a programming error found at the first lookup, in
// every test that flies a law, not a run that misbehaves later.
void check_spec(const LawSpec& s, std::set<std::string>& names, std::set<std::uint32_t>& tags) {
  const auto bad = [&](const std::string& why) {
    throw std::logic_error("law '" + s.name + "': " + why);
  };
  if (s.name.empty() || !s.make) bad("no name or no factory");
  for (const std::string& n : s.aliases)
    if (n.empty()) bad("an empty alias");
  if (!names.insert(s.name).second) bad("its name is taken");
  if (!tags.insert(law_tag(s.name)).second) bad("its tag (a hash of its name) is another law's");
  for (const std::string& n : s.aliases)
    if (!names.insert(n).second) bad("alias '" + n + "' is taken");
  if (s.payload_max > kMaxLawPayload) bad("payload_max beyond kMaxLawPayload");
  std::set<std::string> params;
  for (const LawParam& p : s.params) {
    if (p.name.empty() || !params.insert(p.name).second) bad("a parameter without a unique name");
    if (!(p.min <= p.fallback && p.fallback <= p.max)) bad(p.name + "'s fallback is out of range");
  }
  if (s.claims.honest_hull && !params.count("f")) bad("claims the honest hull without an \"f\"");
}

}  // namespace

const std::vector<LawSpec>& registered_laws() {
  static const std::vector<LawSpec> all = [] {
    std::vector<LawSpec> v;
#define QSWARM_LAW(fn) v.push_back(laws::fn());
#include "common/laws/laws.inc"
#undef QSWARM_LAW
    std::set<std::string> names;
    std::set<std::uint32_t> tags;
    for (const LawSpec& s : v) check_spec(s, names, tags);
    return v;
  }();
  return all;
}

std::string law_names() {
  std::string out;
  for (const LawSpec& s : registered_laws()) out += (out.empty() ? "" : ", ") + s.name;
  return out;
}

const LawSpec& find_law(const std::string& name) {
  for (const LawSpec& s : registered_laws()) {
    if (s.name == name) return s;
    for (const std::string& a : s.aliases)
      if (a == name) return s;
  }
  throw std::invalid_argument("update law '" + name + "': expected one of " + law_names());
}

std::uint32_t law_tag(const std::string& name) {
  std::uint32_t h = 2166136261u;  // FNV-1a
  for (const char c : name) {
    h ^= static_cast<unsigned char>(c);
    h *= 16777619u;
  }
  return h == 0 ? 1 : h;
}

std::map<std::string, double> resolve_law_params(const LawSpec& spec,
                                                 const std::map<std::string, double>& given,
                                                 const std::string& field) {
  std::map<std::string, double> out;
  for (const auto& [name, value] : given) {
    std::string where = "field '";
    where.append(field).append("[\"").append(name).append("\"]' of law ").append(spec.name);
    const LawParam* p = nullptr;
    for (const LawParam& q : spec.params)
      if (q.name == name) p = &q;
    if (p == nullptr) {
      std::string known;
      for (const LawParam& q : spec.params) known += (known.empty() ? "" : ", ") + q.name;
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
  for (const LawParam& p : spec.params) out.emplace(p.name, p.fallback);
  return out;
}

int honest_hull_f(const LawConfig& cfg) {
  const LawSpec& spec = find_law(cfg.law);
  if (!spec.claims.honest_hull) return -1;
  const auto it = cfg.params.find("f");
  return static_cast<int>(it != cfg.params.end() ? it->second
                                                 : resolve_law_params(spec, {}).at("f"));
}

}  // namespace qswarm
