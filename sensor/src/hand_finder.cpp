#include "tachi/sensor/hand_finder.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace tachi::sensor {
namespace {
constexpr int kStep = 4;
constexpr int kGridW = kDepthWidth / kStep;
constexpr int kGridH = kDepthHeight / kStep;
constexpr int kGridCells = kGridW * kGridH;
constexpr std::uint16_t kUnknown = 0;  // background not seen yet (raw 0 is nearer than the Kinect's range)
}  // namespace

struct HandFinder::Impl {
  DepthModel model;
  HandFinderParams params;
  std::array<std::uint16_t, 2048> foreground_below{};  // raw < this[bg] means foreground
  std::array<std::uint16_t, 2048> band_limit{};        // hand band: raw <= this[nearest raw]
  // Per cell: the nearest depth that has stayed put for a while (what "static" means here: the
  // scene at start, furniture, a resting arm), the farthest depth seen (fallback where nothing was
  // stable yet), and the current run of steady readings.
  std::vector<std::uint16_t> stable = std::vector<std::uint16_t>(kGridCells, kUnknown);
  std::vector<std::uint16_t> farthest = std::vector<std::uint16_t>(kGridCells, kUnknown);
  std::vector<std::uint16_t> run_value = std::vector<std::uint16_t>(kGridCells, kUnknown);
  std::vector<std::uint16_t> run_length = std::vector<std::uint16_t>(kGridCells, 0);
  bool first_frame = true;
  bool excluded = false;  // `arm` holds this frame's followed arm (grid cells, dilated)
  cv::Mat grid = cv::Mat(kGridH, kGridW, CV_16U);
  cv::Mat fg = cv::Mat(kGridH, kGridW, CV_8U);
  cv::Mat fg_open, labels, stats, centroids, arm;
  cv::Mat candidate_mask, band_cells, band_region;  // find_arm_end's candidates
  std::vector<std::uint16_t> nearest;  // per component: nearest reading, and where
  std::vector<cv::Point> nearest_at;
  std::vector<std::uint32_t> visited = std::vector<std::uint32_t>(kGridCells, 0);  // reaches_back's BFS
  std::uint32_t visit_generation = 0;
  std::vector<cv::Point> queue;
  cv::Mat kernel3 = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  cv::Mat roi_mask, roi_closed, roi_dist;
  cv::Mat roi_mask_buffer = cv::Mat(kDepthHeight + 2, kDepthWidth + 2, CV_8U);
  cv::Mat roi_closed_buffer = cv::Mat(kDepthHeight + 2, kDepthWidth + 2, CV_8U);
  cv::Mat roi_dist_buffer = cv::Mat(kDepthHeight + 2, kDepthWidth + 2, CV_32F);
  std::vector<std::uint16_t> palm_raw;
  bool tracking = false;
  cv::Point previous_cell{-1, -1};
  Eigen::Vector3d last_seen = Eigen::Vector3d::Zero();
  int frames_since_seen = 1 << 20;

  Impl(const DepthModel& m, const HandFinderParams& p) : model(m), params(p) {
    for (std::size_t raw = 0; raw < 2048; ++raw) {
      const double z = model.metres(static_cast<std::uint16_t>(raw));
      foreground_below[raw] = raw_limit(z > 0 ? z - params.foreground_m : 0.0, false);
      band_limit[raw] = raw_limit(z > 0 ? z + params.hand_depth_band_m : 0.0, true);
    }
  }

  /// Raw value at depth z, rounded down (floor) or up; 0 for no valid depth.
  std::uint16_t raw_limit(double z, bool up) const {
    if (z <= 0.05) return 0;
    const double raw = model.raw_at(z);
    const double r = up ? std::floor(raw) : std::ceil(raw);
    return static_cast<std::uint16_t>(std::clamp(r, 0.0, static_cast<double>(kMaxValidRaw)));
  }

  /// A palm candidate measured at full resolution (steps 3-4).
  struct Palm {
    double u = 0, v = 0;          ///< inscribed circle's centre, pixels
    float z = 0;                  ///< median depth inside it
    double radius_m = 0;          ///< its radius
    double valid_fraction = 0;    ///< share of the circle with readings
    bool cut_by_border = false;   ///< the hand leaves the image within a palm diameter of the circle
  };

  HandObservation find(std::span<const std::uint16_t> raw);
  void update_background(const cv::Mat* exclude);
  bool measure(std::span<const std::uint16_t> raw, const cv::Rect& cells, std::uint16_t near_raw, cv::Point seed_cell, Palm& palm);
  bool measure_in_band(std::span<const std::uint16_t> raw, const cv::Rect& cells, std::uint16_t near_raw, std::uint16_t far_raw,
                       cv::Point seed_cell, Palm& palm);
  bool reaches_back(cv::Point seed, std::uint16_t near_raw);
  bool turned_palm_stretch(std::span<const std::uint16_t> raw, int rx0, int ry0, int rx1, int ry1);
  cv::Matx23d stretch, unstretch;  // turned_palm_stretch's ROI -> stretched image, and back
  cv::Size stretched_size;
  cv::Mat roi_stretched, stretched_dist;
  bool find_arm_end(std::span<const std::uint16_t> raw, Palm& palm, cv::Point& seed);
  bool palm_accepted(const Palm& palm) const;
  bool jumped(const Palm& palm) const;
  bool palm_sized(const Palm& palm) const {
    return palm.radius_m >= params.min_palm_radius_m && palm.radius_m <= params.max_palm_radius_m;
  }


  /// Where a cell has never had a steady reading (an IR shadow beside a resting arm, say), what is
  /// behind it is what is beside it: the farthest steady reading within 6 cells along the row
  /// (shadows are horizontal bands), else the farthest reading seen there.
  std::uint16_t background_nearby(int gx, int gy) const {
    const std::size_t base = static_cast<std::size_t>(gy) * kGridW;
    std::uint16_t best = kUnknown;
    for (int x = std::max(0, gx - 6); x <= std::min(kGridW - 1, gx + 6); ++x) best = std::max(best, stable[base + x]);
    return best != kUnknown ? best : farthest[base + gx];
  }
};

/// Learns the static scene from the grid: a reading steady for kSteadyFrames becomes the
/// background where it is nearer than the current one (so a resting arm, or an object put down
/// later, is background); a farther steady reading replaces it only after kLongSteadyFrames (an
/// object removed). Cells of the arm being followed are left alone, so a pausing hand stays
/// foreground. The first frame is taken as background at once.
void HandFinder::Impl::update_background(const cv::Mat* exclude) {
  constexpr std::uint16_t kSteadyFrames = 10;
  constexpr std::uint16_t kLongSteadyFrames = 300;
  for (int gy = 0; gy < kGridH; ++gy) {
    const auto* g = grid.ptr<std::uint16_t>(gy);
    const std::uint8_t* ex = exclude ? exclude->ptr<std::uint8_t>(gy) : nullptr;
    const std::size_t base = static_cast<std::size_t>(gy) * kGridW;
    for (int gx = 0; gx < kGridW; ++gx) {
      const std::uint16_t d = g[gx];
      if (d >= kNoReading) continue;
      const std::size_t i = base + gx;
      if (d > farthest[i]) farthest[i] = d;
      if (first_frame) {
        stable[i] = d;
        run_value[i] = d;
        run_length[i] = 1;
        continue;
      }
      // Steady: within ~1 cm (a few raw units, more at long range where noise is larger).
      const int tolerance = 2 + run_value[i] / 256;
      if (std::abs(static_cast<int>(d) - static_cast<int>(run_value[i])) <= tolerance) {
        if (run_length[i] < 65535) ++run_length[i];
      } else {
        run_value[i] = d;
        run_length[i] = 1;
      }
      if (ex && ex[gx]) continue;
      if ((run_length[i] >= kSteadyFrames && (stable[i] == kUnknown || run_value[i] < stable[i])) ||
          run_length[i] >= kLongSteadyFrames)
        stable[i] = run_value[i];
    }
  }
  first_frame = false;
}

void use_one_opencv_thread() { cv::setNumThreads(0); }  // 0: no pool, everything in the caller

HandFinder::HandFinder(const DepthModel& model, const HandFinderParams& params)
    : impl_(std::make_unique<Impl>(model, params)) {}
HandFinder::~HandFinder() = default;
HandFinder::HandFinder(HandFinder&&) noexcept = default;
HandFinder& HandFinder::operator=(HandFinder&&) noexcept = default;
HandObservation HandFinder::find(std::span<const std::uint16_t> raw) {
  if (raw.size() != static_cast<std::size_t>(kDepthPixels)) return {};
  impl_->excluded = false;
  HandObservation out = impl_->find(raw);
  impl_->update_background(impl_->excluded ? &impl_->arm : nullptr);
  return out;
}
void HandFinder::reset() {
  for (auto* v : {&impl_->stable, &impl_->farthest, &impl_->run_value}) std::fill(v->begin(), v->end(), kUnknown);
  std::fill(impl_->run_length.begin(), impl_->run_length.end(), 0);
  impl_->first_frame = true;
  impl_->tracking = false;
  impl_->frames_since_seen = 1 << 20;
}

/// Steps 3-4 for one candidate hand: its grid cells `cells` (bounding box), the nearest reading
/// `near_raw` at grid cell `seed_cell`. Fills `palm`; false when no palm-like region is there.
bool HandFinder::Impl::measure(std::span<const std::uint16_t> raw, const cv::Rect& cells, std::uint16_t near_raw,
                               cv::Point seed_cell, Palm& palm) {
  if (!measure_in_band(raw, cells, near_raw, band_limit[near_raw], seed_cell, palm)) return false;
  // A circle much larger than a palm: the band reached something just behind the hand (a hand
  // against the chest, the torso 5-8 cm behind). A flat palm and its fingers lie within a few cm.
  // Halved again (1.75 cm) where the torso is nearer still.
  const double z_near = model.metres(near_raw);
  for (double band = params.narrow_band_m; palm.radius_m > params.narrow_band_above_m && band >= 0.015; band /= 2) {
    Palm narrow;
    if (!measure_in_band(raw, cells, near_raw, raw_limit(z_near + band, true), seed_cell, narrow)) break;
    palm = narrow;
  }
  return true;
}

bool HandFinder::Impl::measure_in_band(std::span<const std::uint16_t> raw, const cv::Rect& cells, std::uint16_t near_raw,
                                       std::uint16_t far_raw, cv::Point seed_cell, Palm& palm) {
  // Near the body part of the palm may be less than foreground_m in front of what was there
  // before, so at full resolution the depth band and connectivity bound the hand, in a ROI
  // grown by a palm diameter.
  const auto& k = model.intrinsics();
  const int pad = static_cast<int>(std::ceil(2 * params.palm_radius_m * k.fx / std::max(0.3f, model.metres(near_raw)))) + 4;
  const int rx0 = std::max(0, cells.x * kStep - pad), ry0 = std::max(0, cells.y * kStep - pad);
  const int rx1 = std::min(kDepthWidth, (cells.x + cells.width) * kStep + pad);
  const int ry1 = std::min(kDepthHeight, (cells.y + cells.height) * kStep + pad);
  const int rw = rx1 - rx0, rh = ry1 - ry0;

  // Full-resolution hand mask in the ROI, with a zero border so the image edge bounds the palm.
  // Views of full-frame buffers made once: a ROI of a new size allocates nothing.
  const cv::Rect roi_rect(0, 0, rw + 2, rh + 2);
  roi_mask = roi_mask_buffer(roi_rect);
  roi_closed = roi_closed_buffer(roi_rect);
  roi_dist = roi_dist_buffer(roi_rect);
  roi_mask.setTo(0);
  const std::uint16_t slack_raw = near_raw > 20 ? static_cast<std::uint16_t>(near_raw - 20) : 0;
  for (int y = ry0; y < ry1; ++y) {
    const std::uint16_t* row = raw.data() + static_cast<std::size_t>(y) * kDepthWidth;
    auto* m = roi_mask.ptr<std::uint8_t>(y - ry0 + 1) + 1;
    for (int x = rx0; x < rx1; ++x) {
      const std::uint16_t d = row[x];
      if (d >= kNoReading) continue;
      m[x - rx0] = (d <= far_raw && d >= slack_raw) ? 255 : 0;
    }
  }
  // The hand: the band's region connected to the arm's nearest reading.
  const cv::Point seed = seed_cell * kStep + cv::Point(kStep / 2 - rx0 + 1, kStep / 2 - ry0 + 1);
  if (roi_mask.at<std::uint8_t>(seed) != 255) return false;
  cv::floodFill(roi_mask, seed, cv::Scalar(128));
  cv::compare(roi_mask, 128, roi_mask, cv::CMP_EQ);
  // Holes in the hand (dropouts with hand all around) count as hand: flood the outside from the
  // zero border; whatever it cannot reach is hand or hole. Gaps between fingers open to the
  // outside, so fingers stay apart and do not widen the palm.
  roi_mask.copyTo(roi_closed);
  cv::floodFill(roi_closed, cv::Point(0, 0), cv::Scalar(128));
  cv::compare(roi_closed, 128, roi_closed, cv::CMP_NE);
  cv::distanceTransform(roi_closed, roi_dist, cv::DIST_L2, cv::DIST_MASK_5);
  double max_dist = 0;
  cv::Point max_at;
  cv::minMaxLoc(roi_dist, nullptr, &max_dist, nullptr, &max_at);
  if (max_dist < 2.0) return false;
  // Sub-pixel: centroid of the distance-transform plateau (within 1 px of the maximum).
  const auto plateau_centre = [](const cv::Mat& dist, double peak, cv::Point at) {
    double su = 0, sv = 0, sw = 0;
    const float plateau = static_cast<float>(peak - 1.0);
    const int r = static_cast<int>(std::ceil(peak));
    for (int y = std::max(0, at.y - r); y < std::min(dist.rows, at.y + r + 1); ++y) {
      const float* dr = dist.ptr<float>(y);
      for (int x = std::max(0, at.x - r); x < std::min(dist.cols, at.x + r + 1); ++x)
        if (dr[x] >= plateau) {
          const double w = dr[x] - plateau;
          su += w * x;
          sv += w * y;
          sw += w;
        }
    }
    return cv::Point2d(su / sw, sv / sw);
  };
  cv::Point2d centre = plateau_centre(roi_dist, max_dist, max_at);
  double size_px = max_dist;  // the palm circle's radius, measured in the palm's plane
  // A palm turned away from the sensor is foreshortened by cos(tilt) across the turn: its
  // inscribed circle shrinks toward a forearm's (at 60 degrees to half a palm). Where the circle
  // is too small, the palm plane is fitted to the mask's readings (least squares, z = a x + b y + c
  // in metres) and the mask stretched by 1 / cos(tilt) along the depth gradient, undoing the
  // foreshortening; the circle is then found in the stretched mask and mapped back.
  const float z_near = model.metres(near_raw);
  if (max_dist * z_near / k.fx < params.min_palm_radius_m && turned_palm_stretch(raw, rx0, ry0, rx1, ry1)) {
    cv::warpAffine(roi_closed, roi_stretched, stretch, stretched_size, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
    cv::distanceTransform(roi_stretched, stretched_dist, cv::DIST_L2, cv::DIST_MASK_5);
    double stretched_max = 0;
    cv::minMaxLoc(stretched_dist, nullptr, &stretched_max, nullptr, &max_at);
    if (stretched_max >= 2.0) {
      const cv::Point2d c = plateau_centre(stretched_dist, stretched_max, max_at);
      centre = {unstretch(0, 0) * c.x + unstretch(0, 1) * c.y + unstretch(0, 2),
                unstretch(1, 0) * c.x + unstretch(1, 1) * c.y + unstretch(1, 2)};
      size_px = stretched_max;
    }
  }
  const double u = rx0 - 1 + centre.x, v = ry0 - 1 + centre.y;

  // Palm depth: median reading inside the palm circle.
  palm_raw.clear();
  const double r2 = max_dist * max_dist;
  int circle_pixels = 0;
  for (int y = std::max(ry0, static_cast<int>(v - max_dist)); y <= std::min(ry1 - 1, static_cast<int>(v + max_dist)); ++y) {
    const std::uint16_t* row = raw.data() + static_cast<std::size_t>(y) * kDepthWidth;
    const auto* m = roi_mask.ptr<std::uint8_t>(y - ry0 + 1) + 1;
    for (int x = std::max(rx0, static_cast<int>(u - max_dist)); x <= std::min(rx1 - 1, static_cast<int>(u + max_dist)); ++x) {
      if ((x - u) * (x - u) + (y - v) * (y - v) > r2) continue;
      ++circle_pixels;
      if (m[x - rx0]) palm_raw.push_back(row[x]);
    }
  }
  if (palm_raw.size() < 8) return false;
  const auto mid = palm_raw.begin() + static_cast<std::ptrdiff_t>(palm_raw.size() / 2);
  std::nth_element(palm_raw.begin(), mid, palm_raw.end());
  palm.z = model.metres(*mid);
  if (palm.z <= 0) return false;
  palm.u = u;
  palm.v = v;
  palm.radius_m = size_px * palm.z / k.fx;
  palm.valid_fraction = static_cast<double>(palm_raw.size()) / std::max(1, circle_pixels);

  // Cut by the border: what is left of a palm half out of view (fingers, the upper palm) still
  // holds a palm-sized circle, centred up to 5 cm inward of the real one. Such a hand crosses the
  // border near the circle over most of a palm's width (a forearm crossing below a whole palm is
  // narrower) and its circle is smaller than a whole palm's.
  const double reach = max_dist + 2 * params.palm_radius_m * k.fx / palm.z;
  const double reach2 = reach * reach;
  const auto on_hand = [&](int x, int y) {
    return roi_mask.at<std::uint8_t>(y - ry0 + 1, x - rx0 + 1) != 0 && (x - u) * (x - u) + (y - v) * (y - v) < reach2;
  };
  const int left = std::clamp(params.invalid_left_columns, 0, kDepthWidth - 1);
  int top = 0, bottom = 0, left_edge = 0, right_edge = 0;  // hand pixels on each border near the circle
  for (int x = std::max(rx0, left); x < rx1; ++x) {
    if (ry0 == 0 && on_hand(x, 0)) ++top;
    if (ry1 == kDepthHeight && on_hand(x, kDepthHeight - 1)) ++bottom;
  }
  for (int y = ry0; y < ry1; ++y) {
    if (rx0 <= left && left < rx1 && on_hand(left, y)) ++left_edge;
    if (rx1 == kDepthWidth && on_hand(kDepthWidth - 1, y)) ++right_edge;
  }
  const double crossing_m = std::max({top, bottom, left_edge, right_edge}) * static_cast<double>(palm.z) / k.fx;
  palm.cut_by_border = crossing_m >= params.border_cut_width_m && palm.radius_m < params.whole_palm_radius_m;
  return true;
}

/// Fits the palm plane to the hand mask's readings (roi_mask, ROI [rx0, rx1) x [ry0, ry1)) and,
/// when it is turned more than ~30 degrees from the sensor, sets `stretch` (ROI -> stretched
/// image: 1 / cos(tilt) along the image direction of the depth gradient), its inverse and the
/// stretched size. False for a palm facing the sensor or too few readings.
bool HandFinder::Impl::turned_palm_stretch(std::span<const std::uint16_t> raw, int rx0, int ry0, int rx1, int ry1) {
  const auto& k = model.intrinsics();
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  int count = 0;
  for (int y = ry0; y < ry1; ++y) {
    const std::uint16_t* row = raw.data() + static_cast<std::size_t>(y) * kDepthWidth;
    const auto* m = roi_mask.ptr<std::uint8_t>(y - ry0 + 1) + 1;
    for (int x = rx0; x < rx1; ++x) {
      if (!m[x - rx0]) continue;
      const double z = model.metres(row[x]);
      const Eigen::Vector3d a((x - k.cx) * z / k.fx, (y - k.cy) * z / k.fy, 1.0);
      ata += a * a.transpose();
      atb += a * z;
      ++count;
    }
  }
  if (count < 50) return false;
  const Eigen::Vector3d plane = ata.ldlt().solve(atb);  // z = a X + b Y + c
  const double g = std::hypot(plane.x(), plane.y());    // tan(tilt)
  if (!std::isfinite(g) || g < 0.6 || g > 4.0) return false;  // under ~30 or beyond ~76 degrees
  const double s = std::sqrt(1.0 + g * g);                    // 1 / cos(tilt)
  const double cx = plane.x() / g, cy = plane.y() / g;        // image direction of the gradient
  // M = I + (s - 1) d d^T, about the ROI's origin, then shifted so that nothing is negative.
  cv::Matx22d m(1 + (s - 1) * cx * cx, (s - 1) * cx * cy, (s - 1) * cx * cy, 1 + (s - 1) * cy * cy);
  const int w = roi_mask.cols, h = roi_mask.rows;
  double minx = 0, miny = 0, maxx = 0, maxy = 0;
  for (const cv::Point2d p : {cv::Point2d(0, 0), cv::Point2d(w, 0), cv::Point2d(0, h), cv::Point2d(w, h)}) {
    const cv::Vec2d q = m * cv::Vec2d(p.x, p.y);
    minx = std::min(minx, q[0]);
    miny = std::min(miny, q[1]);
    maxx = std::max(maxx, q[0]);
    maxy = std::max(maxy, q[1]);
  }
  stretch = cv::Matx23d(m(0, 0), m(0, 1), -minx, m(1, 0), m(1, 1), -miny);
  cv::invertAffineTransform(stretch, unstretch);
  stretched_size = cv::Size(static_cast<int>(std::ceil(maxx - minx)) + 1, static_cast<int>(std::ceil(maxy - miny)) + 1);
  return true;
}

/// Whether the surface at grid cell `seed` continues, without a depth jump (steps under
/// kStepM between grid neighbours), to at least `arm_protrusion_m` behind `near_raw`, and nowhere
/// nearer: an arm's end reaching out of a body. A head, a torso, a box or a person farther back
/// has no such depth; the upper arm of a hand out of view has its forearm nearer.
bool HandFinder::Impl::reaches_back(cv::Point seed, std::uint16_t near_raw) {
  constexpr float kStepM = 0.03f;
  const float z0 = model.metres(near_raw);
  const float goal = z0 + static_cast<float>(params.arm_protrusion_m);
  if (++visit_generation == 0) {
    std::fill(visited.begin(), visited.end(), 0u);
    visit_generation = 1;
  }
  queue.clear();
  const auto at = [](cv::Point p) { return static_cast<std::size_t>(p.y) * kGridW + static_cast<std::size_t>(p.x); };
  visited[at(seed)] = visit_generation;
  queue.push_back(seed);
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const cv::Point c = queue[head];
    const float zc = model.metres(grid.at<std::uint16_t>(c));
    if (zc >= goal) return true;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const cv::Point n{c.x + dx, c.y + dy};
        if (n.x < 0 || n.y < 0 || n.x >= kGridW || n.y >= kGridH || visited[at(n)] == visit_generation) continue;
        const std::uint16_t d = grid.at<std::uint16_t>(n);
        if (d >= kNoReading) continue;
        const float zn = model.metres(d);
        if (zn <= 0 || std::abs(zn - zc) > kStepM) continue;
        if (zn < z0 - kStepM) return false;  // the surface goes on toward the sensor: a limb's middle, not its end
        visited[at(n)] = visit_generation;
        queue.push_back(n);
      }
  }
  return false;
}

/// Acquisition without a background: the nearest readings of the grid in turn (up to
/// kCandidates regions), each taken with its depth band as a hand if it is palm-shaped, clear of the
/// border, and an arm's end (reaches_back). Finds a hand held still since the first frame, which
/// the background holds; a box, a head or a torso fail the shape or the depth test.
bool HandFinder::Impl::find_arm_end(std::span<const std::uint16_t> raw, Palm& palm, cv::Point& seed_out) {
  constexpr int kCandidates = 6;
  candidate_mask.create(kGridH, kGridW, CV_8U);
  candidate_mask.setTo(0);
  const auto& k = model.intrinsics();
  for (int attempt = 0; attempt < kCandidates; ++attempt) {
    std::uint16_t near_raw = kNoReading;
    cv::Point seed{-1, -1};
    for (int gy = 0; gy < kGridH; ++gy) {
      const auto* g = grid.ptr<std::uint16_t>(gy);
      const auto* c = candidate_mask.ptr<std::uint8_t>(gy);
      for (int gx = 0; gx < kGridW; ++gx)
        if (g[gx] < near_raw && !c[gx] && g[gx] > 0) {
          near_raw = g[gx];
          seed = {gx, gy};
        }
    }
    if (seed.x < 0) return false;
    // The candidate: the grid cells within the depth band connected to the seed.
    const std::uint16_t far_raw = band_limit[near_raw];
    cv::compare(grid, far_raw, band_cells, cv::CMP_LE);
    cv::Rect box;
    cv::floodFill(band_cells, seed, cv::Scalar(128), &box, cv::Scalar(0), cv::Scalar(0), 8);
    cv::compare(band_cells, 128, band_region, cv::CMP_EQ);
    candidate_mask.setTo(255, band_region);
    // A hand with a stretch of forearm inside the band spans 5-35 cm; a box front or a torso more.
    const double z = model.metres(near_raw);
    const double w_m = box.width * kStep * z / k.fx, h_m = box.height * kStep * z / k.fy;
    if (std::max(w_m, h_m) < 0.05 || std::min(w_m, h_m) > 0.35) continue;
    if (z > params.max_acquire_depth_m) continue;  // nor here: a person walking by behind the user
    // The grid test first: it is cheap, the full-resolution measure is not.
    if (!reaches_back(seed, near_raw) || !measure(raw, box, near_raw, seed, palm) || !palm_accepted(palm)) continue;
    band_region.copyTo(arm);
    cv::dilate(arm, arm, kernel3);
    seed_out = seed;
    return true;
  }
  return false;
}

/// Continuity: a hand that has just left (across an edge, say) does not reappear far away at
/// once; what does is another part of the arm.
bool HandFinder::Impl::jumped(const Palm& palm) const {
  if (frames_since_seen == 0 || frames_since_seen > params.reacquire_frames) return false;
  return (model.back_project(palm.u, palm.v, palm.z) - last_seen).norm() > params.max_jump_m;
}

bool HandFinder::Impl::palm_accepted(const Palm& palm) const {
  const double expected_px = params.palm_radius_m * model.intrinsics().fx / palm.z + params.edge_margin_px;
  const bool inside = palm.u - expected_px >= params.invalid_left_columns && palm.u + expected_px <= kDepthWidth - 1 &&
                      palm.v - expected_px >= 0 && palm.v + expected_px <= kDepthHeight - 1;
  return inside && palm_sized(palm) && palm.valid_fraction >= 0.5 && !palm.cut_by_border;
}

HandObservation HandFinder::Impl::find(std::span<const std::uint16_t> raw) {
  HandObservation out;
  if (frames_since_seen < (1 << 20)) ++frames_since_seen;
  if (raw.size() != static_cast<std::size_t>(kDepthPixels)) return out;

  // 1. Grid sample; foreground = nearer than the background by foreground_m.
  for (int gy = 0; gy < kGridH; ++gy) {
    const std::uint16_t* row = raw.data() + static_cast<std::size_t>(gy * kStep + kStep / 2) * kDepthWidth + kStep / 2;
    auto* g = grid.ptr<std::uint16_t>(gy);
    auto* f = fg.ptr<std::uint8_t>(gy);
    const std::size_t base = static_cast<std::size_t>(gy) * kGridW;
    for (int gx = 0; gx < kGridW; ++gx) {
      const std::uint16_t d = row[gx * kStep];
      g[gx] = d;
      const std::uint16_t bg = stable[base + gx] != kUnknown ? stable[base + gx] : background_nearby(gx, gy);
      f[gx] = (d < kNoReading && bg != kUnknown && d < foreground_below[bg]) ? 255 : 0;
    }
  }
  cv::morphologyEx(fg, fg_open, cv::MORPH_OPEN, kernel3);
  const int n = cv::connectedComponentsWithStats(fg_open, labels, stats, centroids, 8, CV_32S);

  // 2. Per component: nearest reading; the component under the previous hand, else the nearest.
  nearest.assign(static_cast<std::size_t>(n), kNoReading);
  nearest_at.assign(static_cast<std::size_t>(n), cv::Point());
  for (int gy = 0; gy < kGridH; ++gy) {
    const int* l = labels.ptr<int>(gy);
    const auto* g = grid.ptr<std::uint16_t>(gy);
    for (int gx = 0; gx < kGridW; ++gx)
      if (l[gx] > 0 && g[gx] < nearest[static_cast<std::size_t>(l[gx])]) {
        nearest[static_cast<std::size_t>(l[gx])] = g[gx];
        nearest_at[static_cast<std::size_t>(l[gx])] = {gx, gy};
      }
  }
  int chosen = 0;
  const bool continuing = tracking;
  if (tracking) {
    // Continuity: the big-enough component nearest (on the grid) to the previous palm.
    double best = 12.0 * 12.0;
    for (int gy = std::max(0, previous_cell.y - 12); gy < std::min(kGridH, previous_cell.y + 13); ++gy) {
      const int* l = labels.ptr<int>(gy);
      for (int gx = std::max(0, previous_cell.x - 12); gx < std::min(kGridW, previous_cell.x + 13); ++gx) {
        if (l[gx] == 0 || stats.at<int>(l[gx], cv::CC_STAT_AREA) < params.min_component_cells) continue;
        const double d2 = (gx - previous_cell.x) * (gx - previous_cell.x) + (gy - previous_cell.y) * (gy - previous_cell.y);
        if (d2 < best) {
          best = d2;
          chosen = l[gx];
        }
      }
    }
  }
  if (chosen == 0) {
    std::uint16_t best = kNoReading;
    for (int c = 1; c < n; ++c)
      if (stats.at<int>(c, cv::CC_STAT_AREA) >= params.min_component_cells && nearest[static_cast<std::size_t>(c)] < best) {
        best = nearest[static_cast<std::size_t>(c)];
        chosen = c;
      }
  }

  Palm palm;
  bool found = false;
  if (chosen != 0) {
    const std::uint16_t near_raw = nearest[static_cast<std::size_t>(chosen)];
    const std::uint16_t far_raw = band_limit[near_raw];
    // The hand's cells: the chosen component within the depth band; their bounding box is the ROI.
    int x0 = kGridW, y0 = kGridH, x1 = -1, y1 = -1;
    for (int gy = 0; gy < kGridH; ++gy) {
      const int* l = labels.ptr<int>(gy);
      const auto* g = grid.ptr<std::uint16_t>(gy);
      for (int gx = 0; gx < kGridW; ++gx)
        if (l[gx] == chosen && g[gx] <= far_raw) {
          x0 = std::min(x0, gx);
          x1 = std::max(x1, gx);
          y0 = std::min(y0, gy);
          y1 = std::max(y1, gy);
        }
    }
    cv::compare(labels, chosen, arm, cv::CMP_EQ);
    cv::dilate(arm, arm, kernel3);
    excluded = true;
    const cv::Point seed = nearest_at[static_cast<std::size_t>(chosen)];
    if (measure(raw, cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1), near_raw, seed, palm)) {
      previous_cell = {static_cast<int>(palm.u) / kStep, static_cast<int>(palm.v) / kStep};
      tracking = palm_sized(palm);  // keep following an arm whose palm is at the edge
      // A new track does not start on a person walking by behind the user.
      const bool jump = jumped(palm);
      found = palm_accepted(palm) && (continuing || palm.z <= params.max_acquire_depth_m) && !jump;
      if (jump || (!found && !continuing)) tracking = false;
    } else {
      tracking = false;
    }
  } else {
    tracking = false;
  }
  // No hand where the background says: one held still (part of the background), or a new one.
  if (!found) {
    cv::Point seed;
    found = find_arm_end(raw, palm, seed) && !jumped(palm);
    if (found) {
      excluded = true;
      previous_cell = {static_cast<int>(palm.u) / kStep, static_cast<int>(palm.v) / kStep};
      tracking = true;
    }
  }
  if (!found) return out;

  const Eigen::Vector3d p = model.back_project(palm.u, palm.v, palm.z);
  last_seen = p;
  frames_since_seen = 0;
  out.tracked = true;
  out.position_m = p.cast<float>();
  out.u = static_cast<float>(palm.u);
  out.v = static_cast<float>(palm.v);
  out.palm_radius_m = static_cast<float>(palm.radius_m);
  const double size_score = std::exp(-std::pow((palm.radius_m - params.palm_radius_m) / 0.02, 2));
  out.confidence = static_cast<float>(std::clamp(palm.valid_fraction, 0.0, 1.0) * (0.5 + 0.5 * size_score));
  return out;
}

}  // namespace tachi::sensor
