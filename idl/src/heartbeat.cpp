#include "tachi/bus/heartbeat.hpp"

#include <unistd.h>

#include <cstdio>

namespace tachi::bus {

Heartbeat::Heartbeat(const Participant& participant, std::string node, std::chrono::milliseconds period)
    : writer_(participant, topics::node_status), period_(period) {
  std::snprintf(status_.node, sizeof status_.node, "%s", node.c_str());
  status_.pid = static_cast<std::uint32_t>(getpid());
  status_.state = tachi_msg_NODE_STARTING;
  publish();
}

Heartbeat::~Heartbeat() {
  try {
    status_.state = tachi_msg_NODE_STOPPING;
    publish();
    writer_.wait_for_acks(std::chrono::milliseconds(200));
  } catch (...) {
    // Going away anyway: a failed goodbye must not turn a clean exit into a crash.
  }
}

void Heartbeat::update(tachi_msg_NodeState state, std::uint64_t messages_in, std::uint64_t messages_out,
                       const std::string& detail) {
  const bool changed = state != status_.state;
  status_.state = state;
  status_.messages_in = messages_in;
  status_.messages_out = messages_out;
  std::snprintf(status_.detail, sizeof status_.detail, "%s", detail.c_str());
  if (changed || std::chrono::steady_clock::now() - last_ >= period_) publish();
}

void Heartbeat::publish() {
  status_.time_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  writer_.write(status_);
  last_ = std::chrono::steady_clock::now();
}

}  // namespace tachi::bus
