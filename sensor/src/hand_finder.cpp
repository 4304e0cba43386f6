#include "tachi/sensor/hand_finder.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

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
  cv::Mat fg_open, labels, stats, centroids, component, arm;
  cv::Mat kernel3 = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  cv::Mat roi_mask, roi_closed, roi_dist;
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

  HandObservation find(std::span<const std::uint16_t> raw);
  void update_background(const cv::Mat* exclude);

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
  if (n <= 1) {
    tracking = false;
    return out;
  }

  // 2. Per component: nearest reading; the component under the previous hand, else the nearest.
  std::vector<std::uint16_t> nearest(static_cast<std::size_t>(n), kNoReading);
  std::vector<cv::Point> nearest_at(static_cast<std::size_t>(n));
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
  if (chosen == 0) {
    tracking = false;
    return out;
  }
  const std::uint16_t near_raw = nearest[static_cast<std::size_t>(chosen)];
  const std::uint16_t far_raw = band_limit[near_raw];

  // The hand's cells: the chosen component within the depth band; their bounding box is the ROI.
  int x0 = kGridW, y0 = kGridH, x1 = -1, y1 = -1;
  component.create(kGridH, kGridW, CV_8U);
  for (int gy = 0; gy < kGridH; ++gy) {
    const int* l = labels.ptr<int>(gy);
    const auto* g = grid.ptr<std::uint16_t>(gy);
    auto* c = component.ptr<std::uint8_t>(gy);
    for (int gx = 0; gx < kGridW; ++gx) {
      const bool in = l[gx] == chosen && g[gx] <= far_raw;
      c[gx] = in ? 255 : 0;
      if (in) {
        x0 = std::min(x0, gx);
        x1 = std::max(x1, gx);
        y0 = std::min(y0, gy);
        y1 = std::max(y1, gy);
      }
    }
  }
  cv::compare(labels, chosen, arm, cv::CMP_EQ);
  cv::dilate(arm, arm, kernel3);
  excluded = true;
  // Near the body part of the palm may be less than foreground_m in front of what was there
  // before, so at full resolution the depth band and connectivity bound the hand, in a ROI
  // grown by a palm diameter.
  const auto& k = model.intrinsics();
  const int kPad = static_cast<int>(std::ceil(2 * params.palm_radius_m * k.fx / std::max(0.3f, model.metres(near_raw)))) + 4;
  const int rx0 = std::max(0, x0 * kStep - kPad), ry0 = std::max(0, y0 * kStep - kPad);
  const int rx1 = std::min(kDepthWidth, (x1 + 1) * kStep + kPad), ry1 = std::min(kDepthHeight, (y1 + 1) * kStep + kPad);
  const int rw = rx1 - rx0, rh = ry1 - ry0;

  // 3. Full-resolution hand mask in the ROI, with a zero border so the image edge bounds the palm.
  roi_mask.create(rh + 2, rw + 2, CV_8U);
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
  const cv::Point seed = nearest_at[static_cast<std::size_t>(chosen)] * kStep + cv::Point(kStep / 2 - rx0 + 1, kStep / 2 - ry0 + 1);
  if (roi_mask.at<std::uint8_t>(seed) != 255) {
    tracking = false;
    return out;
  }
  cv::floodFill(roi_mask, seed, cv::Scalar(128));
  cv::compare(roi_mask, 128, roi_mask, cv::CMP_EQ);
  // Holes in the hand (dropouts with hand all around) count as hand: flood the outside from the
  // zero border; whatever it cannot reach is hand or hole. Gaps between fingers open to the
  // outside, so fingers stay apart and do not widen the palm.
  roi_closed = roi_mask.clone();
  cv::floodFill(roi_closed, cv::Point(0, 0), cv::Scalar(128));
  cv::compare(roi_closed, 128, roi_closed, cv::CMP_NE);
  cv::distanceTransform(roi_closed, roi_dist, cv::DIST_L2, cv::DIST_MASK_5);
  double max_dist = 0;
  cv::Point max_at;
  cv::minMaxLoc(roi_dist, nullptr, &max_dist, nullptr, &max_at);
  if (max_dist < 2.0) {
    tracking = false;
    return out;
  }
  // Sub-pixel: centroid of the distance-transform plateau (within 1 px of the maximum).
  double su = 0, sv = 0, sw = 0;
  const float plateau = static_cast<float>(max_dist - 1.0);
  const int r = static_cast<int>(std::ceil(max_dist));
  for (int y = std::max(0, max_at.y - r); y < std::min(roi_dist.rows, max_at.y + r + 1); ++y) {
    const float* dr = roi_dist.ptr<float>(y);
    for (int x = std::max(0, max_at.x - r); x < std::min(roi_dist.cols, max_at.x + r + 1); ++x)
      if (dr[x] >= plateau) {
        const double w = dr[x] - plateau;
        su += w * x;
        sv += w * y;
        sw += w;
      }
  }
  const double u = rx0 - 1 + su / sw, v = ry0 - 1 + sv / sw;

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
  if (palm_raw.size() < 8) {
    tracking = false;
    return out;
  }
  const auto mid = palm_raw.begin() + static_cast<std::ptrdiff_t>(palm_raw.size() / 2);
  std::nth_element(palm_raw.begin(), mid, palm_raw.end());
  const float z = model.metres(*mid);
  if (z <= 0) {
    tracking = false;
    return out;
  }
  const double radius_m = max_dist * z / k.fx;
  const double expected_px = params.palm_radius_m * k.fx / z + params.edge_margin_px;
  const bool inside = u - expected_px >= params.invalid_left_columns && u + expected_px <= kDepthWidth - 1 &&
                      v - expected_px >= 0 && v + expected_px <= kDepthHeight - 1;
  const bool palm_sized = radius_m >= params.min_palm_radius_m && radius_m <= params.max_palm_radius_m;
  const double valid_fraction = static_cast<double>(palm_raw.size()) / std::max(1, circle_pixels);

  previous_cell = {static_cast<int>(u) / kStep, static_cast<int>(v) / kStep};
  tracking = palm_sized;  // keep following an arm whose palm is at the edge
  if (!inside || !palm_sized || valid_fraction < 0.5) return out;

  const Eigen::Vector3d p = model.back_project(u, v, z);
  // Continuity: a hand that has just left (across an edge, say) does not reappear far away at
  // once; what does is another part of the arm.
  if (frames_since_seen > 0 && frames_since_seen <= params.reacquire_frames && (p - last_seen).norm() > params.max_jump_m) {
    tracking = false;
    return out;
  }
  last_seen = p;
  frames_since_seen = 0;
  out.tracked = true;
  out.position_m = p.cast<float>();
  out.u = static_cast<float>(u);
  out.v = static_cast<float>(v);
  out.palm_radius_m = static_cast<float>(radius_m);
  const double size_score = std::exp(-std::pow((radius_m - params.palm_radius_m) / 0.02, 2));
  out.confidence = static_cast<float>(std::clamp(valid_fraction, 0.0, 1.0) * (0.5 + 0.5 * size_score));
  return out;
}

}  // namespace tachi::sensor
