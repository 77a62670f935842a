#pragma once

#include <cstdint>
#include <string>

#include "proto/scenario.pb.h"

namespace qswarm {

// CLI shortcuts for the common faults; each throws ScenarioError naming the flag. They add to the
// scenario's fault plan.
void add_loss_shortcut(scenario::Scenario& s, double probability);      // --loss 0.3
void add_cut_shortcut(scenario::Scenario& s, const std::string& spec);  // --cut 1-2@5:15
void add_partition_shortcut(scenario::Scenario& s,
                            const std::string& spec);                     // --partition 1,2@5:15
void add_delay_shortcut(scenario::Scenario& s, const std::string& spec);  // --delay 0.05:0.02
void add_kill_shortcut(scenario::Scenario& s, const std::string& spec);   // --kill 3@10:20
// --random-cuts N: N cuts of random links (ids 1..agents) lasting 1-5 s, starting in [2 s, 75% of
// end_s) so that the swarm has the rest of the run to agree again; seeded.
void add_random_cuts(scenario::Scenario& s, int n, int agents, double end_s, std::uint64_t seed);

}  // namespace qswarm
