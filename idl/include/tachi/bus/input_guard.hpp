// Validation at a node's DDS boundary (docs/reliability.md): a peer may be faulty or hostile, so
// every sample is checked before the node's logic sees it, and each refusal is counted by reason
// in the node's heartbeat ("rejected.<reason>", Heartbeat::count_rejected) and logged, rate-limited.
// Reasons: nonfinite, out_of_range, time_backwards, time_ahead, stale_id, oversized, too_many_sources.
//
// No single sample can poison a guard: a time more than the clock skew (kClockSkew_ns, 1 s) ahead of
// where the source's clock should be (its last accepted time plus the time the receiver's steady clock
// has run since) is refused as `time_ahead`, and a source whose samples have all been refused (back in
// time, ahead, stale ids) for longer than the skew starts afresh from the next one, so even a poisoned
// baseline (the first sample of a source stamped INT64_MAX) locks the source out for at most the skew.
// Pure logic: the sink is any callable, so it is tested without DDS.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
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

  /// How far a source's clock may run ahead of the receiver's between two samples, and the longest a
  /// source is locked out by refusals before it starts afresh.
  static constexpr std::int64_t kClockSkew_ns = 1'000'000'000;

  /// The receiver's clock the guard compares with (steady: a wall-clock step must not refuse a source).
  [[nodiscard]] static std::int64_t now_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
  }

  explicit InputGuard(Sink sink, std::int64_t skew_ns = kClockSkew_ns) : sink_(std::move(sink)), skew_ns_(skew_ns) {}

  /// A position is finite and within `limit_m` of the origin on every axis.
  bool position(float x, float y, float z, float limit_m) {
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return reject("nonfinite");
    if (std::abs(x) > limit_m || std::abs(y) > limit_m || std::abs(z) > limit_m) return reject("out_of_range");
    return true;
  }
  /// Every xyz triple of `xyz` (n floats) is a finite position within `limit_m` (a cloth state).
  bool positions(const float* xyz, std::size_t n, float limit_m) {
    bool finite = true, near = true;
    for (std::size_t i = 0; i < n; ++i) {  // one pass, no early exit: vectorises (a 128 x 128 state is 49 k floats)
      finite &= std::isfinite(xyz[i]);
      near &= std::abs(xyz[i]) <= limit_m;
    }
    if (!finite) return reject("nonfinite");
    if (!near) return reject("out_of_range");
    return true;
  }
  /// The time of `source`'s samples never goes back (equal is fine: one frame may be sent twice) and
  /// never leaps ahead of the source's expected clock by more than the skew; `now_ns` is the
  /// receiver's steady clock. A source played faster than real time (a recording at `--rate max`)
  /// passes: only each step is compared, never the sum.
  /// With `restart_gap_ns` > 0, a jump back by more than that is a restarted source whose clock
  /// starts again (a sensor replaying its recording from the top): accepted, and the source starts afresh.
  bool time(std::uint64_t source, std::int64_t time_ns, std::int64_t now_ns, std::int64_t restart_gap_ns = 0) {
    auto* last = slot(source);
    if (last == nullptr) return false;
    if (last->seen) {
      // Differences as unsigned: exact for any two int64 times (INT64_MAX - INT64_MIN), no overflow.
      const auto u = [](std::int64_t v) { return static_cast<std::uint64_t>(v); };
      const bool back = time_ns < last->time_ns;
      const std::uint64_t back_by = back ? u(last->time_ns) - u(time_ns) : 0;
      const std::uint64_t ahead_by = back ? 0 : u(time_ns) - u(last->time_ns);
      const std::uint64_t allowed_ahead = u(std::max<std::int64_t>(now_ns - last->accepted_at_ns, 0)) + u(skew_ns_);
      const bool restarted = restart_gap_ns > 0 && back_by > u(restart_gap_ns);
      const char* why = nullptr;
      if (back && !restarted) why = "time_backwards";
      else if (ahead_by > allowed_ahead) why = "time_ahead";
      if (why != nullptr && !locked_out_too_long(last->refusing_since_ns, now_ns)) return reject(why);
    }
    *last = {true, time_ns, now_ns, kNotRefusing};
    return true;
  }
  /// `source`'s ids (e.g. stroke ids) never go back: a lower one names a stroke that already ended.
  /// Refused for longer than the skew, the source starts afresh (a poisoned id cannot end all cutting).
  bool id(std::uint64_t source, std::uint64_t value, std::int64_t now_ns) {
    const auto it = last_id_.find(source);
    if (it == last_id_.end()) {
      if (last_id_.size() >= kMaxSources) return reject("too_many_sources");
      last_id_[source] = {value, kNotRefusing};
      return true;
    }
    if (value < it->second.value && !locked_out_too_long(it->second.refusing_since_ns, now_ns)) return reject("stale_id");
    it->second = {value, kNotRefusing};
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
  static constexpr std::int64_t kNotRefusing = std::numeric_limits<std::int64_t>::min();
  struct TimeTrack {
    bool seen = false;
    std::int64_t time_ns = 0;         // the last accepted sample's time (the source's clock)
    std::int64_t accepted_at_ns = 0;  // when it was accepted (the receiver's clock)
    std::int64_t refusing_since_ns = kNotRefusing;  // first refusal since then
  };
  struct IdTrack {
    std::uint64_t value = 0;
    std::int64_t refusing_since_ns = kNotRefusing;
  };
  /// Marks a refusal at `now_ns`; true once refusals have gone on for longer than the skew.
  bool locked_out_too_long(std::int64_t& refusing_since_ns, std::int64_t now_ns) {
    if (refusing_since_ns == kNotRefusing) refusing_since_ns = now_ns;
    return now_ns - refusing_since_ns > skew_ns_;
  }
  TimeTrack* slot(std::uint64_t source) {
    const auto it = last_time_.find(source);
    if (it != last_time_.end()) return &it->second;
    if (last_time_.size() >= kMaxSources) {
      reject("too_many_sources");
      return nullptr;
    }
    return &last_time_[source];
  }
  Sink sink_;
  std::int64_t skew_ns_;
  std::map<std::uint64_t, TimeTrack> last_time_;
  std::map<std::uint64_t, IdTrack> last_id_;
  std::uint64_t rejected_ = 0;
};

}  // namespace tachi::bus
