#pragma once

namespace qswarm {

// How far (simulated s) a running agent's stamp may be ahead of the swarm's clock and still be
// one of the run's ticks: a late joiner's first stamps, a process's scheduling, a tick or two of
// skew. Past it a stamp is implausible (a forger's, a relay's from the future): the recorder
// refuses the sample, and a joining agent does not take its clock from it.
inline constexpr double kStampSlackS = 5.0;

}  // namespace qswarm
