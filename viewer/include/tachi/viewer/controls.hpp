// What the window's keys and mouse do, as pure functions of the event and the view, so the window
// code only forwards events (and tests need no display).
// The mouse blade is seed 001 section 3's interface: "a 2d spot on the screen near the mouse pointer
// is converted into 3d space" (here: onto the cloth's surface under the cursor, else onto the cloth's
// rest plane), the left button held cuts along the drag, releasing it ends the stroke.
#pragma once

#include "tachi/viewer/render.hpp"

#include <cstdint>
#include <optional>

namespace tachi::viewer {

enum class KeyAction { None, Quit, Snapshot, ToggleHelp, ViewChanged };

/// Applies a key from cv::waitKeyEx (letters, '+', '-', arrows of GTK/X11 or Qt) to the view;
/// `home` is the view `r` returns to.
KeyAction on_key(int key, View& view, const View& home);

/// Orbits by a mouse drag of (dx, dy) pixels (left drag without --mouse, right drag with it).
void orbit_by_drag(View& view, float dx_px, float dy_px);

/// One sample of the mouse blade for the hand-stroke topic.
struct BladeSample {
  std::uint32_t stroke_id = 0;          ///< grows by one with every press, like the filter's gate
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();
  bool cutting = false;
  bool outside_cloth = false;           ///< the cursor was off the cloth (taken onto the rest plane)
};

class MouseBlade {
 public:
  /// Left button down: opens a stroke at the spot under the cursor.
  std::optional<BladeSample> press(const Mesh& mesh, const View& view, cv::Point2f pixel);
  /// Cursor moved: a cutting sample while the button is held, nothing otherwise.
  std::optional<BladeSample> move(const Mesh& mesh, const View& view, cv::Point2f pixel);
  /// Left button up (or the window going away mid-stroke): the sample that closes the stroke.
  std::optional<BladeSample> release(const Mesh& mesh, const View& view, cv::Point2f pixel);

  [[nodiscard]] bool cutting() const { return cutting_; }
  [[nodiscard]] std::uint32_t stroke_id() const { return stroke_id_; }

 private:
  std::optional<BladeSample> locate(const Mesh& mesh, const View& view, cv::Point2f pixel, bool cutting);
  bool cutting_ = false;
  std::uint32_t stroke_id_ = 0;
  std::optional<Eigen::Vector3f> last_;
};

}  // namespace tachi::viewer
