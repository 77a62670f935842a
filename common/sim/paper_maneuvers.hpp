#pragma once

#include <string>

#include "common/scenario/run_config.hpp"

namespace qswarm {

// The paper's section 4 flights, simulated in-process with the core's open-loop primitives and
// the paper's airframe (no DDS): written as CSV for `swarm paper`'s figures and report.
//
//   single_agent.csv          the rise-yaw-fly maneuver (12 s up 10 m, yaw pi/2 over 4 s, 4 m
//                             along body x over 4 s)
//   rendezvous_dynamics.csv   every agent of `rendezvous` flies yaw-then-fly to the agents'
//                             initial average (4 s yaw, then body x, then 2 s hover)
//   segments.csv              every segment's start and duration, per file and drone
//
// Columns: drone, t_s, x, y, z, roll, pitch, yaw [rad], w1..w4 [rad/s], thrust_N, yaw_torque_Nm,
// segment (hover, climb, yaw, body_x). Rows every 0.02 s of a 0.002 s RK4 integration; the numbers
// are printed with 17 significant digits, so the files are identical from run to run.
// Throws std::runtime_error naming the file when one cannot be written completely.
void write_paper_maneuvers(const RunConfig& rendezvous, const std::string& out_dir);

}  // namespace qswarm
