// Per-stage latency figures for the heartbeats: each stage keeps the delays of its recent outputs
// (capture of the depth frame -> this stage's output, ms) and reports their median and 99th
// percentile. Clocks: CLOCK_REALTIME (wall clock), so one host compares exactly and several hosts
// compare up to their clock offset (docs/dds.md "Latency").
#pragma once

#include <cstdint>
#include <cstddef>
#include <vector>

namespace tachi::common {

/// Wall-clock time now, ns since the epoch (what `acquired_ns`/`published_ns` carry).
[[nodiscard]] std::int64_t wall_clock_ns();

/// The last `capacity` delays in milliseconds, with nearest-rank percentiles over them.
class LatencyWindow {
 public:
  explicit LatencyWindow(std::size_t capacity = 1024);

  /// Adds `now_ns - since_ns`; ignores a missing stamp (since_ns <= 0) and delays that are negative
  /// or longer than a minute (another host's clock, or a stamp that is not a time).
  void add_since(std::int64_t since_ns, std::int64_t now_ns);
  void add_ms(double ms);

  [[nodiscard]] std::size_t size() const noexcept { return values_.size(); }
  [[nodiscard]] std::uint64_t total() const noexcept { return total_; }
  /// The window's delays, ms (not in arrival order once it wrapped).
  [[nodiscard]] const std::vector<double>& values() const noexcept { return values_; }
  /// Nearest-rank percentile (0 < p <= 100) of the window; 0 when empty.
  [[nodiscard]] double percentile(double p) const;

 private:
  std::vector<double> values_;
  mutable std::vector<double> scratch_;  ///< percentile()'s working copy, reused
  std::size_t capacity_;
  std::size_t next_ = 0;
  std::uint64_t total_ = 0;
};

}  // namespace tachi::common
