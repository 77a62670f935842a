#include "common/sim/paper_maneuvers.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "common/core/dynamics.hpp"
#include "common/core/primitives.hpp"

namespace qswarm {
namespace {

constexpr double kStepS = 0.002;
constexpr int kRowEvery = 10;  // a row every 0.02 s

const char* segment_name(OpenLoopManeuver::Kind k) {
  switch (k) {
    case OpenLoopManeuver::Kind::kHover:
      return "hover";
    case OpenLoopManeuver::Kind::kClimb:
      return "climb";
    case OpenLoopManeuver::Kind::kYaw:
      return "yaw";
    case OpenLoopManeuver::Kind::kBodyX:
      return "body_x";
  }
  return "hover";
}

// The segment flown at t; the row at the very end belongs to the last segment.
const char* segment_at(const OpenLoopManeuver& m, double t) {
  double start = 0.0;
  for (const auto& seg : m.segments()) {
    if (t < start + seg.duration_s) return segment_name(seg.kind);
    start += seg.duration_s;
  }
  return m.segments().empty() ? "hover" : segment_name(m.segments().back().kind);
}

// A CSV file whose every write is checked when it is closed (a full disk is an error, not a
// short file).
class CsvFile {
 public:
  CsvFile(const std::filesystem::path& path, const char* header) : path_(path.string()) {
    f_ = std::fopen(path_.c_str(), "w");
    if (f_ == nullptr) throw std::runtime_error("cannot create " + path_);
    std::fputs(header, f_);
  }
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  ~CsvFile() {
    if (f_ != nullptr) std::fclose(f_);
  }

  std::FILE* get() { return f_; }

  void close() {
    const bool bad = std::ferror(f_) != 0;
    const int rc = std::fclose(f_);
    f_ = nullptr;
    if (bad || rc != 0)
      throw std::runtime_error("cannot write " + path_ + " completely (disk full?)");
  }

 private:
  std::string path_;
  std::FILE* f_ = nullptr;
};

constexpr const char* kFlightHeader =
    "drone,t_s,x,y,z,roll,pitch,yaw,w1,w2,w3,w4,thrust_N,yaw_torque_Nm,segment\n";

void flight_row(std::FILE* f, unsigned drone, double t, const QuadState& s, const Airframe& af,
                const RotorSpeeds& w, const char* segment) {
  const TaitBryan a = tait_bryan_from_rotation(s.R_WB);
  std::fprintf(
      f, "%u,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%s\n",
      drone, t, s.p_W.x(), s.p_W.y(), s.p_W.z(), a.roll_rad, a.pitch_rad, a.yaw_rad, w[0], w[1],
      w[2], w[3], total_thrust(af, w), rotor_torque(af, w).z(), segment);
}

// Flies `m` from `s` for its whole duration; a row every kRowEvery steps and one at the end. Each
// segment's start and duration go to `segments` (drone,segment,start_s,duration_s,amount).
void fly(CsvFile& csv, CsvFile& segments, unsigned drone, const Airframe& af, OpenLoopManeuver m,
         QuadState s) {
  double start = 0.0;
  for (const auto& seg : m.segments()) {
    std::fprintf(segments.get(), "%u,%s,%.17g,%.17g,%.17g\n", drone, segment_name(seg.kind), start,
                 seg.duration_s, seg.amount);
    start += seg.duration_s;
  }
  const int steps = static_cast<int>(std::lround(m.duration_s() / kStepS));
  for (int i = 0; i <= steps; ++i) {
    const double t = i * kStepS;
    const RotorSpeeds w = m.command(t, s);
    if (i % kRowEvery == 0 || i == steps)
      flight_row(csv.get(), drone, t, s, af, w, segment_at(m, t));
    if (i < steps) s = rk4_step(af, s, w, kStepS);
  }
  if (!s.finite()) {
    throw std::runtime_error("the maneuver of drone " + std::to_string(drone) +
                             " produced non-finite numbers");
  }
}

}  // namespace

void write_paper_maneuvers(const RunConfig& rendezvous, const std::string& out_dir) {
  namespace fs = std::filesystem;
  const Airframe af;  // the paper's Table 1
  CsvFile segments(fs::path(out_dir) / "segments.csv", "drone,segment,start_s,duration_s,amount\n");
  {
    CsvFile csv(fs::path(out_dir) / "single_agent.csv", kFlightHeader);
    std::fputs("# single_agent.csv\n", segments.get());
    fly(csv, segments, 1, af, OpenLoopManeuver::paper_single_agent(af), QuadState{});
    csv.close();
  }
  Vec3 target = Vec3::Zero();
  for (const AgentSpec& a : rendezvous.agents) target += a.position_W;
  target /= static_cast<double>(rendezvous.agents.size());
  CsvFile csv(fs::path(out_dir) / "rendezvous_dynamics.csv", kFlightHeader);
  std::fputs("# rendezvous_dynamics.csv\n", segments.get());
  for (const AgentSpec& a : rendezvous.agents) {
    QuadState s;
    s.p_W = a.position_W;
    s.R_WB = rotation_from_tait_bryan({0.0, 0.0, a.yaw_rad});
    fly(csv, segments, a.id, af, OpenLoopManeuver::yaw_then_fly(af, s, target), s);
  }
  csv.close();
  segments.close();
}

}  // namespace qswarm
