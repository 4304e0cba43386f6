// Waiting on samples instead of sleeping: a multi-process test acts when the bus shows the event it
// needs (the sensor is publishing, the hand is cutting), with a deadline, so it neither races a slow
// machine nor idles on a fast one. Readers made for this should be created after
// `bus::read_every_run()` when the nodes run under `tachi run` (each run has its own partition).
#pragma once

#include "tachi/bus/bus.hpp"
#include "tachi/bus/topics.hpp"

#include <chrono>
#include <functional>

namespace tachi::test {

/// Takes the samples waiting in `reader` (waiting up to `timeout` for the first) and returns how many
/// satisfy `counts`.
template <class T>
int take_matching(bus::Reader<T>& reader, const std::function<bool(const T&)>& counts, std::chrono::milliseconds timeout) {
  reader.wait_for_data(std::chrono::duration_cast<std::chrono::nanoseconds>(timeout));
  int n = 0;
  for (const auto& s : reader.take(256)) n += counts(*s) ? 1 : 0;
  return n;
}

/// Takes samples until `at_least` of them satisfied `counts`, `keep_going` turned false or `timeout`
/// passed; returns how many did.
template <class T>
int wait_for_matching(bus::Reader<T>& reader, int at_least, const std::function<bool(const T&)>& counts,
                      std::chrono::milliseconds timeout, const std::function<bool()>& keep_going = [] { return true; }) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int n = 0;
  while (n < at_least && std::chrono::steady_clock::now() < deadline && keep_going())
    n += take_matching(reader, counts, std::chrono::milliseconds(100));
  return n;
}

/// A stroke sample taken while the gate was cutting (the hand on the cloth, the stroke open).
inline bool is_cutting(const tachi_msg_StrokeSample& s) { return s.gate == tachi_msg_GATE_CUTTING; }

}  // namespace tachi::test
