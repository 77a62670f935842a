#pragma once

#include <spdlog/logger.h>

#include <atomic>
#include <memory>
#include <optional>

#include "agent/options.hpp"
#include "common/claim/claim_runner.hpp"
#include "common/dds/dds_bus.hpp"

namespace qswarm {

// A replica's id claim (--id auto, or --claim with a given id) over the bus's claim topic, before
// it flies: fills `runner` (which keeps the claim up in flight) and returns the id taken, or
// nothing with `exit_code` (0: stopped while claiming; 2: no id for it).
std::optional<AgentId> claim_id(DdsBus& bus, const RunConfig& rc, const AgentFlags& f,
                                AgentId fixed, Clock& clock, const std::atomic<bool>& stop,
                                spdlog::logger& log, std::optional<IdClaimRunner>& runner,
                                int& exit_code);

// Flies agent `id` on the bus until its end, a stop or a planned kill (which it carries out on
// itself), then writes its stats into the run directory. Returns the process's exit code: 0, 2
// when another replica holds its claimed id, 3 when its stats could not be written.
int fly(const RunConfig& rc, AgentId id, AgentFlags& f, DdsBus& bus, Clock& clock,
        std::optional<IdClaimRunner>& claim, const std::atomic<bool>& stop);

}  // namespace qswarm
