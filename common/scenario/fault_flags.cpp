// The command line's fault shortcuts (--loss, --cut, ...): each adds to the scenario's fault plan
// and names its flag when the text is wrong. The resolver then checks the values like any field.
#include "common/scenario/fault_flags.hpp"

#include <cmath>
#include <random>
#include <sstream>

#include "common/scenario/fault_plan.hpp"
#include "common/scenario/scenario.hpp"

namespace qswarm {
namespace {

double parse_number(const std::string& flag, const std::string& text) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    throw ScenarioError(flag + " '" + text + "': expected a number");
  }
}

// "T0:T1", or "T0" (until the end).
std::pair<double, double> parse_window(const std::string& flag, const std::string& text) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) return {parse_number(flag, text), 0.0};
  return {parse_number(flag, text.substr(0, colon)), parse_number(flag, text.substr(colon + 1))};
}

std::pair<std::string, std::string> split_at(const std::string& flag, const std::string& spec,
                                             const char* expected) {
  const auto at = spec.find('@');
  if (at == std::string::npos) throw ScenarioError(flag + " '" + spec + "': expected " + expected);
  return {spec.substr(0, at), spec.substr(at + 1)};
}

std::uint32_t parse_id(const std::string& flag, const std::string& text) {
  const double v = parse_number(flag, text);
  if (v < 1 || v != std::floor(v) || v > 4e9) {
    throw ScenarioError(flag + " '" + text + "': expected an agent id");
  }
  return static_cast<std::uint32_t>(v);
}

}  // namespace

void add_loss_shortcut(scenario::Scenario& s, double p) {
  if (!std::isfinite(p) || p < 0.0 || p > 1.0) {
    throw ScenarioError("--loss " + quoted_number(p) + ": expected a probability in [0, 1]");
  }
  if (p > 0.0) s.mutable_faults()->add_loss()->set_probability(p);
}

void add_cut_shortcut(scenario::Scenario& s, const std::string& spec) {
  const auto [link, win] = split_at("--cut", spec, "A-B@START:END, e.g. 1-2@5:15");
  const auto dash = link.find('-');
  if (dash == std::string::npos) {
    throw ScenarioError("--cut '" + spec + "': expected A-B@START:END, e.g. 1-2@5:15");
  }
  auto* c = s.mutable_faults()->add_cut();
  c->set_a(parse_id("--cut", link.substr(0, dash)));
  c->set_b(parse_id("--cut", link.substr(dash + 1)));
  const auto [t0, t1] = parse_window("--cut", win);
  c->set_start_s(t0);
  c->set_end_s(t1);
}

void add_partition_shortcut(scenario::Scenario& s, const std::string& spec) {
  const auto [ids, win] = split_at("--partition", spec, "ID,ID,...@START:END, e.g. 1,2@5:15");
  auto* p = s.mutable_faults()->add_partition();
  std::stringstream in(ids);
  std::string one;
  while (std::getline(in, one, ',')) p->add_group(parse_id("--partition", one));
  const auto [t0, t1] = parse_window("--partition", win);
  p->set_start_s(t0);
  p->set_end_s(t1);
}

void add_delay_shortcut(scenario::Scenario& s, const std::string& spec) {
  const auto [mean, jitter] = parse_window("--delay", spec);
  auto* d = s.mutable_faults()->add_delay();
  d->set_mean_s(mean);
  d->set_jitter_s(jitter);
}

void add_kill_shortcut(scenario::Scenario& s, const std::string& spec) {
  const auto [who, win] = split_at("--kill", spec, "ID@AT[:RESTART], e.g. 3@10:20");
  auto* k = s.mutable_faults()->add_kill();
  k->set_agent(parse_id("--kill", who));
  const auto [t0, t1] = parse_window("--kill", win);
  k->set_at_s(t0);
  k->set_restart_at_s(t1);
}

void add_random_cuts(scenario::Scenario& s, int n, int agents, double end_s, std::uint64_t seed) {
  std::mt19937_64 rng(link_seed(seed, 0xC0, 0xC7));
  std::uniform_int_distribution<int> pick(1, std::max(2, agents));
  std::uniform_real_distribution<double> start(2.0, std::max(3.0, 0.75 * end_s - 5.0)),
      len(1.0, 5.0);
  for (int i = 0; i < n; ++i) {
    const int a = pick(rng);
    int b = pick(rng);
    while (b == a) b = pick(rng);
    auto* c = s.mutable_faults()->add_cut();
    c->set_a(static_cast<std::uint32_t>(a));
    c->set_b(static_cast<std::uint32_t>(b));
    const double t0 = start(rng);
    c->set_start_s(t0);
    c->set_end_s(t0 + len(rng));
  }
}

}  // namespace qswarm
