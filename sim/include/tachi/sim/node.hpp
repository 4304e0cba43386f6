// tachi-sim's live stage as a class (the ROS 2 composition style: the process is a deployment choice, the
// stage is this object): a Session on the DDS bus, strokes in; topology, state, cut events and the scene
// object out. Its timing policies are tested alone (live_policies.hpp); tests/sim/sim_live_test.cpp runs it
// as the tachi-sim process. Linked from tachi_sim_node, which adds DDS to the pure tachi_sim.
#pragma once

#include "tachi/sim/options.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace tachi::bus {
class Participant;
}

namespace tachi::sim {

/// What the live stage adds to the options it shares with the offline driver.
struct LiveOptions {
  std::uint32_t cloth_id = 1;
  int state_every = 1;            ///< publish the cloth state every Nth step
  double duration_s = 0.0;        ///< stop after this long (0: until SIGINT/SIGTERM)
  double exit_when_idle_s = 0.0;  ///< stop when no hand sample arrived for this long after the first (0: never)
  float hand_radius_m = 0.0F;     ///< the idle hand as a collider sphere (0: off)
  std::string journal;            ///< replay then append every applied hand sample here (empty: no journal)
  std::optional<int> max_steps;   ///< stop after this many solver steps (--steps given in live mode)
};

class SimNode {
 public:
  /// Replays the journal (when given) into a new session, then joins `dds`: the initial topology (and the
  /// object) go out now. `dds` must outlive the node.
  SimNode(const OfflineOptions& shared, const LiveOptions& live, bus::Participant& dds);
  ~SimNode();
  SimNode(const SimNode&) = delete;
  SimNode& operator=(const SimNode&) = delete;

  /// Waits for strokes until the next solver step is due, applies them, steps and publishes.
  /// False once the run should end (--steps, --duration, --exit-when-idle).
  bool spin_once();
  /// Closes the open stroke, publishes the last topology, cuts and state, waits (1 s at most) for readers
  /// to acknowledge them; writes cloth.obj and summary.json when `shared.export_dir` is set. The exit code.
  int finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tachi::sim
