// The live viewer's policies, pure so they are tested without a window or a bus: when a frame is due and
// how long to wait for input, how many video frames a rendered image stands for, when a held mouse blade
// repeats its sample, what the viewer says when the cloth stops arriving, when the run is over, and the
// window's mouse (orbit/pan/zoom, or seed 001's blade). ViewerNode (node.hpp) applies them.
#pragma once

#include "tachi/viewer/controls.hpp"

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace tachi::viewer {

using Clock = std::chrono::steady_clock;

/// One of the window's mouse events (the window queues them; the node applies them).
struct MouseEvent {
  enum Kind { Move, LeftDown, LeftUp, RightDown, RightUp, Wheel } kind = Move;
  cv::Point2f pixel;
  int wheel = 0;  ///< > 0 away from the user (zoom in)
  bool shift = false;
};

/// Frames at --fps: `due` says whether to render now and moves to the next slot; a viewer more than five
/// frames behind (a busy machine) starts again from now rather than racing to catch up.
class FrameSchedule {
 public:
  FrameSchedule(double fps, Clock::time_point start);
  bool due(Clock::time_point now);
  /// How long to wait for input before the next look: until the next frame, at least 1 ms, at most 100 ms
  /// (a signal does not wake a DDS waitset, and at --fps 1 a frame is too long to stop in).
  [[nodiscard]] Clock::duration wait(Clock::time_point now) const;

 private:
  Clock::duration period_;
  Clock::time_point next_;
};

/// The number of video frames written once an image is shown `elapsed_s` after the video's first frame:
/// frame k stands for time k / fps, so a viewer that renders slower than --fps still makes a video that
/// plays at the speed the run went, and a frame rendered before its slot waits for the next call.
std::uint64_t video_frames_due(double elapsed_s, double fps);

/// A held, unmoving mouse blade repeats its sample this often (tachi-sim lets another source take over
/// after 1 s of silence).
class BladeHold {
 public:
  static constexpr Clock::duration kPeriod = std::chrono::milliseconds(250);
  explicit BladeHold(Clock::time_point start) : last_(start) {}
  void sent(Clock::time_point now) { last_ = now; }
  [[nodiscard]] bool due(Clock::time_point now) const { return now - last_ > kPeriod; }

 private:
  Clock::time_point last_;
};

/// What the viewer says while no cloth state arrives: the HUD's warning after 3 s, the log's every 5 s.
class ClothWatch {
 public:
  static constexpr Clock::duration kHudAfter = std::chrono::seconds(3);
  static constexpr Clock::duration kLogPeriod = std::chrono::seconds(5);
  ClothWatch(unsigned domain, Clock::time_point start) : domain_(domain), last_state_(start), last_log_(start - kLogPeriod) {}
  void state_arrived(Clock::time_point now) { last_state_ = now; }
  /// The warning for the HUD and the heartbeat (empty while the cloth arrives).
  [[nodiscard]] std::string warning(Clock::time_point now) const;
  /// True when the warning is due in the log now (then not again for 5 s).
  bool log_due(Clock::time_point now);
  [[nodiscard]] Clock::duration without_state(Clock::time_point now) const { return now - last_state_; }

 private:
  unsigned domain_;
  Clock::time_point last_state_;
  Clock::time_point last_log_;
};

/// --duration and --exit-when-idle (0: off): the run is over after `duration_s`, or once no cloth state
/// arrived for `exit_when_idle_s` after the first one (a viewer started before the simulator waits).
struct RunLimits {
  double duration_s = 0.0;
  double exit_when_idle_s = 0.0;
  [[nodiscard]] bool over(Clock::duration running, std::uint64_t states_received, Clock::duration without_state) const;
};

/// The window's mouse: orbit/pan/zoom the view, or (blade on) cut with the left button (seed 001), the
/// right button orbiting (with shift: panning).
class MouseControl {
 public:
  explicit MouseControl(bool blade) : blade_enabled_(blade) {}

  /// Applies one event; the blade sample to publish, if any.
  std::optional<BladeSample> on_event(const MouseEvent& e, const Mesh& mesh, View& view);
  /// While the button is held still, the same spot again (re-cast: the cloth moves under it), so the
  /// simulator does not take the mouse for a source that fell silent mid-stroke.
  std::optional<BladeSample> hold(const Mesh& mesh, const View& view);
  /// The sample that ends a stroke still open when the viewer stops.
  std::optional<BladeSample> finish(const Mesh& mesh, const View& view);
  [[nodiscard]] std::optional<BladeCursor> cursor() const;
  /// "(mouse)" or "(mouse, cutting)" after the simulator's blade in the HUD; empty without the blade.
  [[nodiscard]] std::string label() const;
  /// Blade samples handed out so far (the samples' frame numbers).
  [[nodiscard]] std::uint64_t samples() const { return samples_; }

 private:
  std::optional<BladeSample> counted(std::optional<BladeSample> sample);
  enum class Drag { None, Orbit, Pan };
  bool blade_enabled_;
  MouseBlade blade_;
  Drag drag_ = Drag::None;
  cv::Point2f last_{-1.0F, -1.0F};
  std::uint64_t samples_ = 0;
};

}  // namespace tachi::viewer
