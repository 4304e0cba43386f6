// Several pipeline stages composed into one process, each on its own thread (the shape of ROS 2's
// component composition): what run_until_signal (node.hpp) does for one node, for a list of nodes of
// different classes. tachi-pipeline runs `tachi run --in-process`'s nodes through it; the nodes are the
// same classes the single-stage executables run, over the same bus (a participant each).
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <vector>

namespace tachi::common {

/// One stage of a composition, given as functions so that different node classes run side by side.
struct ComposedNode {
  std::string name;                 ///< "sim": the name its thread's log lines carry
  bool finite = false;              ///< ends by itself (a played recording, a settled cloth)
  std::function<bool()> spin_once;  ///< as Node::spin_once: blocks briefly, false when the node's run is over
  std::function<int()> finish;      ///< as Node::finish: flushes what the node owes, returns its exit code
  /// Spins on run_composed's calling thread, not one of its own: a node with a window (GUI toolkits are
  /// driven from the thread that opened the window). The first such node only.
  bool needs_calling_thread = false;
};

/// Runs each node on its own thread (one that needs_calling_thread on the caller's) until SIGINT/SIGTERM
/// (or request_stop), or, when some nodes are
/// finite, until every finite node has finished: the others then get `grace` to pass their last
/// samples on, are stopped, and finish. The rule is `tachi run`'s for its children.
/// A node that throws stops the composition, as a process that dies stops with its exit code: the
/// others are stopped and finish, and the composition's code is the failed node's (kExitDiskFull for
/// DiskFull, else kExitFailure). Otherwise the first non-zero code a node's finish returned, or 0.
/// Each thread's log lines carry its node's name (spdlog's default logger, pattern flag %*).
[[nodiscard]] int run_composed(std::vector<ComposedNode> nodes, std::chrono::milliseconds grace);

/// Makes spdlog's default logger print the calling thread's node name (set by run_composed) after the
/// logger's name: "[tachi-pipeline:sim] [info] ...".
void log_node_names(const std::string& logger_name);

}  // namespace tachi::common
