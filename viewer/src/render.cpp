#include "tachi/viewer/render.hpp"

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace tachi::viewer {
namespace {
const cv::Scalar kClothFront{215, 200, 170};
const cv::Scalar kClothBack{150, 170, 205};
const cv::Scalar kStrokeColour{0, 215, 255};
const cv::Scalar kPinColour{30, 30, 220};

bool finite(const Eigen::Vector3f& p) { return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()); }
}  // namespace

cv::Point2f to_pixel(const View& view, const Eigen::Vector3f& world) {
  const float pixels_per_metre = static_cast<float>(view.width) / view.metres_across;
  return {static_cast<float>(view.width) * 0.5f + (world.x() - view.centre.x()) * pixels_per_metre,
          static_cast<float>(view.height) * 0.5f - (world.y() - view.centre.y()) * pixels_per_metre};
}

cv::Scalar hand_colour(const Hand& hand) {
  if (hand.outside_cloth) return kOutsideColour;
  return hand.state == HandState::Cutting ? kCuttingColour : kIdleColour;
}

cv::Mat render(const Scene& scene, const View& view) {
  cv::Mat image(view.height, view.width, CV_8UC3, kBackground);
  const auto& mesh = scene.mesh;
  const std::size_t particles = mesh.positions.size();

  // Painter's order: far triangles (more negative z) first, so a fold in front hides what is behind.
  std::vector<std::pair<float, std::size_t>> order;
  order.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (tri[0] >= particles || tri[1] >= particles || tri[2] >= particles) continue;  // stale topology
    const auto& a = mesh.positions[tri[0]];
    const auto& b = mesh.positions[tri[1]];
    const auto& c = mesh.positions[tri[2]];
    if (!finite(a) || !finite(b) || !finite(c)) continue;
    order.emplace_back(a.z() + b.z() + c.z(), t);
  }
  std::sort(order.begin(), order.end());

  for (const auto& [depth, t] : order) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3f& a = mesh.positions[tri[0]];
    const Eigen::Vector3f& b = mesh.positions[tri[1]];
    const Eigen::Vector3f& c = mesh.positions[tri[2]];
    const Eigen::Vector3f normal = (b - a).cross(c - a);
    const float length = normal.norm();
    const float facing = length > 0.0f ? normal.z() / length : 0.0f;
    const cv::Scalar& base = facing >= 0.0f ? kClothFront : kClothBack;
    const double light = 0.35 + 0.65 * std::abs(facing);
    const cv::Point corners[3] = {to_pixel(view, a), to_pixel(view, b), to_pixel(view, c)};
    cv::fillConvexPoly(image, corners, 3, base * light, cv::LINE_8);
  }

  for (std::size_t i = 0; i < mesh.pinned.size() && i < particles; ++i)
    if (mesh.pinned[i] && finite(mesh.positions[i])) cv::circle(image, to_pixel(view, mesh.positions[i]), 3, kPinColour, cv::FILLED);

  if (scene.stroke.size() >= 2) {
    std::vector<cv::Point> line;
    line.reserve(scene.stroke.size());
    for (const auto& p : scene.stroke)
      if (finite(p)) line.push_back(to_pixel(view, p));
    cv::polylines(image, line, false, kStrokeColour, 2, cv::LINE_AA);
  }

  if (scene.hand && finite(scene.hand->position_m)) {
    const cv::Point centre = to_pixel(view, scene.hand->position_m);
    const cv::Scalar colour = hand_colour(*scene.hand);
    cv::circle(image, centre, 11, colour, cv::FILLED, cv::LINE_AA);
    cv::circle(image, centre, 12, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }

  if (!scene.status.empty())
    cv::putText(image, scene.status, {10, view.height - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(230, 230, 230), 1,
                cv::LINE_AA);
  return image;
}

}  // namespace tachi::viewer
