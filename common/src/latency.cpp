#include "tachi/common/latency.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace tachi::common {

std::int64_t wall_clock_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

LatencyWindow::LatencyWindow(std::size_t capacity) : capacity_(std::max<std::size_t>(capacity, 1)) {
  values_.reserve(capacity_);
  scratch_.reserve(capacity_);
}

void LatencyWindow::add_since(std::int64_t since_ns, std::int64_t now_ns) {
  constexpr std::int64_t kMinuteNs = 60'000'000'000;
  if (since_ns <= 0) return;
  const std::int64_t delay = now_ns - since_ns;
  if (delay < 0 || delay > kMinuteNs) return;
  add_ms(static_cast<double>(delay) * 1e-6);
}

void LatencyWindow::add_ms(double ms) {
  if (!std::isfinite(ms)) return;
  if (values_.size() < capacity_) {
    values_.push_back(ms);
  } else {
    values_[next_] = ms;  // a ring: the window follows the run instead of freezing on its start
    next_ = (next_ + 1) % capacity_;
  }
  ++total_;
}

double LatencyWindow::percentile(double p) const {
  if (values_.empty()) return 0.0;
  // Called per frame by the stages (their heartbeat figures): a scratch copy that keeps its capacity
  // instead of an 8 KB allocation per call.
  std::vector<double>& sorted = scratch_;
  sorted.assign(values_.begin(), values_.end());
  const auto rank = static_cast<std::size_t>(std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(sorted.size())));
  const std::size_t k = rank == 0 ? 0 : rank - 1;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(k), sorted.end());
  return sorted[k];
}

namespace {
constexpr double kFloorMs = 1e-3;      // 1 us
constexpr double kCeilingMs = 60'000;  // a minute
const double kLogGrowth = std::log1p(0.01);  // each bucket 1 % wider than the one below
}  // namespace

DurationHistogram::DurationHistogram()
    : counts_(static_cast<std::size_t>(std::ceil(std::log(kCeilingMs / kFloorMs) / kLogGrowth)) + 1, 0) {}

std::size_t DurationHistogram::bucket_of(double ms) const {
  const double clamped = std::clamp(ms, kFloorMs, kCeilingMs);
  const auto b = static_cast<std::size_t>(std::log(clamped / kFloorMs) / kLogGrowth);
  return std::min(b, counts_.size() - 1);
}

void DurationHistogram::add_ms(double ms) {
  if (!std::isfinite(ms) || ms < 0.0) return;
  ++counts_[bucket_of(ms)];
  min_ = count_ == 0 ? ms : std::min(min_, ms);
  max_ = count_ == 0 ? ms : std::max(max_, ms);
  ++count_;
}

double DurationHistogram::quantile(double q) const {
  if (count_ == 0) return 0.0;
  const auto rank = static_cast<std::uint64_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(count_ - 1) + 0.5);
  if (rank == 0) return min_;
  if (rank == count_ - 1) return max_;
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < counts_.size(); ++b) {
    seen += counts_[b];
    if (seen > rank) {
      // The bucket's geometric middle, never outside what was seen.
      const double mid = kFloorMs * std::exp((static_cast<double>(b) + 0.5) * kLogGrowth);
      return std::clamp(mid, min_, max_);
    }
  }
  return max_;
}

}  // namespace tachi::common
