#include "tachi/viewer/controls.hpp"

namespace tachi::viewer {
namespace {
constexpr float kOrbitStep_rad = 0.1f;
constexpr float kPanStep_px = 20.0f;
constexpr float kZoomStep = 1.15f;
constexpr float kDragOrbit_rad_per_px = 0.01f;

// Arrow keys as cv::waitKeyEx reports them: GTK/X11 keysyms and Qt key codes.
enum Arrow : int { kLeftX = 0xff51, kUpX = 0xff52, kRightX = 0xff53, kDownX = 0xff54,
                   kLeftQt = 0x1000012, kUpQt = 0x1000013, kRightQt = 0x1000014, kDownQt = 0x1000015 };
}  // namespace

KeyAction on_key(int key, View& view, const View& home) {
  switch (key) {
    case 'q': case 'Q': case 27: return KeyAction::Quit;
    case 'p': case 'P': return KeyAction::Snapshot;
    case 'h': case 'H': return KeyAction::ToggleHelp;
    case 'a': case kLeftX: case kLeftQt: view.orbit(-kOrbitStep_rad, 0.0f); break;
    case 'd': case kRightX: case kRightQt: view.orbit(kOrbitStep_rad, 0.0f); break;
    case 'w': case kUpX: case kUpQt: view.orbit(0.0f, -kOrbitStep_rad); break;
    case 'x': case kDownX: case kDownQt: view.orbit(0.0f, kOrbitStep_rad); break;
    case 'i': view.pan(0.0f, -kPanStep_px); break;
    case 'k': view.pan(0.0f, kPanStep_px); break;
    case 'j': view.pan(-kPanStep_px, 0.0f); break;
    case 'l': view.pan(kPanStep_px, 0.0f); break;
    case '+': case '=': view.zoom(kZoomStep); break;
    case '-': case '_': view.zoom(1.0f / kZoomStep); break;
    case 'r': case 'R': {
      const int width = view.width, height = view.height;
      view = home;
      view.width = width;
      view.height = height;
      break;
    }
    default: return KeyAction::None;
  }
  return KeyAction::ViewChanged;
}

void orbit_by_drag(View& view, float dx_px, float dy_px) {
  view.orbit(dx_px * kDragOrbit_rad_per_px, dy_px * kDragOrbit_rad_per_px);
}

std::optional<BladeSample> MouseBlade::locate(const Mesh& mesh, const View& view, cv::Point2f pixel, bool cutting) {
  BladeSample sample;
  sample.stroke_id = stroke_id_;
  sample.cutting = cutting;
  if (const auto on_cloth = pick_surface(mesh, view, pixel)) {
    sample.position_m = *on_cloth;
  } else if (const auto on_plane = pick_rest_plane(view, pixel)) {
    sample.position_m = *on_plane;
    sample.outside_cloth = true;
  } else if (last_) {
    sample.position_m = *last_;  // looking along the cloth's plane: stay where the blade was
    sample.outside_cloth = true;
  } else {
    return std::nullopt;
  }
  last_ = sample.position_m;
  return sample;
}

std::optional<BladeSample> MouseBlade::press(const Mesh& mesh, const View& view, cv::Point2f pixel) {
  if (cutting_) return move(mesh, view, pixel);
  ++stroke_id_;
  cutting_ = true;
  return locate(mesh, view, pixel, true);
}

std::optional<BladeSample> MouseBlade::move(const Mesh& mesh, const View& view, cv::Point2f pixel) {
  if (!cutting_) return std::nullopt;
  return locate(mesh, view, pixel, true);
}

std::optional<BladeSample> MouseBlade::release(const Mesh& mesh, const View& view, cv::Point2f pixel) {
  if (!cutting_) return std::nullopt;
  cutting_ = false;
  return locate(mesh, view, pixel, false);
}

}  // namespace tachi::viewer
