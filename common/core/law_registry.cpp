#include "common/core/law_registry.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>

#include "common/core/seam_lookup.hpp"

namespace qswarm {

namespace laws {
#define QSWARM_LAW(fn) LawSpec fn();
#include "common/laws/laws.inc"
#undef QSWARM_LAW
}  // namespace laws

namespace {

// A law that breaks the seam's own rules is a programming error found at the first lookup, in
// every test that flies a law, not a run that misbehaves later.
void check_spec(const LawSpec& s, std::set<std::string>& names, std::set<std::uint32_t>& tags) {
  const auto bad = [&](const std::string& why) {
    throw std::logic_error("law '" + s.name + "': " + why);
  };
  if (!s.make) bad("no factory");
  if (const std::string why = seam_names_problem(s, names); !why.empty()) bad(why);
  if (!tags.insert(law_tag(s.name)).second) bad("its tag (a hash of its name) is another law's");
  if (s.payload_max > kMaxLawPayload) bad("payload_max beyond kMaxLawPayload");
  if (const std::string why = seam_params_problem(s.params); !why.empty()) bad(why);
  if (s.claims.honest_hull && std::none_of(s.params.begin(), s.params.end(),
                                           [](const LawParam& p) { return p.name == "f"; }))
    bad("claims the honest hull without an \"f\"");
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

std::string law_names() { return seam_names(registered_laws()); }

const LawSpec& find_law(const std::string& name) {
  return find_in_seam(registered_laws(), name, "update law");
}

std::uint32_t law_tag(const std::string& name) { return seam_tag(name); }

std::map<std::string, double> resolve_law_params(const LawSpec& spec,
                                                 const std::map<std::string, double>& given,
                                                 const std::string& field) {
  return resolve_seam_params(spec.params, given, field, "law " + spec.name);
}

int honest_hull_f(const LawConfig& cfg) {
  const LawSpec& spec = find_law(cfg.law);
  if (!spec.claims.honest_hull) return -1;
  const auto it = cfg.params.find("f");
  return static_cast<int>(it != cfg.params.end() ? it->second
                                                 : resolve_law_params(spec, {}).at("f"));
}

}  // namespace qswarm
