#include "tachi/bus/heartbeat.hpp"

#include "tachi/common/process.hpp"

#include <unistd.h>

#include <cstdio>

namespace tachi::bus {

Heartbeat::Heartbeat(const Participant& participant, std::string node, std::chrono::milliseconds period)
    : writer_(participant, topics::node_status), period_(period) {
  std::snprintf(status_.node, sizeof status_.node, "%s", node.c_str());
  status_.pid = static_cast<std::uint32_t>(getpid());
  char host[sizeof status_.host] = {};
  if (gethostname(host, sizeof host - 1) == 0) std::snprintf(status_.host, sizeof status_.host, "%s", host);
  metrics_.reserve(64);  // publish() points the sequence at this buffer: it must not move
  status_.state = tachi_msg_NODE_STARTING;
  publish();
}

Heartbeat::~Heartbeat() {
  try {
    status_.state = tachi_msg_NODE_STOPPING;
    publish();
    // Stopped by a signal, the readers (the launcher, the monitor) may be going too: a shorter goodbye
    // keeps the whole stop within a second.
    writer_.wait_for_acks(std::chrono::milliseconds(common::stop_requested() ? 50 : 200));
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

void Heartbeat::set_metric(std::string_view name, double value) {
  for (auto& m : metrics_) {
    if (name == m.name) {
      m.value = value;
      return;
    }
  }
  if (metrics_.size() == metrics_.capacity()) return;  // the IDL bounds the sequence at 64
  tachi_msg_Metric m{};
  std::snprintf(m.name, sizeof m.name, "%.*s", static_cast<int>(name.size()), name.data());
  m.value = value;
  metrics_.push_back(m);
}

void Heartbeat::count_rejected(std::string_view reason, std::uint64_t n) {
  status_.rejected += n;
  const std::string name = "rejected." + std::string(reason);
  for (auto& m : metrics_) {
    if (name == m.name) {
      m.value += static_cast<double>(n);
      return;
    }
  }
  set_metric(name, static_cast<double>(n));
}

void Heartbeat::publish() {
  status_.metrics._buffer = metrics_.data();
  status_.metrics._length = status_.metrics._maximum = static_cast<std::uint32_t>(metrics_.size());
  status_.metrics._release = false;
  status_.time_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  writer_.write(status_);
  last_ = std::chrono::steady_clock::now();
}

}  // namespace tachi::bus
