// Waiting on a node's heartbeat (tachi/node/status) instead of sleeping: a multi-process test waits for
// the event it needs (the node is up, it has the cloth, it rejected N inputs, it rendered N more frames)
// with a deadline, so it neither races a slow machine nor idles on a fast one.
#pragma once

#include "tachi/bus/bus.hpp"
#include "tachi/bus/topics.hpp"

#include <chrono>
#include <functional>
#include <optional>
#include <string>

namespace tachi::test {

/// The value of the named figure in a heartbeat, if the node reports it.
inline std::optional<double> metric(const tachi_msg_NodeStatus& s, const std::string& name) {
  for (std::uint32_t i = 0; i < s.metrics._length; ++i)
    if (name == s.metrics._buffer[i].name) return s.metrics._buffer[i].value;
  return std::nullopt;
}

/// Takes `node`'s heartbeats from `status` until one satisfies `done` (true) or `timeout` passes
/// (false). Heartbeats of other nodes are dropped.
inline bool wait_for_status(bus::Reader<tachi_msg_NodeStatus>& status, const std::string& node,
                            const std::function<bool(const tachi_msg_NodeStatus&)>& done,
                            std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    for (const auto& s : status.take(256))
      if (node == s->node && done(*s)) return true;
    status.wait_for_data(std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - std::chrono::steady_clock::now()));
  }
  return false;
}

/// `node`'s figure `name` once it is >= `at_least` (nullopt at the deadline).
inline std::optional<double> wait_for_metric(bus::Reader<tachi_msg_NodeStatus>& status, const std::string& node,
                                             const std::string& name, double at_least, std::chrono::milliseconds timeout) {
  std::optional<double> seen;
  if (!wait_for_status(status, node, [&](const tachi_msg_NodeStatus& s) {
        seen = metric(s, name);
        return seen && *seen >= at_least;
      }, timeout))
    return std::nullopt;
  return seen;
}

/// The latest value of `node`'s counter `name` (the largest in the heartbeats waiting to be taken; it
/// waits for one if none is), or nullopt at the deadline.
inline std::optional<double> latest_metric(bus::Reader<tachi_msg_NodeStatus>& status, const std::string& node,
                                           const std::string& name, std::chrono::milliseconds timeout) {
  std::optional<double> latest;
  const auto keep_largest = [&](const tachi_msg_NodeStatus& s) {
    if (const auto v = metric(s, name); v && (!latest || *v > *latest)) latest = v;
    return false;
  };
  wait_for_status(status, node, [&](const tachi_msg_NodeStatus& s) { keep_largest(s); return latest.has_value(); }, timeout);
  for (const auto& s : status.take(256))
    if (node == s->node) keep_largest(*s);
  return latest;
}

}  // namespace tachi::test
