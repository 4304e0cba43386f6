// Draws what the user needs to cut well: the cloth (front view, shaded by its normal so folds and
// falling pieces read), the hand mark, the stroke being cut, and a status line.
// Hand-mark colours follow Mesuda et al., "Virtual Cloth Cutting", sec. 4-5: blue while not cutting,
// green while cutting, and (their proposed fix) red when the hand is outside the cloth.
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
};

enum class HandState { Idle, Cutting };

struct Hand {
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();  // world frame
  HandState state = HandState::Idle;
  bool outside_cloth = false;
};

struct Scene {
  Mesh mesh;
  std::optional<Hand> hand;                 // empty when the hand is lost
  std::vector<Eigen::Vector3f> stroke;      // samples of the stroke being cut (world frame)
  std::string status;                       // one line of text, bottom left
};

/// A front orthographic view: `metres_across` of the world fit the image width, centred on `centre`.
struct View {
  int width = 800;
  int height = 800;
  float metres_across = 1.6f;
  Eigen::Vector2f centre = Eigen::Vector2f(0.0f, -0.1f);
};

/// Colours (BGR) of the hand mark, so tests and docs agree with the drawing.
inline const cv::Scalar kIdleColour{255, 64, 0};       // blue
inline const cv::Scalar kCuttingColour{0, 200, 0};     // green
inline const cv::Scalar kOutsideColour{0, 0, 255};     // red
inline const cv::Scalar kBackground{40, 30, 30};

/// World point -> pixel of the view.
cv::Point2f to_pixel(const View& view, const Eigen::Vector3f& world);

/// Colour of the hand mark for a hand (outside wins over the gate state: the user must see it).
cv::Scalar hand_colour(const Hand& hand);

/// Renders the scene into an 8-bit BGR image of the view's size.
cv::Mat render(const Scene& scene, const View& view);

}  // namespace tachi::viewer
