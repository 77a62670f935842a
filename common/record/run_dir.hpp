#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/scenario/run_config.hpp"

namespace qswarm {

// A run directory that cannot be claimed (exists with files, is claimed by another run, cannot be
// created). The message names --out and says why; `swarm run` exits 2.
class RunDirError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A scenario name as a file name: letters, digits, '.', '-', '_' kept, anything else '_', no
// leading dot, at most 64 characters ("../../x" cannot leave runs/).
std::string safe_name(const std::string& name);

// Claims the directory one run writes its record into, and returns its absolute path: `out`, or
// ROOT/TIMESTAMP-NAME (with -2, -3, ... if taken) when `out` is empty. The directory must be new or
// empty; the claim is an exclusive marker file (.swarm-run, created with O_EXCL), so two runs given
// the same --out never both write there.
std::filesystem::path claim_run_dir(const std::string& out, const std::string& scenario_name,
                                    const std::string& timestamp,
                                    const std::filesystem::path& root = "runs");

// The local time as run directories are named: YYYYMMDD-HHMMSS.
std::string run_timestamp();

// When the supervisor could not write the summary (it died), the launcher writes one that says
// why, so that a run never ends without summary.json. Returns whether it was written.
bool write_fallback_summary(const std::filesystem::path& dir, const RunConfig& rc,
                            const std::string& reason, double wall_time_s);

// Children that crashed unseen by the supervisor (at teardown): summary.json is rewritten with
// converged false and the problems appended to its end_reason. Returns whether it was written.
bool amend_summary(const std::filesystem::path& dir, const std::vector<std::string>& problems);

}  // namespace qswarm
