#pragma once

#include <string>

namespace qswarm {

struct ViewCommandOptions {
  std::string run_dir;
  double speed = 1.0;  // simulated seconds per wall second
  int port = 8765;     // 0: any free port
  std::string listen = "127.0.0.1";
};

// `swarm view RUN_DIR`: serves a recorded run to the live view's page and Foxglove's WebSocket
// protocol, as if live, until Ctrl-C. Exit 2 for bad input (a missing directory, no records, a
// speed that is not a positive number, a port that cannot be listened on), naming the flag.
int view_command(const ViewCommandOptions& o);

}  // namespace qswarm
