// Runs a pipeline stage (a node class: SimNode, FilterNode, SensorNode, VoiceNode) until SIGINT/SIGTERM or until
// the node says it is done, then lets it finish: the one loop every thin main shares.
#pragma once

#include "tachi/common/app.hpp"

namespace tachi::common {

/// `node.spin_once()` blocks briefly (on its waitset or input) and returns false when the run is over;
/// `node.finish()` flushes what the node owes its readers and returns the process's exit code.
template <class Node>
int run_until_signal(Node& node) {
  install_stop_handlers();
  run_until_stopped([&node] { return node.spin_once(); });
  return node.finish();
}

}  // namespace tachi::common
