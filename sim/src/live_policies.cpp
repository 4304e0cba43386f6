#include "tachi/sim/live_policies.hpp"

#include <algorithm>

namespace tachi::sim {

TopologyRate::TopologyRate(LiveClock::time_point now, double rate_hz, double burst, LiveClock::duration keyframe_period)
    : rate_hz_(rate_hz), burst_(burst), keyframe_period_(keyframe_period), tokens_(burst), last_refill_(now),
      last_keyframe_(now) {}

bool TopologyRate::delta_allowed(LiveClock::time_point now) {
  tokens_ = std::min(burst_, tokens_ + rate_hz_ * std::chrono::duration<double>(now - last_refill_).count());
  last_refill_ = now;
  return tokens_ >= 1.0;
}

void TopologyRate::delta_sent() {
  tokens_ -= 1.0;
  keyframe_owed_ = true;
}

bool TopologyRate::take_keyframe(LiveClock::time_point now) {
  if (!keyframe_owed_ || now - last_keyframe_ < keyframe_period_) return false;
  keyframe_owed_ = false;
  last_keyframe_ = now;
  return true;
}

StrokePublisherGrace::Verdict StrokePublisherGrace::on_sample(std::uint64_t session_id, bool cutting) {
  if (cutting) cutting_session_ = session_id;
  if (gone_at_ && session_id == gone_session_) {
    gone_at_.reset();
    return Verdict::PublisherBack;
  }
  return Verdict::None;
}

StrokePublisherGrace::Verdict StrokePublisherGrace::tick(bool has_publisher, bool stroke_open, LiveClock::time_point now) {
  Verdict verdict = Verdict::None;
  if (had_publisher_ && !has_publisher && stroke_open) {
    gone_at_ = now;
    gone_session_ = cutting_session_;
    verdict = Verdict::PublisherGone;
  }
  had_publisher_ = has_publisher;
  if (gone_at_ && now - *gone_at_ > grace_) {
    gone_at_.reset();
    return stroke_open && cutting_session_ == gone_session_ ? Verdict::CloseStroke : Verdict::GraceOver;
  }
  return verdict;
}

bool ReplayedSamples::already_applied(std::uint32_t sensor_id, std::uint64_t session_id, std::int64_t time_ns) const {
  const auto it = newest_.find({sensor_id, session_id});
  return it != newest_.end() && time_ns <= it->second;
}

bool StepSchedule::stepped(LiveClock::time_point now) {
  next_ += period_;
  if (now - next_ > max_backlog_ * period_) {
    next_ = now + period_;
    ++overruns_;
    return true;
  }
  return false;
}

void IdleEnd::hand_sample(LiveClock::time_point now) {
  had_sample_ = true;
  last_activity_ = std::max(last_activity_, now);
}

void IdleEnd::source_status(const std::string& node, bool starting, LiveClock::time_point now) {
  if (starting) {
    starting_since_.try_emplace(node, now);  // a repeated STARTING heartbeat does not extend the hold
    return;
  }
  if (starting_since_.erase(node) > 0) last_activity_ = std::max(last_activity_, now);
}

bool IdleEnd::over(LiveClock::time_point now) const {
  if (!had_sample_) return false;
  for (const auto& [node, since] : starting_since_)
    if (now - since < max_hold_) return false;
  return now - last_activity_ > settle_;
}

}  // namespace tachi::sim
