#include "tachi/viewer/render.hpp"

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tachi::viewer {
namespace {
const cv::Scalar kClothFront{215, 200, 170};
const cv::Scalar kClothBack{150, 170, 205};
const cv::Scalar kStrokeColour{0, 215, 255};
const cv::Scalar kPinColour{30, 30, 220};
const cv::Scalar kObjectColour{80, 220, 240};
const cv::Scalar kWarningColour{0, 160, 255};
// Shades of the groups (pieces) of an exported mesh: hue steps far apart so neighbours differ.
const cv::Scalar kGroupShades[] = {{215, 200, 170}, {140, 200, 120}, {120, 160, 230}, {200, 140, 200},
                                   {110, 210, 220}, {230, 170, 110}, {170, 170, 170}, {90, 140, 180}};
constexpr float kMaxPitch_rad = 1.5f;

bool finite(const Eigen::Vector3f& p) { return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()); }

Eigen::Matrix3f rotation(const View& view) {
  return (Eigen::AngleAxisf(view.pitch_rad, Eigen::Vector3f::UnitX()) *
          Eigen::AngleAxisf(view.yaw_rad, Eigen::Vector3f::UnitY()))
      .toRotationMatrix();
}

float pixels_per_metre(const View& view) {
  return static_cast<float>(std::min(view.width, view.height)) / view.metres_across;
}

// A world point in view coordinates (x right, y up, z toward the viewer), in pixels for x and y.
struct Projector {
  explicit Projector(const View& view)
      : r(rotation(view)), centre(view.centre), scale(pixels_per_metre(view)),
        half_w(static_cast<float>(view.width) * 0.5f), half_h(static_cast<float>(view.height) * 0.5f) {}
  cv::Point2f pixel(const Eigen::Vector3f& world) const {
    const Eigen::Vector3f q = r * (world - centre);
    return {half_w + q.x() * scale, half_h - q.y() * scale};
  }
  float depth(const Eigen::Vector3f& world) const { return r.row(2).dot(world - centre); }
  Eigen::Matrix3f r;
  Eigen::Vector3f centre;
  float scale, half_w, half_h;
};

// Fills the triangle abc with `colour`: every pixel whose centre (integer coordinates, as OpenCV's own
// drawing) lies inside or on an edge. Shared edges are drawn by both triangles, so a mesh has no gaps.
// A cloth of 256^2 particles has triangles of a few pixels, where cv::fillConvexPoly's set-up costs
// more than the fill: this half-space test over the bounding box is several times faster there.
void fill_triangle(cv::Mat& image, cv::Point2f a, cv::Point2f b, cv::Point2f c, const cv::Vec3b& colour) {
  float area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  if (!(std::abs(area) > 1e-9f)) return;  // degenerate (or NaN)
  if (area < 0.0f) {
    std::swap(b, c);
    area = -area;
  }
  const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({a.x, b.x, c.x}))));
  const int x1 = std::min(image.cols - 1, static_cast<int>(std::floor(std::max({a.x, b.x, c.x}))));
  const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({a.y, b.y, c.y}))));
  const int y1 = std::min(image.rows - 1, static_cast<int>(std::floor(std::max({a.y, b.y, c.y}))));
  // Edge functions E(x, y) = A x + B y + C of the edges a->b, b->c, c->a: >= 0 on the triangle's side,
  // stepped by A along a row and by B down the rows.
  const float ea = b.y - a.y, eb = a.x - b.x, ec = -(ea * a.x + eb * a.y);
  const float fa = c.y - b.y, fb = b.x - c.x, fc = -(fa * b.x + fb * b.y);
  const float ga = a.y - c.y, gb = c.x - a.x, gc = -(ga * c.x + gb * c.y);
  constexpr float kOnEdge = -1e-3f;
  for (int y = y0; y <= y1; ++y) {
    auto* row = image.ptr<cv::Vec3b>(y);
    const auto fy = static_cast<float>(y);
    const auto fx = static_cast<float>(x0);
    float e = -(ea * fx + eb * fy + ec), f = -(fa * fx + fb * fy + fc), g = -(ga * fx + gb * fy + gc);
    for (int x = x0; x <= x1; ++x, e -= ea, f -= fa, g -= ga)
      if (e >= kOnEdge && f >= kOnEdge && g >= kOnEdge) row[x] = colour;
  }
}

// Text with a dark outline so it reads on the cloth and on the background alike.
void text(cv::Mat& image, const std::string& line, cv::Point at, const cv::Scalar& colour, double size = 0.5) {
  cv::putText(image, line, at, cv::FONT_HERSHEY_SIMPLEX, size, cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(image, line, at, cv::FONT_HERSHEY_SIMPLEX, size, colour, 1, cv::LINE_AA);
}

std::string figure(const std::optional<std::uint32_t>& value) { return value ? std::to_string(*value) : "-"; }

void draw_hud(cv::Mat& image, const Hud& hud) {
  char age[32] = "-";
  if (hud.state_age_ms) std::snprintf(age, sizeof age, "%.1f ms", *hud.state_age_ms);
  char fps[16];
  std::snprintf(fps, sizeof fps, "%.1f", hud.fps);
  const std::string lines[] = {
      std::string("fps ") + fps + "   state age " + age,
      "gate " + hud.gate + "   blade " + hud.blade,
      "grid " + (hud.columns > 0 ? std::to_string(hud.columns) + "x" + std::to_string(hud.rows) : std::string("-")) +
          "   topology v" + std::to_string(hud.topology_version),
      "pieces " + figure(hud.pieces) + "   fallen " + figure(hud.fallen_pieces) + "   rejected " +
          std::to_string(hud.rejected),
  };
  int y = 20;
  for (const auto& line : lines) {
    text(image, line, {10, y}, kHudText);
    y += 20;
  }
  if (!hud.warning.empty()) text(image, hud.warning, {10, y}, kWarningColour);
}

void draw_help(cv::Mat& image) {
  const int line_height = 20;
  const cv::Rect box(image.cols / 2 - 190, 40, 380, line_height * static_cast<int>(kKeyHelp.size()) + 20);
  cv::Mat roi = image(box & cv::Rect(0, 0, image.cols, image.rows));
  roi *= 0.3;  // darken what is behind the list
  int y = box.y + 24;
  for (const auto& line : kKeyHelp) {
    text(image, line, {box.x + 12, y}, kHudText);
    y += line_height;
  }
}

// Seed 001 section 3: a small blade image at the cursor; tip up and to the right while hovering, point
// down (tip at the cursor, red edge) while cutting.
void draw_blade(cv::Mat& image, const BladeCursor& blade) {
  const cv::Point2f tip = blade.pixel;
  const cv::Point2f along = blade.cutting ? cv::Point2f(0.0f, -1.0f) : cv::Point2f(-0.7071f, 0.7071f);
  const cv::Point2f across(-along.y, along.x);
  auto at = [&](float a, float b) { return cv::Point(tip + along * a + across * b); };
  const cv::Point steel[] = {at(0, 0), at(26, 6), at(26, -2)};
  const cv::Point handle[] = {at(26, 5), at(44, 5), at(44, -3), at(26, -3)};
  cv::fillConvexPoly(image, steel, 3, cv::Scalar(210, 210, 215), cv::LINE_AA);
  cv::line(image, at(0, 0), at(26, 6), blade.cutting ? kOutsideColour : cv::Scalar(90, 90, 90), 2, cv::LINE_AA);
  cv::fillConvexPoly(image, handle, 4, cv::Scalar(40, 70, 120), cv::LINE_AA);
}
}  // namespace

void View::orbit(float d_yaw_rad, float d_pitch_rad) {
  yaw_rad = std::remainder(yaw_rad + d_yaw_rad, 2.0f * static_cast<float>(M_PI));
  pitch_rad = std::clamp(pitch_rad + d_pitch_rad, -kMaxPitch_rad, kMaxPitch_rad);
}

void View::pan(float dx_px, float dy_px) {
  const float scale = pixels_per_metre(*this);
  // Screen right/up in world coordinates are the first two rows of the view rotation.
  const Eigen::Matrix3f r = rotation(*this);
  centre -= r.row(0).transpose() * (dx_px / scale);
  centre += r.row(1).transpose() * (dy_px / scale);
}

void View::zoom(float factor) {
  if (factor > 0.0f && std::isfinite(factor)) metres_across = std::clamp(metres_across / factor, 0.05f, 50.0f);
}

cv::Point2f to_pixel(const View& view, const Eigen::Vector3f& world) { return Projector(view).pixel(world); }

float view_depth(const View& view, const Eigen::Vector3f& world) { return Projector(view).depth(world); }

std::optional<Eigen::Vector3f> pick_surface(const Mesh& mesh, const View& view, const cv::Point2f& pixel) {
  const Projector project(view);
  const std::size_t particles = mesh.positions.size();
  std::optional<Eigen::Vector3f> best;
  float best_depth = -std::numeric_limits<float>::infinity();
  for (const auto& tri : mesh.triangles) {
    if (tri[0] >= particles || tri[1] >= particles || tri[2] >= particles) continue;
    const Eigen::Vector3f& a = mesh.positions[tri[0]];
    const Eigen::Vector3f& b = mesh.positions[tri[1]];
    const Eigen::Vector3f& c = mesh.positions[tri[2]];
    if (!finite(a) || !finite(b) || !finite(c)) continue;
    const cv::Point2f pa = project.pixel(a), pb = project.pixel(b), pc = project.pixel(c);
    // Barycentric coordinates of the pixel in the projected triangle.
    const float area = static_cast<float>((pb - pa).cross(pc - pa));
    if (std::abs(area) < 1e-6f) continue;
    const float wb = static_cast<float>((pixel - pa).cross(pc - pa)) / area;
    const float wc = static_cast<float>((pb - pa).cross(pixel - pa)) / area;
    const float wa = 1.0f - wb - wc;
    if (wa < 0.0f || wb < 0.0f || wc < 0.0f) continue;
    const Eigen::Vector3f hit = wa * a + wb * b + wc * c;
    const float depth = project.depth(hit);
    if (depth > best_depth) {
      best_depth = depth;
      best = hit;
    }
  }
  return best;
}

std::optional<Eigen::Vector3f> pick_rest_plane(const View& view, const cv::Point2f& pixel) {
  const Projector project(view);
  const float qx = (pixel.x - project.half_w) / project.scale;
  const float qy = (project.half_h - pixel.y) / project.scale;
  // world = centre + R^T (qx, qy, t); choose t so that world.z = 0.
  const Eigen::Matrix3f rt = project.r.transpose();
  if (std::abs(rt(2, 2)) < 1e-3f) return std::nullopt;
  const float t = -(view.centre.z() + rt(2, 0) * qx + rt(2, 1) * qy) / rt(2, 2);
  Eigen::Vector3f world = view.centre + rt * Eigen::Vector3f(qx, qy, t);
  world.z() = 0.0f;
  return world;
}

cv::Scalar hand_colour(const Hand& hand) {
  if (hand.outside_cloth) return kOutsideColour;
  return hand.state == HandState::Cutting ? kCuttingColour : kIdleColour;
}

cv::Mat render(const Scene& scene, const View& view) {
  cv::Mat image(view.height, view.width, CV_8UC3, kBackground);
  const Projector project(view);
  const auto& mesh = scene.mesh;
  const std::size_t particles = mesh.positions.size();

  // Each particle is projected once; triangles share them.
  std::vector<cv::Point2f> pixel(particles);
  std::vector<float> depth(particles);
  for (std::size_t i = 0; i < particles; ++i) {
    if (!finite(mesh.positions[i])) continue;
    const cv::Point2f p = project.pixel(mesh.positions[i]);
    // Clamped so that a particle far off screen cannot overflow an integer pixel.
    pixel[i] = {std::clamp(p.x, -1e5f, 1e5f), std::clamp(p.y, -1e5f, 1e5f)};
    depth[i] = project.depth(mesh.positions[i]);
  }

  // Painter's order: far triangles first, so a fold in front hides what is behind.
  std::vector<std::pair<float, std::uint32_t>> order;
  order.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (tri[0] >= particles || tri[1] >= particles || tri[2] >= particles) continue;  // stale topology
    if (!finite(mesh.positions[tri[0]]) || !finite(mesh.positions[tri[1]]) || !finite(mesh.positions[tri[2]])) continue;
    order.emplace_back(depth[tri[0]] + depth[tri[1]] + depth[tri[2]], static_cast<std::uint32_t>(t));
  }
  std::sort(order.begin(), order.end());

  const Eigen::RowVector3f towards_viewer = project.r.row(2);
  for (const auto& [ignored, t] : order) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3f& a = mesh.positions[tri[0]];
    const Eigen::Vector3f normal = (mesh.positions[tri[1]] - a).cross(mesh.positions[tri[2]] - a);
    const float length = normal.norm();
    const float facing = length > 0.0f ? towards_viewer.dot(normal) / length : 0.0f;
    const cv::Scalar& base = !mesh.groups.empty() && t < mesh.groups.size()
                                 ? kGroupShades[mesh.groups[t] % std::size(kGroupShades)]
                                 : (facing >= 0.0f ? kClothFront : kClothBack);
    const double light = 0.35 + 0.65 * std::abs(facing);
    const cv::Scalar shade = base * light;
    fill_triangle(image, pixel[tri[0]], pixel[tri[1]], pixel[tri[2]],
                  cv::Vec3b(cv::saturate_cast<uchar>(shade[0]), cv::saturate_cast<uchar>(shade[1]),
                            cv::saturate_cast<uchar>(shade[2])));
  }

  for (std::size_t i = 0; i < mesh.pinned.size() && i < particles; ++i)
    if (mesh.pinned[i] && finite(mesh.positions[i])) cv::circle(image, pixel[i], 3, kPinColour, cv::FILLED);

  for (const auto& p : scene.object_points)
    if (finite(p)) cv::circle(image, project.pixel(p), 2, kObjectColour, cv::FILLED);

  if (scene.flash > 0.0f) {
    const int radius = 2 + static_cast<int>(std::lround(3.0f * std::min(scene.flash, 1.0f)));
    for (const std::uint32_t i : scene.cut_particles)
      if (i < particles && finite(mesh.positions[i])) cv::circle(image, pixel[i], radius, kFlashColour, cv::FILLED);
  }

  if (scene.stroke.size() >= 2) {
    std::vector<cv::Point> line;
    line.reserve(scene.stroke.size());
    for (const auto& p : scene.stroke)
      if (finite(p)) line.push_back(project.pixel(p));
    cv::polylines(image, line, false, kStrokeColour, 2, cv::LINE_AA);
  }

  if (scene.held_particle >= 0 && static_cast<std::size_t>(scene.held_particle) < particles &&
      finite(mesh.positions[static_cast<std::size_t>(scene.held_particle)]))
    cv::circle(image, pixel[static_cast<std::size_t>(scene.held_particle)], 9, kHeldColour, 2, cv::LINE_AA);

  if (scene.hand && finite(scene.hand->position_m)) {
    const cv::Point centre = project.pixel(scene.hand->position_m);
    const cv::Scalar colour = hand_colour(*scene.hand);
    cv::circle(image, centre, 11, colour, cv::FILLED, cv::LINE_AA);
    cv::circle(image, centre, 12, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }

  if (scene.blade) draw_blade(image, *scene.blade);

  if (!scene.status.empty()) text(image, scene.status, {10, view.height - 12}, cv::Scalar(230, 230, 230));
  if (scene.hud) draw_hud(image, *scene.hud);
  if (scene.show_help) draw_help(image);
  return image;
}

}  // namespace tachi::viewer
