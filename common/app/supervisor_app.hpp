#pragma once

#include <spdlog/logger.h>

#include <memory>
#include <string>

#include "common/app/process_options.hpp"
#include "common/record/run_dir.hpp"
#include "common/record/supervisor_loop.hpp"
#include "common/view/view_feed.hpp"
#include "common/view/view_server.hpp"

namespace qswarm {

// What swarm-supervisor does beyond recording: its flags, where it records, and the live view.

struct SupervisorFlags {
  ProcessOptions process;
  SupervisorOptions loop;
  std::string run_dir;     // --run-dir: the launcher's
  std::string new_run_in;  // --new-run-in ROOT: a fresh ROOT/TIMESTAMP-NAME (compose)
  int view_port = -1;      // --view PORT (0: any free port)
  std::string view_listen = "127.0.0.1";
};
void add_supervisor_options(CLI::App& app, SupervisorFlags& f);

// A fresh run directory ROOT/TIMESTAMP-NAME for a supervisor started alone (compose:
// --new-run-in ROOT), with the scenario as run and its plan written there. Throws RunDirError
// when ROOT cannot hold one (bad input), std::runtime_error when a file cannot be written.
RunDir new_run_dir(const std::string& root, const RunConfig& rc);

// The live view beside a recording supervisor (--view): its server runs on its own thread and the
// supervisor's loop hands it records through the feed's bounded buffers. Without it the record
// path has no observer, no thread and no copies.
class SupervisorView {
 public:
  // Listens on `listen`:`port` (0: any free port) and tells the loop to feed it; says where on
  // stdout, in the log and in the run directory (view.url). Throws ViewServerError when it
  // cannot listen.
  SupervisorView(int port, const std::string& listen, const RunConfig& rc, const RunDir& dir,
                 SupervisorLoop& loop, std::shared_ptr<spdlog::logger> log);
  // The end state reaches the pages (within a second), then the server goes; call after the
  // loop's finish.
  void close();

 private:
  SupervisorLoop& loop_;
  std::shared_ptr<spdlog::logger> log_;
  ViewFeed feed_;
  std::unique_ptr<ViewServer> server_;
};

}  // namespace qswarm
