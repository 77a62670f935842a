#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/scenario/run_config.hpp"
#include "proto/plan.pb.h"

namespace qswarm {

// What a run asks of its host, and whether the host sustains it: the run's agent CPU predicted as
// ticks x CPU per tick + neighbour samples received x CPU per sample, with both costs measured on
// this host by `swarm calibrate` (real agent processes flying all-to-all), and the samples counted
// from who hears whom at the start (Neighbourhood::heard_at_start). A swarm that moves into denser
// neighbourhoods receives more than predicted; one that spreads out, less.

// Of the host's cores, the share a run's agents may take and keep their ticks on time: the rest
// is the supervisor, the Discovery Server, Fast DDS's announcements, the kernel's network stack
// and whatever else runs (docs/run-plan.md, measured in docs/benchmarks.md#predicted-load).
constexpr double kUsableCoreShare = 0.75;

// Where the calibration is kept: $QSWARM_CALIBRATION, else $XDG_STATE_HOME/qswarm/
// calibration.txtpb, else ~/.local/state/qswarm/calibration.txtpb.
std::filesystem::path calibration_path();

// This host's name and the CPUs this process may run on.
std::string host_name();
unsigned host_cores();

// The calibration at `path` if it reads, every cost is finite and positive, and it was measured
// on this host with this many cores; otherwise nothing, and `why` says so ("none at PATH; run
// swarm calibrate", "field 'delivery_us_tick': ...", "measured on HOST with 4 cores").
std::optional<plan::HostCalibration> read_calibration(const std::filesystem::path& path,
                                                      const std::string& host, unsigned cores,
                                                      std::string& why);

// The run's load at `time_scale`, judged against `cal` (none: only the prediction is set, and
// `calibration` says why).
plan::Load predict_load(const RunConfig& rc, double time_scale,
                        const std::optional<plan::HostCalibration>& cal, unsigned cores,
                        const std::string& calibration);
// The same, with this host's calibration from calibration_path().
plan::Load predict_load_here(const RunConfig& rc, double time_scale);

// For `swarm inspect` and `swarm run`: what the run asks and what the host sustains.
std::string describe_load(const plan::Load& load);
// One line for a run whose load exceeds its host ("" when it does not).
std::string load_warning(const plan::Load& load);

// One calibration run: its agents' summed CPU in flight, ticks and samples received.
struct CalibrationSample {
  double cpu_s = 0.0;
  double ticks = 0.0;
  double received = 0.0;
};
struct FittedCosts {
  double tick_us = 0.0;
  double delivery_us = 0.0;
};
// CPU per tick and per sample from two runs that differ in samples per tick (least squares on
// cpu = ticks x tick_us + received x delivery_us); nothing when the runs do not tell them apart or
// a cost comes out not positive.
std::optional<FittedCosts> fit_costs(const std::vector<CalibrationSample>& runs);

}  // namespace qswarm
