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

}  // namespace tachi::common
