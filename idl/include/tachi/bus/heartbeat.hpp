// A process's heartbeat on tachi/node/status: its state and message counters once a period and
// whenever its state changes, and NODE_STOPPING when it goes away cleanly. Readers see a process
// that died without saying so through the Status profile's 3 s liveliness lease.
// Besides the counters, a node reports named figures (`set_metric`, e.g. "frames", "latency_p50_ms")
// and rejected inputs by reason (`count_rejected`); both ride along with the next publication.
#pragma once

#include "tachi/bus/topics.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace tachi::bus {

class Heartbeat {
 public:
  Heartbeat(const Participant& participant, std::string node, std::chrono::milliseconds period = std::chrono::seconds(1));
  ~Heartbeat();  // publishes NODE_STOPPING
  Heartbeat(const Heartbeat&) = delete;
  Heartbeat& operator=(const Heartbeat&) = delete;

  /// Publishes when the period has passed or the state changed; cheap to call every loop iteration.
  void update(tachi_msg_NodeState state, std::uint64_t messages_in, std::uint64_t messages_out,
              const std::string& detail = {});

  /// Sets a named figure (added on first use; at most 64 per node, names up to 39 characters).
  void set_metric(std::string_view name, double value);
  /// Counts one rejected input under `reason` (metric "rejected.<reason>") and in the total.
  void count_rejected(std::string_view reason, std::uint64_t n = 1);
  [[nodiscard]] std::uint64_t rejected() const noexcept { return status_.rejected; }
  /// The next update() publishes whatever the period: for an event a monitor should see at once.
  void publish_at_next_update() noexcept { last_ = {}; }

 private:
  void publish();
  Writer<tachi_msg_NodeStatus> writer_;
  tachi_msg_NodeStatus status_{};
  std::vector<tachi_msg_Metric> metrics_;
  std::chrono::milliseconds period_;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace tachi::bus
