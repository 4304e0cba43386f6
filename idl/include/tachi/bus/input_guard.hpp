// Validation at a node's DDS boundary (docs/reliability.md): a peer may be faulty or hostile, so
// every sample is checked before the node's logic sees it, and each refusal is counted by reason
// in the node's heartbeat ("rejected.<reason>", Heartbeat::count_rejected) and logged, rate-limited.
// Reasons: nonfinite, out_of_range, time_backwards, stale_id, oversized, too_many_sources.
// Pure logic: the sink is any callable, so it is tested without DDS.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <string_view>
#include <utility>

namespace tachi::bus {

class InputGuard {
 public:
  using Sink = std::function<void(std::string_view reason)>;
  /// At most this many sources (sensor ids, sessions) are tracked: a flood of made-up keys must not
  /// grow memory without bound.
  static constexpr std::size_t kMaxSources = 64;

  explicit InputGuard(Sink sink) : sink_(std::move(sink)) {}

  /// A position is finite and within `limit_m` of the origin on every axis.
  bool position(float x, float y, float z, float limit_m) {
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return reject("nonfinite");
    if (std::abs(x) > limit_m || std::abs(y) > limit_m || std::abs(z) > limit_m) return reject("out_of_range");
    return true;
  }
  /// The time of `source`'s samples never goes back (equal is fine: one frame may be sent twice).
  /// With `restart_gap_ns` > 0, a jump back by more than that is a restarted source whose clock
  /// starts again (a sensor replaying its recording from the top): accepted, and the source starts afresh.
  bool time(std::uint64_t source, std::int64_t time_ns, std::int64_t restart_gap_ns = 0) {
    auto* last = slot(source);
    if (last == nullptr) return false;
    const bool restarted = restart_gap_ns > 0 && last->second - time_ns > restart_gap_ns;
    if (last->first && time_ns < last->second && !restarted) return reject("time_backwards");
    *last = {true, time_ns};
    return true;
  }
  /// `source`'s ids (e.g. stroke ids) never go back: a lower one names a stroke that already ended.
  bool id(std::uint64_t source, std::uint64_t value) {
    const auto it = last_id_.find(source);
    if (it == last_id_.end()) {
      if (last_id_.size() >= kMaxSources) return reject("too_many_sources");
      last_id_[source] = value;
      return true;
    }
    if (value < it->second) return reject("stale_id");
    it->second = value;
    return true;
  }
  /// A sequence's length is at most `max` (and, with `multiple_of`, a multiple of it).
  bool size(std::size_t n, std::size_t max, std::size_t multiple_of = 1) {
    if (n > max || n % multiple_of != 0) return reject("oversized");
    return true;
  }
  /// Counts a refusal the caller decided on; returns false so `return guard.reject(...)` reads well.
  bool reject(std::string_view reason) {
    ++rejected_;
    if (sink_) sink_(reason);
    return false;
  }
  /// Forgets a source (e.g. its session ended), so its next time starts afresh.
  void forget(std::uint64_t source) {
    last_time_.erase(source);
    last_id_.erase(source);
  }
  [[nodiscard]] std::uint64_t rejected() const noexcept { return rejected_; }

 private:
  std::pair<bool, std::int64_t>* slot(std::uint64_t source) {
    const auto it = last_time_.find(source);
    if (it != last_time_.end()) return &it->second;
    if (last_time_.size() >= kMaxSources) {
      reject("too_many_sources");
      return nullptr;
    }
    return &last_time_[source];
  }
  Sink sink_;
  std::map<std::uint64_t, std::pair<bool, std::int64_t>> last_time_;
  std::map<std::uint64_t, std::uint64_t> last_id_;
  std::uint64_t rejected_ = 0;
};

}  // namespace tachi::bus
