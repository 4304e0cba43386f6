#include "tachi/viewer/live_policies.hpp"

#include <algorithm>
#include <cmath>

namespace tachi::viewer {
using namespace std::chrono_literals;

FrameSchedule::FrameSchedule(double fps, Clock::time_point start)
    : period_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / fps))), next_(start) {}

bool FrameSchedule::due(Clock::time_point now) {
  if (now < next_) return false;
  next_ += period_;
  if (now - next_ > 5 * period_) next_ = now + period_;  // fell behind: do not race
  return true;
}

Clock::duration FrameSchedule::wait(Clock::time_point now) const {
  return std::clamp(next_ - now, Clock::duration(1ms), Clock::duration(100ms));
}

std::uint64_t video_frames_due(double elapsed_s, double fps) {
  // 1e-6: a frame shown exactly at its slot (t = k / fps in floating point) counts as due.
  return static_cast<std::uint64_t>(std::floor(std::max(elapsed_s, 0.0) * fps + 1e-6)) + 1;
}

std::string ClothWatch::warning(Clock::time_point now) const {
  const auto without = without_state(now);
  if (without <= kHudAfter) return {};
  return "no cloth state for " + std::to_string(static_cast<int>(std::chrono::duration<double>(without).count())) +
         " s: is tachi-sim running on domain " + std::to_string(domain_) + "?";
}

bool ClothWatch::log_due(Clock::time_point now) {
  if (without_state(now) <= kHudAfter || now - last_log_ <= kLogPeriod) return false;
  last_log_ = now;
  return true;
}

bool RunLimits::over(Clock::duration running, std::uint64_t states_received, Clock::duration without_state) const {
  if (duration_s > 0 && running > std::chrono::duration<double>(duration_s)) return true;
  return exit_when_idle_s > 0 && states_received > 0 && without_state > std::chrono::duration<double>(exit_when_idle_s);
}

std::optional<BladeSample> MouseControl::counted(std::optional<BladeSample> sample) {
  if (sample) ++samples_;
  return sample;
}

std::optional<BladeSample> MouseControl::on_event(const MouseEvent& e, const Mesh& mesh, View& view) {
  std::optional<BladeSample> sample;
  switch (e.kind) {
    case MouseEvent::LeftDown:
      if (blade_enabled_) sample = blade_.press(mesh, view, e.pixel);
      else drag_ = Drag::Orbit;
      break;
    case MouseEvent::RightDown: drag_ = blade_enabled_ && !e.shift ? Drag::Orbit : Drag::Pan; break;
    case MouseEvent::LeftUp:
      if (blade_enabled_) sample = blade_.release(mesh, view, e.pixel);
      drag_ = Drag::None;
      break;
    case MouseEvent::RightUp: drag_ = Drag::None; break;
    case MouseEvent::Wheel: view.zoom(e.wheel > 0 ? 1.15F : 1.0F / 1.15F); break;
    case MouseEvent::Move:
      if (blade_enabled_) sample = blade_.move(mesh, view, e.pixel);
      if (drag_ == Drag::Orbit) orbit_by_drag(view, e.pixel.x - last_.x, e.pixel.y - last_.y);
      if (drag_ == Drag::Pan) view.pan(e.pixel.x - last_.x, e.pixel.y - last_.y);
      break;
  }
  last_ = e.pixel;
  return counted(sample);
}

std::optional<BladeSample> MouseControl::hold(const Mesh& mesh, const View& view) {
  return counted(blade_.move(mesh, view, last_));
}

std::optional<BladeSample> MouseControl::finish(const Mesh& mesh, const View& view) {
  return counted(blade_.release(mesh, view, last_));
}

std::optional<BladeCursor> MouseControl::cursor() const {
  if (!blade_enabled_ || last_.x < 0.0F) return std::nullopt;
  return BladeCursor{last_, blade_.cutting()};
}

std::string MouseControl::label() const {
  if (!blade_enabled_) return {};
  return blade_.cutting() ? "(mouse, cutting)" : "(mouse)";
}

}  // namespace tachi::viewer
