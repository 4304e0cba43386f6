// Draws what the user needs to cut well: the cloth (orthographic view from an orbiting camera, shaded
// by its normal so folds and falling pieces read), the hand mark, the stroke being cut, the latest cut
// flashing, the held particle, the mouse blade and a HUD of what the system is doing.
// Hand-mark colours follow Mesuda et al., "Virtual Cloth Cutting", sec. 4-5: blue while not cutting,
// green while cutting, and (their proposed fix) red when the hand is outside the cloth.
// The blade cursor follows seed 001 section 3: a 2D blade image replaces the cursor and turns point
// down while the left button is held.
// `render` is a pure function of (scene, view): the window, the video and the tests all go through it.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace tachi::viewer {

/// The cloth as the simulator publishes it: triangles index positions (world metres,
/// cloth in z = 0, x right, y up, centred at the origin).
struct Mesh {
  std::uint32_t topology_version = 0;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::uint8_t> pinned;  // per particle; may be empty
  /// Per triangle, which group (piece of an exported mesh) it belongs to; may be empty. Groups are
  /// drawn in different shades.
  std::vector<std::uint16_t> groups;
};

enum class HandState { Idle, Cutting };

struct Hand {
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();  // world frame
  HandState state = HandState::Idle;
  bool outside_cloth = false;
};

/// The mouse blade (seed 001 section 3) at a window pixel; `cutting` while the left button is held.
struct BladeCursor {
  cv::Point2f pixel;
  bool cutting = false;
};

/// What the system is doing, drawn top left. Empty strings / optionals are drawn as "-".
struct Hud {
  double fps = 0.0;
  std::optional<double> state_age_ms;  ///< now - ClothState.acquired_ns of the shown state
  std::string gate = "-";              ///< e.g. "cutting (mouse)"
  std::string blade = "-";
  int columns = 0;
  int rows = 0;
  std::uint32_t topology_version = 0;
  std::optional<std::uint32_t> pieces;
  std::optional<std::uint32_t> fallen_pieces;
  std::uint64_t rejected = 0;  ///< inputs rejected so far
  std::string warning;         ///< drawn in orange under the figures when set
};

struct Scene {
  Mesh mesh;
  std::optional<Hand> hand;                 // empty when the hand is lost
  std::vector<Eigen::Vector3f> stroke;      // samples of the stroke being cut (world frame)
  std::string status;                       // one line of text, bottom left
  /// The newest cut: particles along its line flash, `flash` fading from 1 to 0.
  std::vector<std::uint32_t> cut_particles;
  float flash = 0.0f;
  int held_particle = -1;                   // the particle a grabbing hand holds (ClothState.held_particle)
  /// Points of other objects in the scene (the point clouds the cloth drapes over), drawn as dots.
  std::vector<Eigen::Vector3f> object_points;
  std::optional<Hud> hud;                   // no HUD when empty (tests of the bare drawing)
  std::optional<BladeCursor> blade;
  bool show_help = false;                   // the key list over the image
};

/// An orthographic camera orbiting `centre`: the world turns by `yaw` about y, then `pitch` about x;
/// `metres_across` of the world fit the shorter side of the image.
struct View {
  int width = 800;
  int height = 800;
  float metres_across = 1.6f;
  Eigen::Vector3f centre = Eigen::Vector3f(0.0f, -0.1f, 0.0f);
  float yaw_rad = 0.0f;
  float pitch_rad = 0.0f;

  void orbit(float d_yaw_rad, float d_pitch_rad);
  /// Moves the centre by a drag of (dx, dy) pixels in the image plane.
  void pan(float dx_px, float dy_px);
  /// Zooms in (factor > 1) or out.
  void zoom(float factor);
};

/// Colours (BGR) of the hand mark, so tests and docs agree with the drawing.
inline const cv::Scalar kIdleColour{255, 64, 0};       // blue
inline const cv::Scalar kCuttingColour{0, 200, 0};     // green
inline const cv::Scalar kOutsideColour{0, 0, 255};     // red
inline const cv::Scalar kBackground{40, 30, 30};
inline const cv::Scalar kFlashColour{0, 255, 255};     // a new cut (yellow)
inline const cv::Scalar kHeldColour{255, 0, 255};      // ring round the held particle (magenta)
inline const cv::Scalar kHudText{235, 235, 235};

/// The keys the window understands, as shown by `h`.
inline const std::vector<std::string> kKeyHelp{
    "h  show / hide these keys",
    "q, Esc  quit",
    "p  save a snapshot (PNG)",
    "a d / arrows  orbit left, right",
    "w x / arrows  orbit up, down",
    "i j k l  pan",
    "+ -  zoom in, out (or the wheel)",
    "r  reset the view",
    "mouse: left drag orbits, right drag pans",
    "  (with --mouse the left button cuts)",
};

/// World point -> pixel of the view.
cv::Point2f to_pixel(const View& view, const Eigen::Vector3f& world);
/// Depth of a world point along the view direction (larger = nearer the viewer).
float view_depth(const View& view, const Eigen::Vector3f& world);

/// The point of the cloth's surface seen at `pixel` (the nearest triangle under it), or nothing when
/// the pixel shows no cloth. Seed 001 section 3: the cursor's 2D spot taken into 3D.
std::optional<Eigen::Vector3f> pick_surface(const Mesh& mesh, const View& view, const cv::Point2f& pixel);
/// Where the ray through `pixel` meets the cloth's rest plane z = 0 (off the cloth), or nothing when the
/// view looks along the plane.
std::optional<Eigen::Vector3f> pick_rest_plane(const View& view, const cv::Point2f& pixel);

/// Colour of the hand mark for a hand (outside wins over the gate state: the user must see it).
cv::Scalar hand_colour(const Hand& hand);

/// Renders the scene into an 8-bit BGR image of the view's size.
cv::Mat render(const Scene& scene, const View& view);

}  // namespace tachi::viewer
