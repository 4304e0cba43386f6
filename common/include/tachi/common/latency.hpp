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

/// Every value of a run, in constant memory: durations (ms) counted in buckets 1 % wide on a log scale
/// from 1 us to a minute (~1,800 counters), so a quantile is within 1 % of the exact one however long the
/// run (an hour of 60 Hz steps kept as values grew the simulator by ~2 MB). Below the range counts as its
/// floor, above as its ceiling; the minimum and maximum are exact.
class DurationHistogram {
 public:
  DurationHistogram();

  /// Adds one duration in ms; a non-finite or negative one is not counted.
  void add_ms(double ms);

  [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
  [[nodiscard]] double max_ms() const noexcept { return count_ ? max_ : 0.0; }
  /// The value of rank round(q (n - 1)) in sorted order (0 <= q <= 1), as summary percentiles take it,
  /// within the bucket's 1 %; 0 when empty.
  [[nodiscard]] double quantile(double q) const;

 private:
  [[nodiscard]] std::size_t bucket_of(double ms) const;
  std::vector<std::uint64_t> counts_;
  std::uint64_t count_ = 0;
  double min_ = 0.0, max_ = 0.0;
};

}  // namespace tachi::common
