#include "tachi/sensor/hand_finder.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace tachi::sensor {
namespace {
constexpr int kStep = 4;
constexpr int kGridW = kDepthWidth / kStep;
constexpr int kGridH = kDepthHeight / kStep;
constexpr int kGridCells = kGridW * kGridH;
constexpr std::uint16_t kUnknown = 0;  // background not seen yet (raw 0 is nearer than the Kinect's range)
// A turned palm (measure_turned_palm).
constexpr double kTurnedHandBandM = 0.025;   // the hand (palm, fingers, thumb) lies within ~2 cm of the palm's plane
constexpr double kPalmBandM = 0.005;         // the palm within a few mm of it (depth noise ~1.5 mm across a turned palm at
                                             // 1 m); the round sides of fingers curve away by up to their radius, ~8 mm
constexpr double kPalmSquareM = 0.05;        // a square this wide fits in a palm (8 x 9 cm)
constexpr double kMinPalmCover = 0.5;        // ... at least this share of it with flat readings
constexpr int kPalmCandidates = 3;           // best-covered places compared (fingers, palm, wrist)
constexpr double kPalmRefitBandM = 0.010;    // a candidate's plane: the readings this near the hand's plane ...
constexpr double kPalmRefitRadiusM = 0.035;  // ... and this near the candidate
constexpr int kPalmPlanePasses = 2;
constexpr double kPalmSearchM = 0.07;        // the palm's circle is sought this near the palm found
constexpr double kMinPalmViewCos = 0.454;    // cos 63 degrees: the most oblique palm (to the line of sight) reported
constexpr double kViewCosSlack = 0.1;         // ~6 degrees, for the first, rough plane
constexpr double kCellM = 0.002;             // grid step in the palm's plane
// A palm seen nearly edge-on (measure_edge_on_palm).
constexpr double kMinEdgeOnViewCos = 0.174;  // cos 80 degrees: beyond, the palm is a line of readings
constexpr double kMaxPlacedViewCos = 0.707;  // cos 45 degrees: a palm seen more squarely is measured, never placed
constexpr double kTipToPalmCentreM = 0.12;   // the hand's far end (its readings' 99.5th percentile along
                                             // the hand) to the palm centre; see measure_edge_on_palm
constexpr double kTipQuantile = 0.995;       // the far end: robust to a few stray readings
constexpr double kPalmHalfLengthM = 0.045;   // the palm spans this either side of its centre along the hand
constexpr double kEdgeSliceM = 0.01;         // the palm's far edge is taken in slices this long along the hand ...
constexpr int kEdgeSlices = static_cast<int>(2 * kPalmHalfLengthM / kEdgeSliceM + 0.5);  // ... over its stretch
constexpr double kEdgeQuantile = 0.99;       // ... each slice's edge (and, with too few slices, the whole stretch's): robust to stray readings
constexpr int kMinSliceReadings = 5;         // ... a slice with fewer readings has no edge
constexpr int kMinEdgeSlices = 3;            // ... with fewer slices, the whole stretch's edge
constexpr double kArmSearchM = 0.25;         // the forearm: the surface that runs on from the hand, this near it
constexpr double kArmAxisM = 0.08;           // ... and this near the hand's axis (a forearm's radius ~2.8 cm, its wrist 3.4 cm behind the palm)
constexpr double kAxisKeptShare = 0.8;       // the hand's axis: refitted to this share of its readings nearest it ...
constexpr int kAxisPasses = 3;               // ... this many times (turned_palm's edge-on RMS: 10.8 -> 9.8 mm, 0.7-0.9 alike)
constexpr double kFrontSurfaceM = 0.02;     // a candidate's front surface (find_arm_end's border test): a palm is flat within ~1 cm
constexpr double kJointRadiusM = 0.08;       // an elbow and the start of its limbs (an upper arm is ~9 cm across)
constexpr double kSurfaceStepM = 0.03;       // a step between grid neighbours on one surface (as reaches_back)
constexpr double kEndBandNearM = 0.02;       // a hand at an arm's geodesic end: its band starts this in front of its
                                             // nearest grid reading (full resolution finds a little nearer), not at
                                             // the forearm running on nearer to the elbow
/// walk_surface: what to do with a neighbouring cell on the surface.
enum class Step { kTake, kSkip, kAbort };
constexpr int kMinArmCells = 3;              // fewer: which end is the wrist is not known, no estimate
constexpr int kMinBorderReadings = 5;        // a hand leaving the image: this many readings at its border
constexpr double kMinPalmShare = 0.55;       // of the palm stretch's flat readings, within the palm placed

/// Sub-pixel centre of a distance transform's maximum `peak` at `at`: the centroid of its plateau
/// (values within 1 px of the maximum), weighted by the height above it.
cv::Point2d plateau_centre(const cv::Mat& dist, double peak, cv::Point at) {
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
  return {su / sw, sv / sw};
}

/// `filled` = `region` (a mask with a zero border) with its holes filled: the outside flooded from
/// the border, whatever it cannot reach is region or hole. Gaps between fingers open to the
/// outside, so they stay open. `region` and `filled` may be the same image.
void fill_holes(const cv::Mat& region, cv::Mat& filled);

/// The largest circle inscribed in the non-zero pixels of `region`: `dist` its distance transform
/// (L2, 5x5 mask), `peak` the radius at `peak_at`, `centre` its sub-pixel centre (plateau_centre).
/// False when no circle of 2 px fits.
bool largest_inscribed_circle(const cv::Mat& region, cv::Mat& dist, double& peak, cv::Point& peak_at, cv::Point2d& centre);

/// How far (pixels) from a distance transform's maximum `peak` at `at` the region stays nearly as
/// wide (values >= kRidgeShare of the peak): a palm is a compact blob, its
/// widest place a short ridge (the palm and the fingers beside it); a limb is a tube of constant
/// width (the upper arm, 4.5 cm in radius, holds a palm-sized circle all along its length).
/// Every wide place of the region counts, unless `connected`: then only the ridge through the
/// maximum. A palm held up with its upper arm at its depth, beyond the narrower wrist and forearm,
/// measured 32 cm of ridge counted whole (seed 86 of the tuning range: its first 15 frames
/// untracked); counted connected for every new track, an elbow whose forearm left the image became
/// a short ridge and was taken (seed 121: 23 frames 34 cm off). So only a palm sought near the
/// nearest reading (arm_end_candidate's second look) counts its own ridge. `connected_scratch`: null
/// for every wide place, else a mask of dist's size (a view of a frame-sized buffer: nothing allocated).
constexpr double kRidgeShare = 0.85;
double ridge_length(const cv::Mat& dist, double peak, cv::Point at, cv::Mat* connected_scratch) {
  const auto level = static_cast<float>(kRidgeShare * peak);
  int far2 = 0;
  if (connected_scratch == nullptr) {
    for (int y = 0; y < dist.rows; ++y) {
      const float* row = dist.ptr<float>(y);
      const int dy2 = (y - at.y) * (y - at.y);
      for (int x = 0; x < dist.cols; ++x)
        if (row[x] >= level) far2 = std::max(far2, dy2 + (x - at.x) * (x - at.x));
    }
    return std::sqrt(static_cast<double>(far2));
  }
  cv::Mat& mask = *connected_scratch;
  cv::compare(dist, level, mask, cv::CMP_GE);
  cv::floodFill(mask, at, cv::Scalar(128), nullptr, cv::Scalar(0), cv::Scalar(0), 8);
  for (int y = 0; y < mask.rows; ++y) {
    const auto* row = mask.ptr<std::uint8_t>(y);
    const int dy2 = (y - at.y) * (y - at.y);
    for (int x = 0; x < mask.cols; ++x)
      if (row[x] == 128) far2 = std::max(far2, dy2 + (x - at.x) * (x - at.x));
  }
  return std::sqrt(static_cast<double>(far2));
}

/// One grid row of HandFinder's background learning (update_background): a reading steady for
/// kSteadyFrames becomes the background where it is nearer than the current one (a resting arm,
/// an object put down later); a steady one replaces it whatever its depth after kLongSteadyFrames
/// (an object removed); cells marked in `exclude` (the followed arm) keep their background.
/// Written with masks rather than branches, so that it vectorises: noise makes "steady"
/// unpredictable, and with branches this was 46 instructions a cell (7x the time).
void learn_background_row(const std::uint16_t* __restrict grid_row, const std::uint8_t* __restrict exclude,
                          std::uint16_t* __restrict stable, std::uint16_t* __restrict farthest, std::uint16_t* __restrict run_value,
                          std::uint16_t* __restrict run_length) {
  constexpr std::uint16_t kSteadyFrames = 10;
  constexpr std::uint16_t kLongSteadyFrames = 300;
  const auto mask = [](bool b) { return static_cast<std::uint16_t>(-static_cast<int>(b)); };  // 0xffff or 0
  const auto inv = [](std::uint16_t m) { return static_cast<std::uint16_t>(~m); };
  for (int gx = 0; gx < kGridW; ++gx) {
    const std::uint16_t d = grid_row[gx], v = run_value[gx], l = run_length[gx], s = stable[gx], f = farthest[gx];
    const std::uint16_t valid = mask(d < kNoReading);
    // Steady: within ~1 cm (a few raw units, more at long range where noise is larger).
    const auto tolerance = static_cast<std::uint16_t>(2 + (v >> 8));
    const auto difference = static_cast<std::uint16_t>(std::max(d, v) - std::min(d, v));
    const std::uint16_t steady = mask(difference <= tolerance);
    const auto grown = static_cast<std::uint16_t>(l + (l != 0xffff));
    const std::uint16_t moved = valid & inv(steady);
    const auto length = static_cast<std::uint16_t>((valid & steady & grown) | (moved & 1) | (inv(valid) & l));
    const auto value = static_cast<std::uint16_t>((moved & d) | (inv(moved) & v));
    const std::uint16_t further = valid & mask(d > f);
    farthest[gx] = static_cast<std::uint16_t>((further & d) | (inv(further) & f));
    run_length[gx] = length;
    run_value[gx] = value;
    const std::uint16_t nearer = mask((s == kUnknown) | (value < s));
    const std::uint16_t learn = valid & inv(mask(exclude[gx] != 0)) &
                                ((mask(length >= kSteadyFrames) & nearer) | mask(length >= kLongSteadyFrames));
    stable[gx] = static_cast<std::uint16_t>((learn & value) | (inv(learn) & s));
  }
}

/// The smallest reading in a grid row among the cells with a reading other than 0 and not marked
/// in `tried`; kNoReading when there is none.
std::uint16_t untried_row_minimum(const std::uint16_t* __restrict grid_row, const std::uint8_t* __restrict tried) {
  std::uint16_t best = kNoReading;
  for (int gx = 0; gx < kGridW; ++gx) {
    const std::uint16_t candidate = ((tried[gx] != 0) | (grid_row[gx] == 0)) ? kNoReading : grid_row[gx];
    best = std::min(best, candidate);
  }
  return best;
}

/// The maximum of a distance transform (CV_32F, >= 0) and its first place in row order, as
/// cv::minMaxLoc gives it, for a third of its work: non-negative floats order as their bit
/// patterns do, so each row's maximum is an integer reduction, which vectorises.
void distance_peak(const cv::Mat& dist, double& peak, cv::Point& at) {
  std::int32_t best = -1;
  int best_row = 0;
  for (int y = 0; y < dist.rows; ++y) {
    const float* __restrict row = dist.ptr<float>(y);
    std::int32_t row_max = -1;
    for (int x = 0; x < dist.cols; ++x) {
      std::int32_t bits = 0;
      std::memcpy(&bits, row + x, sizeof bits);
      row_max = std::max(row_max, bits);
    }
    if (row_max > best) {
      best = row_max;
      best_row = y;
    }
  }
  const float* row = dist.ptr<float>(best_row);
  int x = 0;
  while (x + 1 < dist.cols && std::bit_cast<std::int32_t>(row[x]) != best) ++x;
  at = {x, best_row};
  peak = row[x];
}

void fill_holes(const cv::Mat& region, cv::Mat& filled) {
  if (filled.data != region.data) region.copyTo(filled);
  cv::floodFill(filled, cv::Point(0, 0), cv::Scalar(128));
  cv::compare(filled, 128, filled, cv::CMP_NE);
}

bool largest_inscribed_circle(const cv::Mat& region, cv::Mat& dist, double& peak, cv::Point& peak_at, cv::Point2d& centre) {
  cv::distanceTransform(region, dist, cv::DIST_L2, cv::DIST_MASK_5);
  peak = 0;
  distance_peak(dist, peak, peak_at);
  if (peak < 2.0) return false;
  centre = plateau_centre(dist, peak, peak_at);
  return true;
}
}  // namespace

struct HandFinder::Impl {
  DepthModel model;
  HandFinderParams params;
  std::array<std::uint16_t, 2048> foreground_below{};  // raw < this[bg] means foreground
  std::array<std::uint16_t, 2048> band_limit{};        // hand band: raw <= this[nearest raw]
  std::array<std::uint16_t, 2048> front_limit{};       // a candidate's front surface: raw <= this[nearest raw]
  std::array<float, 2048> surface_step{};              // walk_surface: the largest step between neighbours at a raw reading
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
  cv::Mat fg_open, labels, arm;
  cv::Mat candidate_mask, band_cells, band_region, front_cells;  // find_arm_end's candidates
  std::vector<std::uint16_t> nearest;  // per component: nearest reading, and where
  std::vector<cv::Point> nearest_at;
  std::vector<int> area;  // per component: cells
  std::vector<cv::Rect> component_box;  // per component: its cells' bounding box on the grid (came_to_rest)
  std::vector<std::uint32_t> visited = std::vector<std::uint32_t>(kGridCells, 0);  // reaches_back's BFS
  std::uint32_t visit_generation = 0;
  std::vector<cv::Point> queue;
  cv::Mat kernel3 = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  cv::Mat roi_mask, roi_closed, roi_dist, ridge_mask;
  cv::Mat roi_mask_buffer = cv::Mat(kDepthHeight + 2, kDepthWidth + 2, CV_8U);
  cv::Mat roi_closed_buffer = cv::Mat(kDepthHeight + 2, kDepthWidth + 2, CV_8U);
  cv::Mat roi_dist_buffer = cv::Mat(kDepthHeight + 2, kDepthWidth + 2, CV_32F);
  cv::Mat ridge_mask_buffer = cv::Mat(kDepthHeight + 2, kDepthWidth + 2, CV_8U);  // ridge_length's connected ridge
  std::vector<std::uint16_t> palm_raw;
  std::vector<cv::Point> palm_pixels;      // ... and where they are
  bool tracking = false;
  cv::Point previous_cell{-1, -1};
  // The grid cell of the last palm reported: previous_cell is also where a component that was
  // measured and refused this frame had its palm, which is not where the hand was.
  cv::Point last_seen_cell{-1, -1};
  Eigen::Vector3d last_seen = Eigen::Vector3d::Zero();
  int frames_since_seen = 1 << 20;
  Eigen::Vector3d last_step = Eigen::Vector3d::Zero();  // last_seen less the palm a frame before it
  bool step_known = false;                               // the palm was found in two frames running
  // The last palm that kept its course (found a third frame running within max_off_course_m of where
  // its step carried it): the jump test's reference while the hand is lost (jump_from_kept_course).
  Eigen::Vector3d last_on_course = Eigen::Vector3d::Zero();
  int frames_since_on_course = 1 << 20;
  // The largest circle of the palm this track has reported (own_palm_shrink_m): what the hand's whole
  // palm holds at its turn, for the border-cut test of a followed palm.
  double own_palm_radius_m = 0;
  bool continued_in_background = false;  // this frame (find clears it): find_arm_end found the last frame's hand where it was, or its step carried it

  Impl(const DepthModel& m, const HandFinderParams& p) : model(m), params(p) {
    for (std::size_t raw = 0; raw < 2048; ++raw) {
      const double z = model.metres(static_cast<std::uint16_t>(raw));
      foreground_below[raw] = raw_limit(z > 0 ? z - params.foreground_m : 0.0, false);
      band_limit[raw] = raw_limit(z > 0 ? z + params.hand_depth_band_m : 0.0, true);
      front_limit[raw] = raw_limit(z > 0 ? z + kFrontSurfaceM : 0.0, true);
      // The Kinect's depth step at this reading (one raw unit, 0.0031 z^2 m: 3 mm at 1 m, 1.5 cm at
      // 2.2 m); none past the last valid reading.
      const double quantum = z > 0 && raw < kMaxValidRaw ? model.metres(static_cast<std::uint16_t>(raw + 1)) - z : 0.0;
      surface_step[raw] = static_cast<float>(std::max(kSurfaceStepM, params.surface_step_quanta * quantum));
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
    bool placed_by_model = false; ///< an edge-on palm: its centre placed by the hand's shape (lower confidence)
    bool in_own_plane = false;    ///< measured in its own plane (measure_turned_palm): its circle is the palm face's already
    double tips_down = 0;         ///< placed palms: sine of the fingers' direction below the camera's level (1: down)
    double ridge_m = 0;           ///< how far from the circle's centre the region stays nearly as wide (ridge_length)
    double bulge_significance = 0;  ///< how surely its readings bulge toward the sensor (measure_bulge) ...
    double bulge_min_per_m = 0;     ///< ... and how much along the flattest direction (1 / (2 R) for a sphere's cap)
    double bulge_view_cos = 0;      ///< ... and how squarely it faces the sensor (cosine to the line of sight)
  };
  /// find_arm_end: a candidate refused this frame as no arm's end (refuse_arm_of_refused_palm), its
  /// palm measured only when a later candidate that holds its band region has passed.
  struct RefusedArmEnd {
    cv::Rect box;           // its band's cells' box (grid cells)
    std::uint16_t near_raw = 0;
    cv::Point seed;
    bool two_sided = false;
    cv::Mat region;         // its band region (CV_8U grid mask); kept allocated across frames
    bool measured = false;  // palm and is_palm hold the measure
    Palm palm;
    bool is_palm = false;   // measured, and it passes a new track's palm tests
    bool overlapped = false;  // scratch: the candidate being tried holds its region
  };
  std::vector<RefusedArmEnd> refused;  // the first refused_count are this frame's
  std::size_t refused_count = 0;
  cv::Mat refused_regions;  // the union of their regions

  HandObservation find(std::span<const std::uint16_t> raw);
  void update_background(const cv::Mat* exclude);
  /// Whose palm a measurement is for: a new track's, whose tests ask for its bulge (is_dome), or
  /// the followed hand's, whose palm is sought near its nearest reading and where it was
  /// (HandFinderParams::palm_from_nearest_m), or a new track's measured again near its nearest
  /// reading (its widest place was a limb: arm_end_candidate).
  enum class Candidate { kNewTrack, kFollowed, kNewTrackNearSeed };
  /// `two_sided`: the band also stops kEndBandNearM in front of near_raw (a hand at an arm's
  /// geodesic end, whose forearm runs on nearer to an elbow; see arm_end).
  bool measure(std::span<const std::uint16_t> raw, const cv::Rect& cells, std::uint16_t near_raw, cv::Point seed_cell, Palm& palm,
               bool two_sided, Candidate candidate);
  /// Sides of the ROI (for measure_in_band's `grow` and `touched`).
  enum Side : int { kLeft = 1, kTop = 2, kRight = 4, kBottom = 8 };
  /// Steps 3-4 in the depth band [near_raw, far_raw]: the ROI is the cells' box padded by a palm
  /// diameter, twice that on the sides in `grow`; `touched` says where the band's region met it.
  bool measure_in_band(std::span<const std::uint16_t> raw, const cv::Rect& cells, std::uint16_t near_raw, std::uint16_t far_raw,
                       cv::Point seed_cell, Palm& palm, int grow, bool two_sided, Candidate candidate);
  int touched = 0;
  void measure_bulge(std::span<const std::uint16_t> raw, Palm& palm) const;
  /// A new track's test: the palm circle bulges like a head's or an elbow's (HandFinderParams::dome_significance).
  bool is_dome(const Palm& palm) const {
    return params.dome_significance > 0 && palm.bulge_significance > params.dome_significance &&
           palm.bulge_min_per_m > params.dome_min_curvature_per_m && palm.bulge_view_cos > params.dome_min_view_cos;
  }
  template <class OnCell, class OnStep>
  bool walk_surface(cv::Point seed, OnCell&& on_cell, OnStep&& on_step, bool depth_steps = false);
  static std::size_t grid_index(cv::Point p) { return static_cast<std::size_t>(p.y) * kGridW + static_cast<std::size_t>(p.x); }
  bool reaches_back(cv::Point seed, std::uint16_t near_raw, bool past_nearer = false);
  bool front_touches_border(cv::Point seed, std::uint16_t near_raw, bool two_sided = false);
  /// Whether that front surface reaches the image's border farther from the palm's centre than a
  /// hand's fingertips do (kTipToPalmCentreM and a cell): the border cuts something beyond the hand.
  bool front_crosses_border_beyond_hand(cv::Point seed, std::uint16_t near_raw, bool two_sided, const Palm& palm);
  /// The grid cells of the depth band [near side, band_limit[near_raw]] connected to `seed` into
  /// band_region (255), their box into `box`; `two_sided`: the near side is kEndBandNearM in front.
  void band_cells_at(cv::Point seed, std::uint16_t near_raw, bool two_sided, cv::Rect& box);
  /// The near side of a two-sided band around `near_raw` (kEndBandNearM in front of it).
  std::uint16_t end_band_near(std::uint16_t near_raw) const { return raw_limit(model.metres(near_raw) - kEndBandNearM, false); }
  bool is_joint(cv::Point seed, std::uint16_t near_raw, const cv::Point* reached_from = nullptr);
  /// The end of an arm (arm_end): the hand at the arm's geodesic extremity.
  struct ArmEnd {
    cv::Point seed;              ///< the end's hand: its nearest grid cell ...
    std::uint16_t near_raw = 0;  ///< ... and that reading
    cv::Rect cells;              ///< the end's hand: its grid cells' bounding box
    bool elsewhere = false;      ///< the end's hand does not hold the arm's nearest reading, which lies on the way to it
  };
  bool arm_end(cv::Point seed, std::uint16_t near_raw, ArmEnd& end);
  std::vector<cv::Point> arm_region, arm_roots;  // arm_end's surface, and where it runs on toward the body
  std::vector<std::uint32_t> in_arm_region = std::vector<std::uint32_t>(kGridCells, 0);  // generation marks
  std::vector<std::uint32_t> geodesic_pass = std::vector<std::uint32_t>(kGridCells, 0);  // ... of geodesic's
  std::vector<float> geodesic = std::vector<float>(kGridCells, 0.0f);  // metres along the surface
  std::uint32_t arm_generation = 0, geodesic_generation = 0;
  std::vector<std::pair<float, int>> geodesic_heap;
  /// Dijkstra over arm_region from `sources` (distance 0), up to `limit_m`; the cell reached
  /// farthest. Distances (3D, metres) land in `geodesic`, marked by geodesic_pass.
  cv::Point geodesic_walk(const std::vector<cv::Point>& sources, float limit_m);
  std::vector<cv::Point> slab;  // is_joint's cells 5-10 cm behind the candidate
  /// A plane (camera frame, metres) through the readings under a mask.
  struct Plane {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = -Eigen::Vector3d::UnitZ();  ///< unit, toward the sensor
  };
  struct Roi {
    int x0, y0, x1, y1;  ///< [x0, x1) x [y0, y1) of the frame; roi_mask and its kin have a 1 px border around it
  };
  /// A metric grid in a plane: cell (i, j) is the point origin + kCellM (i e1 + j e2).
  struct PlaneGrid {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero(), e1 = Eigen::Vector3d::UnitX(), e2 = Eigen::Vector3d::UnitY();
    cv::Size size;
    cv::Matx33d grid_to_roi;  ///< homography: grid cell -> ROI pixel
    Eigen::Vector3d point(double i, double j) const { return origin + kCellM * (i * e1 + j * e2); }
  };
  bool fit_plane(std::span<const std::uint16_t> raw, const Roi& roi, Plane& plane, double* spread_m = nullptr);
  static bool plane_through(const Eigen::Matrix3d& outer, const Eigen::Vector3d& sum, int count, Plane& plane,
                            double* spread_m = nullptr);
  void plane_band_mask(std::span<const std::uint16_t> raw, const Roi& roi, const Plane& plane, double band);
  void select_near_plane(const Plane& plane, double band, const Eigen::Vector3d* centre, double radius, bool mark);
  bool fit_selected(Plane& plane, double* spread_m = nullptr) const;
  bool make_plane_grid(const Roi& roi, const Plane& plane, PlaneGrid& out) const;
  bool measure_turned_palm(std::span<const std::uint16_t> raw, const Roi& roi, cv::Point seed, Plane plane, Palm& palm);
  bool measure_edge_on_palm(const Roi& roi, const Plane& hand_plane, Palm& palm);
  Eigen::Vector3d palm_face_centre(std::span<const std::uint16_t> raw, const Palm& palm, const Eigen::Vector3d& at);
  Eigen::Vector3d trimmed_major_axis(Eigen::Vector3d axis, Eigen::Vector3d mean);
  std::vector<double> off_axis;            // trimmed_major_axis's distances of the hand's readings from the axis
  bool arm_centre(const Roi& roi, const Eigen::Vector3d& hand_centre, const Eigen::Vector3d& hand_axis, Eigen::Vector3d& centre);
  std::vector<double> along;               // measure_edge_on_palm's coordinates of the hand's readings
  std::vector<std::size_t> palm_stretch;   // ... and the palm's stretch of them
  std::vector<std::pair<int, double>> sliced;  // ... its flat readings' slices along it and their far-side coordinates
  std::vector<double> slice_centres;           // ... and the centre each slice's far edge gives
  cv::Mat rectified_closed, rectified_mask, rectified_dist, rectified_cover;  // measure_turned_palm's view of the palm plane
  cv::Mat roi_hand;  // measure_turned_palm's hand region (a view of roi_hand_buffer)
  struct HandPoint {
    Eigen::Vector3d point;  ///< camera frame, metres
    int mask_offset;        ///< its byte in roi_mask (and roi_hand)
  };
  std::vector<HandPoint> hand_points;  // the hand region's readings
  std::vector<std::size_t> selected;   // select_near_plane's choice among them

  cv::Mat roi_hand_buffer = cv::Mat(kDepthHeight + 2, kDepthWidth + 2, CV_8U);
  bool follow_component(std::span<const std::uint16_t> raw, int component, bool continuing, bool take_over, Palm& palm);
  bool came_to_rest(int component) const;
  bool find_arm_end(std::span<const std::uint16_t> raw, Palm& palm, cv::Point& seed);
  bool arm_end_candidate(std::span<const std::uint16_t> raw, cv::Point seed, std::uint16_t near_raw, const cv::Rect& box,
                         bool two_sided, Palm& palm);
  bool palm_accepted(const Palm& palm) const;
  bool jumped(const Palm& palm) const;
  bool off_course(const Palm& palm) const;
  /// Whether a candidate's hand cells (the band's region, on the grid) reach the image's border
  /// (the invalid band at the left included). A new track does not start there: what the border
  /// cuts may be anything (the corner of a table or a box shows a palm-sized face and a side
  /// running back like an arm), and a hand is reported only whole in view anyway.
  /// The first grid column with readings: Kinect's invalid band at the left is no image.
  int left_border_cell() const { return (params.invalid_left_columns + kStep - 1) / kStep; }
  /// Whether two grid masks (CV_8U, kGridH x kGridW) share a cell inside `cells`.
  static bool overlaps(const cv::Mat& a, const cv::Mat& b, const cv::Rect& cells) {
    for (int gy = cells.y; gy < cells.y + cells.height; ++gy) {
      const std::uint8_t* pa = a.ptr<std::uint8_t>(gy);
      const std::uint8_t* pb = b.ptr<std::uint8_t>(gy);
      for (int gx = cells.x; gx < cells.x + cells.width; ++gx)
        if ((pa[gx] & pb[gx]) != 0) return true;
    }
    return false;
  }
  /// A new track's palm shape: a palm-sized circle whose width does not run on along a limb for more than
  /// `max_ridge_m` (max_palm_ridge_m in the search, max_foreground_new_palm_ridge_m from the foreground), no
  /// dome, no shoulders beneath it (a head).
  bool new_track_shape(const Palm& p, double max_ridge_m) const {
    return p.radius_m <= params.max_new_palm_radius_m && p.ridge_m <= max_ridge_m && !is_dome(p) && !shoulders_below(p);
  }
  /// A new track's palm tests, as arm_end_candidate asks them of a candidate with nearest reading near_raw
  /// (which asks max_new_palm_from_nearest_m too, of its own candidate; a refused palm is not asked it).
  bool new_track_palm(const Palm& p, std::uint16_t near_raw) const {
    return palm_accepted(p) && new_track_shape(p, params.max_palm_ridge_m) && !behind_band(p, near_raw);
  }
  /// refuse_arm_of_refused_palm: a candidate whose band held one of this frame's refused arm ends
  /// (their `overlapped`, set when it was tried) and whose palm passed lies on the arm of such a palm
  /// that passes a new track's tests, unless it is measured at one of those palms.
  bool on_arm_of_refused_palm(std::span<const std::uint16_t> raw, const Palm& palm);
  bool touches_border(const cv::Rect& cells) const {
    const int left = left_border_cell();
    return cells.x <= left || cells.y <= 0 || cells.x + cells.width >= kGridW || cells.y + cells.height >= kGridH;
  }
  /// Whether a component's nearest reading (grid cell `seed`) lies at the image's border: what is
  /// nearer still is out of view, so its end (a hand, or only a forearm of an arm that leaves the
  /// image) is not seen, and a track does not start on it: an arm leaving the image shows a thick
  /// place at its bend that passes for a palm (seen on seed 78, 55 frames).
  bool nearest_at_border(cv::Point seed) const {
    const int m = params.nearest_border_cells;
    return m >= 0 && touches_border(cv::Rect(seed.x - m, seed.y - m, 2 * m + 1, 2 * m + 1));
  }
  /// HandFinderParams::head_shoulders_half_m: a body's shoulders beneath the palm circle (a head).
  bool shoulders_below(const Palm& palm) const {
    if (params.head_shoulders_half_m <= 0 || palm.z <= 0) return false;
    const auto& k = model.intrinsics();
    const double half_px = params.head_shoulders_half_m * k.fx / palm.z;
    // Where the image's side cuts the span (a person walking in from the side), the part in view, if
    // it is at least half the span (seeds 320, 466: the head at the image's left edge).
    const int gx0 = std::max(left_border_cell(), static_cast<int>(std::floor((palm.u - half_px) / kStep)));
    const int gx1 = std::min(kGridW - 1, static_cast<int>(std::ceil((palm.u + half_px) / kStep)));
    if (gx1 - gx0 + 1 < static_cast<int>(half_px / kStep)) return false;
    const int gy0 = static_cast<int>((palm.v + 0.25 * k.fy / palm.z) / kStep);
    const int gy1 = std::min(kGridH - 1, static_cast<int>((palm.v + 0.45 * k.fy / palm.z) / kStep));
    for (int gy = std::max(0, gy0); gy <= gy1; ++gy) {
      const auto* g = grid.ptr<std::uint16_t>(gy);
      int near = 0, readings = 0;
      bool broken = false;
      for (int gx = gx0; gx <= gx1 && !broken; ++gx) {
        if (g[gx] == 0 || g[gx] >= kNoReading) continue;  // a dropout: neither for nor against
        ++readings;
        if (std::abs(model.metres(g[gx]) - palm.z) <= params.head_depth_m) ++near;
        else broken = true;
      }
      // Across the whole span at the palm's depth (dropouts aside: at most a quarter of the cells).
      if (!broken && readings * 4 >= (gx1 - gx0 + 1) * 3 && near == readings) return true;
    }
    return false;
  }
  /// HandFinderParams::body_surround_share: the palm circle lies in the static scene's surface at its
  /// own depth (a near user's upper arm or shoulder beside the torso), not in front of it as a hand does.
  bool set_in_static_surface(const Palm& palm) const {
    if (params.body_surround_share <= 0 || params.body_surround_share > 1 || palm.z <= 0) return false;
    const double fx = model.intrinsics().fx;
    // Grid cell (gx, gy) samples pixel (kStep gx + kStep / 2, kStep gy + kStep / 2).
    const double cx = (palm.u - kStep / 2) / kStep, cy = (palm.v - kStep / 2) / kStep;
    const double r0 = params.body_ring_inner_m * fx / palm.z / kStep, r1 = params.body_ring_outer_m * fx / palm.z / kStep;
    int readings = 0, static_near = 0;
    for (int gy = std::max(0, static_cast<int>(cy - r1)); gy <= std::min(kGridH - 1, static_cast<int>(cy + r1)); ++gy) {
      const auto* g = grid.ptr<std::uint16_t>(gy);
      const auto* f = fg.ptr<std::uint8_t>(gy);
      for (int gx = std::max(0, static_cast<int>(cx - r1)); gx <= std::min(kGridW - 1, static_cast<int>(cx + r1)); ++gx) {
        const double d = std::hypot(gx - cx, gy - cy);
        if (d < r0 || d > r1 || g[gx] == 0 || g[gx] >= kNoReading) continue;  // outside the ring, or a dropout
        ++readings;
        if (f[gx] == 0 && std::abs(model.metres(g[gx]) - palm.z) <= params.body_depth_m) ++static_near;
      }
    }
    return readings > 0 && static_near > params.body_surround_share * readings;
  }
  /// A new track's palm beyond the hand's depth band of its candidate's nearest reading `near_raw`
  /// (max_new_palm_behind_nearest_m): measured on an arm running back from it, not on its hand.
  bool behind_band(const Palm& palm, std::uint16_t near_raw) const {
    return params.max_new_palm_behind_nearest_m > 0 && palm.z - model.metres(near_raw) > params.max_new_palm_behind_nearest_m;
  }
  /// Grid cell `c`'s reading as a 3D point (the cell's centre pixel at its depth).
  Eigen::Vector3d cell_point(cv::Point c) const {
    return model.back_project(c.x * kStep + kStep / 2, c.y * kStep + kStep / 2, model.metres(grid.at<std::uint16_t>(c)));
  }
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
  if (first_frame) {
    for (int gy = 0; gy < kGridH; ++gy) {
      const auto* g = grid.ptr<std::uint16_t>(gy);
      for (int gx = 0; gx < kGridW; ++gx) {
        const std::uint16_t d = g[gx];
        if (d >= kNoReading) continue;
        const std::size_t i = static_cast<std::size_t>(gy) * kGridW + gx;
        farthest[i] = std::max(farthest[i], d);
        stable[i] = run_value[i] = d;
        run_length[i] = 1;
      }
    }
    first_frame = false;
    return;
  }
  static const std::array<std::uint8_t, kGridW> kNoExclusion{};
  for (int gy = 0; gy < kGridH; ++gy) {
    const std::size_t base = static_cast<std::size_t>(gy) * kGridW;
    learn_background_row(grid.ptr<std::uint16_t>(gy), exclude ? exclude->ptr<std::uint8_t>(gy) : kNoExclusion.data(),
                         stable.data() + base, farthest.data() + base, run_value.data() + base, run_length.data() + base);
  }
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
  impl_->frames_since_on_course = 1 << 20;
  impl_->own_palm_radius_m = 0;
  impl_->step_known = false;
}

/// Steps 3-4 for one candidate hand: its grid cells `cells` (bounding box), the nearest reading
/// `near_raw` at grid cell `seed_cell`. Fills `palm`; false when no palm-like region is there.
bool HandFinder::Impl::measure(std::span<const std::uint16_t> raw, const cv::Rect& cells, std::uint16_t near_raw,
                               cv::Point seed_cell, Palm& palm, bool two_sided, Candidate candidate) {
  // From a fresh palm: callers measure one Palm for candidate after candidate, and the circle path does not
  // set every field (an earlier candidate's placed_by_model, in_own_plane or tips_down would stay).
  palm = Palm{};
  if (!measure_in_band(raw, cells, near_raw, band_limit[near_raw], seed_cell, palm, 0, two_sided, candidate)) return false;
  // No palm or no whole one, and the band's region was cut by the ROI (made from the foreground's cells, which
  // may hold only part of the hand: one rising through where the arm rested is less than
  // foreground_m in front of it there; a hand held still, learnt into the background but for its
  // fingers): measured again with the ROI grown by a palm diameter on those sides. A palm-sized
  // circle there replaces none; a larger one replaces a small one if it adjoins it, within a palm's
  // diameter, as a palm adjoins its fingers (seed 66: the fingers' block, a 3.3 cm circle 6 cm above
  // the palm's; seed 369: a circle 30 cm away, on whatever else the grown ROI's band held).
  if ((!palm_sized(palm) || palm.radius_m < params.whole_palm_radius_m) && touched != 0) {
    Palm grown;
    const auto adjoins = [&] {
      return (model.back_project(grown.u, grown.v, grown.z) - model.back_project(palm.u, palm.v, palm.z)).norm() <=
             2 * params.palm_radius_m;
    };
    if (measure_in_band(raw, cells, near_raw, band_limit[near_raw], seed_cell, grown, touched, two_sided, candidate) &&
        palm_sized(grown) && (!palm_sized(palm) || (grown.radius_m > palm.radius_m && adjoins())))
      palm = grown;
  }
  // A circle much larger than a palm: the band reached something just behind the hand (a hand
  // against the chest, the torso 5-8 cm behind). A flat palm and its fingers lie within a few cm.
  // Halved again (1.75 cm) where the torso is nearer still.
  const double z_near = model.metres(near_raw);
  for (double band = params.narrow_band_m; palm.radius_m > params.narrow_band_above_m && band >= 0.015; band /= 2) {
    Palm narrow;
    if (!measure_in_band(raw, cells, near_raw, raw_limit(z_near + band, true), seed_cell, narrow, 0, two_sided, candidate)) break;
    palm = narrow;
  }
  return true;
}

bool HandFinder::Impl::measure_in_band(std::span<const std::uint16_t> raw, const cv::Rect& cells, std::uint16_t near_raw,
                                       std::uint16_t far_raw, cv::Point seed_cell, Palm& palm, int grow, bool two_sided,
                                       Candidate candidate) {
  const bool bulge_wanted = candidate != Candidate::kFollowed;  // only a new track's tests ask is_dome
  // Near the body part of the palm may be less than foreground_m in front of what was there
  // before, so at full resolution the depth band and connectivity bound the hand, in a ROI
  // grown by a palm diameter.
  const auto& k = model.intrinsics();
  const int pad = static_cast<int>(std::ceil(2 * params.palm_radius_m * k.fx / std::max(0.3f, model.metres(near_raw)))) + 4;
  const int px0 = std::max(0, cells.x * kStep - pad * ((grow & kLeft) ? 2 : 1));
  const int py0 = std::max(0, cells.y * kStep - pad * ((grow & kTop) ? 2 : 1));
  const int px1 = std::min(kDepthWidth, (cells.x + cells.width) * kStep + pad * ((grow & kRight) ? 2 : 1));
  const int py1 = std::min(kDepthHeight, (cells.y + cells.height) * kStep + pad * ((grow & kBottom) ? 2 : 1));
  int rx0 = px0, ry0 = py0, rx1 = px1, ry1 = py1;  // the ROI; shrunk to the hand below

  // Full-resolution hand mask in the ROI, with a zero border so the image edge bounds the palm.
  // Views of full-frame buffers made once: a ROI of a new size allocates nothing.
  const cv::Rect roi_rect(0, 0, px1 - px0 + 2, py1 - py0 + 2);
  roi_mask = roi_mask_buffer(roi_rect);
  // The border rows and columns zero, every other pixel written: branch-free, so it vectorises (no
  // reading, 2047, is beyond any far_raw).
  roi_mask.row(0).setTo(0);
  roi_mask.row(roi_mask.rows - 1).setTo(0);
  const std::uint16_t slack_raw = two_sided ? end_band_near(near_raw) : near_raw > 20 ? static_cast<std::uint16_t>(near_raw - 20) : 0;
  const std::uint16_t band_far = std::min(far_raw, kMaxValidRaw);
  for (int y = ry0; y < ry1; ++y) {
    const std::uint16_t* row = raw.data() + static_cast<std::size_t>(y) * kDepthWidth + rx0;
    auto* m = roi_mask.ptr<std::uint8_t>(y - ry0 + 1);
    m[0] = 0;
    m[rx1 - rx0 + 1] = 0;
    ++m;
    for (int i = 0; i < rx1 - rx0; ++i) m[i] = (row[i] <= band_far && row[i] >= slack_raw) ? 255 : 0;
  }
  // The hand: the band's region connected to the arm's nearest reading.
  const cv::Point seed = seed_cell * kStep + cv::Point(kStep / 2 - rx0 + 1, kStep / 2 - ry0 + 1);
  if (roi_mask.at<std::uint8_t>(seed) != 255) return false;
  cv::Rect filled;
  cv::floodFill(roi_mask, seed, cv::Scalar(128), &filled);
  // Where the band's region reaches the ROI's edge inside the image (measure grows the ROI there).
  touched = (filled.x == 1 && px0 > 0 ? kLeft : 0) | (filled.y == 1 && py0 > 0 ? kTop : 0) |
            (filled.x + filled.width == roi_rect.width - 1 && px1 < kDepthWidth ? kRight : 0) |
            (filled.y + filled.height == roi_rect.height - 1 && py1 < kDepthHeight ? kBottom : 0);
  // From here on, the ROI is the hand's bounding box with a zero border (the filled region never
  // touches the ROI's border): the hole filling and the distance transform, ~10% of tachi-sensor's
  // time, then cover the hand rather than the padded ROI. A turned palm goes back to the whole ROI.
  const cv::Rect hand_rect(filled.x - 1, filled.y - 1, filled.width + 2, filled.height + 2);
  roi_mask = roi_mask(hand_rect);
  cv::compare(roi_mask, 128, roi_mask, cv::CMP_EQ);
  rx0 = px0 - 1 + hand_rect.x + 1;
  ry0 = py0 - 1 + hand_rect.y + 1;
  rx1 = rx0 + filled.width;
  ry1 = ry0 + filled.height;
  roi_closed = roi_closed_buffer(cv::Rect(0, 0, hand_rect.width, hand_rect.height));
  roi_dist = roi_dist_buffer(cv::Rect(0, 0, hand_rect.width, hand_rect.height));
  // Holes in the hand (dropouts with hand all around) count as hand; fingers stay apart and do not
  // widen the palm.
  fill_holes(roi_mask, roi_closed);
  cv::distanceTransform(roi_closed, roi_dist, cv::DIST_L2, cv::DIST_MASK_5);
  // The palm: the region's widest place; for a followed hand, the widest place near the seed
  // (params.palm_from_nearest_m) unless that holds no palm-sized circle and the region's widest
  // place is near where the palm was (a hand that left the image across its side leaves its upper
  // arm, palm-sized, 20 cm from it: seed 126 followed it for 28 frames when taken anywhere).
  double max_dist = 0;
  cv::Point max_at;
  const float z_near = model.metres(near_raw);
  distance_peak(roi_dist, max_dist, max_at);
  if (params.palm_from_nearest_m > 0 && candidate != Candidate::kNewTrack) {
    const int half = static_cast<int>(std::ceil(params.palm_from_nearest_m * k.fx / std::max(0.3f, z_near)));
    const cv::Point at_seed = seed - hand_rect.tl();
    const cv::Rect near_seed =
        cv::Rect(at_seed.x - half, at_seed.y - half, 2 * half + 1, 2 * half + 1) & cv::Rect(0, 0, roi_dist.cols, roi_dist.rows);
    // A circle wider than a palm's (the body behind a hand held against it) is left to measure's
    // narrower bands, which then look near the seed.
    if (!near_seed.contains(max_at) && max_dist * z_near / k.fx <= params.narrow_band_above_m) {
      double near_dist = 0;
      cv::Point near_at;
      distance_peak(roi_dist(near_seed), near_dist, near_at);
      const cv::Point2d was = cv::Point2d(previous_cell * kStep) + cv::Point2d(kStep / 2.0, kStep / 2.0);
      const cv::Point2d peak(rx0 - 1 + max_at.x, ry0 - 1 + max_at.y);
      const bool near_before = std::max(std::abs(peak.x - was.x), std::abs(peak.y - was.y)) <= half;
      if (near_dist * z_near / k.fx >= params.min_palm_radius_m || max_dist * z_near / k.fx < params.min_palm_radius_m ||
          !near_before || candidate == Candidate::kNewTrackNearSeed) {
        max_dist = near_dist;
        max_at = near_at + near_seed.tl();
      }
    }
  }
  if (max_dist < 2.0) return false;
  if (candidate == Candidate::kNewTrackNearSeed) ridge_mask = ridge_mask_buffer(cv::Rect(0, 0, roi_dist.cols, roi_dist.rows));
  const double ridge_px =
      ridge_length(roi_dist, max_dist, max_at, candidate == Candidate::kNewTrackNearSeed ? &ridge_mask : nullptr);
  cv::Point2d centre = plateau_centre(roi_dist, max_dist, max_at);
  // A palm turned away from the sensor is foreshortened across the turn, and its far side falls
  // out of the depth band of the nearest reading (the thumb): its inscribed circle shrinks toward
  // a forearm's. Where the circle is too small, the palm is measured in its own plane instead.
  double circle_px = max_dist;  // radius in the image of the region whose readings give the depth
  const auto turned_palm = [&] {
    Plane plane;  // of the band's region, a first guess at the palm's
    if (!fit_plane(raw, Roi{rx0, ry0, rx1, ry1}, plane)) return false;
    roi_mask = roi_mask_buffer(roi_rect);
    const bool measured = measure_turned_palm(raw, Roi{px0, py0, px1, py1}, max_at + hand_rect.tl(), plane, palm);
    if (measured) {
      rx0 = px0, ry0 = py0, rx1 = px1, ry1 = py1;
    } else {
      // Its masks may have replaced the band's region; no matter: a circle this small is no palm.
      roi_mask = roi_mask_buffer(roi_rect)(hand_rect);
    }
    return measured;
  };
  if (max_dist * z_near / k.fx < params.min_palm_radius_m && turned_palm()) {
    circle_px = palm.radius_m * k.fx / palm.z;
    palm.ridge_m = 0;  // measured in its own plane: the flattest palm-sized place, not a tube
    palm.in_own_plane = true;
  } else {
    const double u = rx0 - 1 + centre.x, v = ry0 - 1 + centre.y;
    // Palm depth: median reading inside the palm circle.
    palm_raw.clear();
    palm_pixels.clear();
    const double r2 = max_dist * max_dist;
    int circle_pixels = 0;
    for (int y = std::max(ry0, static_cast<int>(v - max_dist)); y <= std::min(ry1 - 1, static_cast<int>(v + max_dist)); ++y) {
      const std::uint16_t* row = raw.data() + static_cast<std::size_t>(y) * kDepthWidth;
      const auto* m = roi_mask.ptr<std::uint8_t>(y - ry0 + 1) + 1;
      for (int x = std::max(rx0, static_cast<int>(u - max_dist)); x <= std::min(rx1 - 1, static_cast<int>(u + max_dist)); ++x) {
        if ((x - u) * (x - u) + (y - v) * (y - v) > r2) continue;
        ++circle_pixels;
        if (m[x - rx0]) {
          palm_raw.push_back(row[x]);
          if (bulge_wanted) palm_pixels.emplace_back(x, y);  // for measure_bulge only
        }
      }
    }
    if (palm_raw.size() < 8) return false;
    const auto mid = palm_raw.begin() + static_cast<std::ptrdiff_t>(palm_raw.size() / 2);
    std::nth_element(palm_raw.begin(), mid, palm_raw.end());
    palm.z = model.metres(*mid);
    if (palm.z <= 0) return false;
    palm.u = u;
    palm.v = v;
    palm.radius_m = max_dist * palm.z / k.fx;
    palm.ridge_m = ridge_px * palm.z / k.fx;
    palm.valid_fraction = static_cast<double>(palm_raw.size()) / std::max(1, circle_pixels);
    if (bulge_wanted)
      measure_bulge(raw, palm);
    else
      palm.bulge_significance = palm.bulge_min_per_m = palm.bulge_view_cos = 0;
  }
  const double u = palm.u, v = palm.v;

  // Cut by the border: what is left of a palm half out of view (fingers, the upper palm) still
  // holds a palm-sized circle, centred up to 5 cm inward of the real one. Such a hand crosses the
  // border near the circle over most of a palm's width (a forearm crossing below a whole palm is
  // narrower) and its circle is smaller than a whole palm's.
  const double reach = circle_px + 2 * params.palm_radius_m * k.fx / palm.z;
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

/// The centre of the palm's face, for a palm measured by its silhouette's inscribed circle (`at`,
/// the circle's centre at the median depth of its readings). A hand is a slab ~3 cm thick: turned
/// by an angle a about an axis across the view, its silhouette gains the hand's side (t sin a wide)
/// on one edge, so the silhouette's widest place lies ~(t / 2) sin a from the face's centre toward
/// that side (measured on seeds 1-300: typically 5-10 mm at 30-60 degrees; 64 of the 66 clips turned
/// 15 degrees or more leaned along the turn).
/// The face is found as what a hand's side is not: the readings near the palm's plane. That plane
/// is fitted to the circle's readings (total least squares, then refitted to those within
/// the face band); the window's readings within the face band of it, connected to the circle, holes
/// filled, give the face's inscribed circle, whose centre is taken onto the plane. Blended in
/// between kFaceFromDeg and kFaceFullDeg of turn, so that the reported point moves continuously with
/// the hand's turn; a palm facing the sensor keeps `at`.
Eigen::Vector3d HandFinder::Impl::palm_face_centre(std::span<const std::uint16_t> raw, const Palm& palm,
                                                   const Eigen::Vector3d& at) {
  constexpr double kFaceBandM = 0.010;    // the face (palm, fingers' fronts, thumb) within this of its plane;
                                          // the hand's side curves away behind it by up to its thickness
  constexpr double kFaceBandSteps = 1.5;  // ... and within this many of Kinect's depth steps (13 mm at 2.15 m:
                                          // a 1 cm band there frayed the face, and its circle wandered 1-3 cm)
  constexpr double kFaceFromDeg = 10.0;   // turned less: the side is under ~2 mm wide, `at` kept
  constexpr double kFaceFullDeg = 20.0;   // turned more: the face's centre taken whole
  constexpr double kMaxFaceShiftM = 0.02; // half a hand's thickness: the side moves the widest place no more
  const auto& k = model.intrinsics();
  const double r_px = palm.radius_m * k.fx / palm.z;
  if (!(r_px >= 2.0)) return at;
  const double depth_step = 0.001 / std::abs(model.raw_at(palm.z + 0.001) - model.raw_at(palm.z));
  const double band = std::max(kFaceBandM, kFaceBandSteps * depth_step);
  // The plane of the readings within `radius` px of (cu, cv), within `band` of `near` when
  // given. The circle lies inside the hand's region; a hole's reading from behind the hand is
  // dropped by the depth gate and the refit. Every other row and column: a palm's circle holds
  // ~150-1,700 of them, plenty for three unknowns, at a quarter of the cost.
  const auto circle_plane = [&](double cu, double cv, double radius, const Plane* near, Plane& plane) {
    const int x0 = std::max(0, static_cast<int>(std::floor(cu - radius))), x1 = std::min(kDepthWidth - 1, static_cast<int>(std::ceil(cu + radius)));
    const int y0 = std::max(0, static_cast<int>(std::floor(cv - radius))), y1 = std::min(kDepthHeight - 1, static_cast<int>(std::ceil(cv + radius)));
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    const double offset = near ? near->centroid.dot(near->normal) : 0.0;
    for (int y = y0 + (y0 & 1); y <= y1; y += 2) {
      const std::uint16_t* row = raw.data() + static_cast<std::size_t>(y) * kDepthWidth;
      for (int x = x0 + (x0 & 1); x <= x1; x += 2) {
        if ((x - cu) * (x - cu) + (y - cv) * (y - cv) > radius * radius || row[x] >= kNoReading) continue;
        const double z = model.metres(row[x]);
        if (std::abs(z - palm.z) > palm.radius_m + 0.02) continue;
        const Eigen::Vector3d q = model.back_project(x, y, z);
        if (near && std::abs(q.dot(near->normal) - offset) > band) continue;
        outer += q * q.transpose();
        sum += q;
        ++count;
      }
    }
    return plane_through(outer, sum, count, plane);
  };
  Plane rough, plane;
  if (!circle_plane(palm.u, palm.v, r_px, nullptr, rough) || !circle_plane(palm.u, palm.v, r_px, &rough, plane)) return at;
  const double view_cos = std::clamp(-plane.normal.dot(plane.centroid.normalized()), -1.0, 1.0);
  const double turn_deg = std::acos(view_cos) * 180.0 / std::numbers::pi;
  const double f = std::clamp((turn_deg - kFaceFromDeg) / (kFaceFullDeg - kFaceFromDeg), 0.0, 1.0);
  const double weight = f * f * (3 - 2 * f);
  if (weight <= 0) return at;
  // The face's readings in a window 1.5 palm radii around the circle, with a zero border: the face's
  // circle lies within a side's width (clamped below to half a radius) of the silhouette's.
  const int half = static_cast<int>(std::ceil(1.5 * r_px)) + 2;
  const int wx0 = std::max(0, static_cast<int>(palm.u) - half), wx1 = std::min(kDepthWidth, static_cast<int>(palm.u) + half + 1);
  const int wy0 = std::max(0, static_cast<int>(palm.v) - half), wy1 = std::min(kDepthHeight, static_cast<int>(palm.v) + half + 1);
  const int w = wx1 - wx0 + 2, h = wy1 - wy0 + 2;
  // The frame-sized buffers' views, free once the frame's palm is chosen.
  roi_mask = roi_mask_buffer(cv::Rect(0, 0, w, h));
  roi_dist = roi_dist_buffer(cv::Rect(0, 0, w, h));
  plane_band_mask(raw, Roi{wx0, wy0, wx1, wy1}, plane, band);
  cv::Mat& mask = roi_mask;
  // Connected to the circle's centre (or the face reading nearest it within the circle).
  cv::Point seed(static_cast<int>(std::lround(palm.u)) - wx0 + 1, static_cast<int>(std::lround(palm.v)) - wy0 + 1);
  if (mask.at<std::uint8_t>(seed) != 255) {
    double best = r_px * r_px / 4;
    bool found = false;
    const int reach = static_cast<int>(r_px / 2);
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const cv::Point q = seed + cv::Point(dx, dy);
        if (q.x < 1 || q.y < 1 || q.x >= w - 1 || q.y >= h - 1 || mask.at<std::uint8_t>(q) != 255) continue;
        if (const double d2 = dx * dx + dy * dy; d2 < best) best = d2, seed = q, found = true;
      }
    if (!found) return at;
  }
  cv::floodFill(mask, seed, cv::Scalar(128));
  cv::compare(mask, 128, mask, cv::CMP_EQ);
  fill_holes(mask, mask);  // dropouts, a finger's gap closed all round
  double peak = 0;
  cv::Point peak_at;
  cv::Point2d c;
  if (!largest_inscribed_circle(mask, roi_dist, peak, peak_at, c)) return at;
  const double u = wx0 - 1 + c.x, v = wy0 - 1 + c.y;
  // The face's circle is the silhouette's less the hand's side: it lies within a radius of it. Farther,
  // it is some other flat place (the fingers' block): `at` kept.
  if ((u - palm.u) * (u - palm.u) + (v - palm.v) * (v - palm.v) > r_px * r_px) return at;
  // The plane again, of the face's circle alone (the silhouette's held some of the hand's side).
  Plane face_plane;
  if (circle_plane(u, v, peak, &plane, face_plane)) plane = face_plane;
  const double face_offset = plane.centroid.dot(plane.normal);
  const Eigen::Vector3d ray = model.back_project(u, v, 1.0);
  const double ray_along_normal = ray.dot(plane.normal);
  if (std::abs(ray_along_normal) < 1e-6) return at;
  const Eigen::Vector3d face = ray * (face_offset / ray_along_normal);
  if (!face.allFinite() || face.z() <= 0) return at;
  // Farther than a side can move it, the face's circle is partly some other flat place: moved only
  // as far as a side could (clamped, not refused, so the point moves continuously).
  Eigen::Vector3d shift = face - at;
  if (const double length = shift.norm(); length > kMaxFaceShiftM) shift *= kMaxFaceShiftM / length;
  return at + weight * shift;
}

/// How much the palm circle's readings (palm_pixels) bulge toward the sensor. A sphere's cap of
/// radius R lies z = z0 + r^2 / (2 R) (its sagitta, to second order), a flat palm at any tilt on a
/// plane, a cupped one bulges away. Fitted by least squares as a quadric in inverse depth,
/// 1 / z = a + b x + c y + d x^2 + e x y + f y^2 (x, y in metres about the circle's centre at its
/// depth), because a plane is linear in 1 / z over the image (n . (x, y, f) z = d), not in z: a
/// turned palm would bulge otherwise. To second order z ~ z0 - z0^2 (1 / z - 1 / z0), so the
/// curvatures toward the sensor are -z0^2 times the eigenvalues of [[d, e/2], [e/2, f]].
/// bulge_significance: the mean curvature (d + f) over its standard error (from the residuals,
/// Gauss-Markov), so that Kinect's disparity steps (~9 mm at 1.7 m) on a small circle do not count;
/// bulge_min_per_m: the curvature along the flattest direction (a turned palm's rounded rim curves
/// along one direction only, a head or an elbow along all).
void HandFinder::Impl::measure_bulge(std::span<const std::uint16_t> raw, Palm& palm) const {
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  palm.bulge_significance = palm.bulge_min_per_m = palm.bulge_view_cos = 0;
  const double metres_per_px = palm.z / model.intrinsics().fx, inverse_z0 = 1.0 / palm.z;
  // One pass: the normal equations' lower triangle, and the sum of squared targets for the residual.
  Matrix6d normal = Matrix6d::Zero();
  Vector6d rhs = Vector6d::Zero();
  double target_squares = 0;
  int count = 0;
  for (const cv::Point& p : palm_pixels) {
    const double z = model.metres(raw[static_cast<std::size_t>(p.y) * kDepthWidth + p.x]);
    if (z <= 0) continue;
    const double x = (p.x - palm.u) * metres_per_px, y = (p.y - palm.v) * metres_per_px, target = 1.0 / z - inverse_z0;
    Vector6d f;
    f << 1.0, x, y, x * x, x * y, y * y;
    normal.selfadjointView<Eigen::Lower>().rankUpdate(f);
    rhs += f * target;
    target_squares += target * target;
    ++count;
  }
  if (count < 12) return;
  const Matrix6d full = normal.selfadjointView<Eigen::Lower>();  // a copy: no aliasing with the lower triangle read
  const Eigen::FullPivLU<Matrix6d> lu(full);
  if (!lu.isInvertible()) return;
  const Vector6d q = lu.solve(rhs);
  // Residual sum of squares |t - F q|^2 = t.t - q.(F^T t), at the least-squares solution.
  const double residual_squares = std::max(0.0, target_squares - q.dot(rhs));
  const Matrix6d covariance = lu.inverse() * (residual_squares / (count - 6));
  const double mean_variance = covariance(3, 3) + covariance(5, 5) + 2 * covariance(3, 5);
  if (!(mean_variance > 0)) return;
  palm.bulge_significance = -(q(3) + q(5)) / std::sqrt(mean_variance);
  Eigen::Matrix2d hessian;
  hessian << q(3), q(4) / 2, q(4) / 2, q(5);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> curvatures(hessian, Eigen::EigenvaluesOnly);
  palm.bulge_min_per_m = -curvatures.eigenvalues()(1) * palm.z * palm.z;
  // The fitted surface's normal at the centre, (-dz/dx, -dz/dy, 1) with dz/dx = -z0^2 b, against the line of sight.
  const Eigen::Vector3d facing = Eigen::Vector3d(q(1), q(2), inverse_z0 * inverse_z0).normalized();
  palm.bulge_view_cos = facing.dot(model.back_project(palm.u, palm.v, palm.z).normalized());
}

/// The plane through the readings under roi_mask (ROI [rx0, rx1) x [ry0, ry1)) by total least
/// squares: through their centroid, normal to the direction of least variance (the smallest
/// eigenvector of their covariance; Pearson 1901). Unlike z = a X + b Y + c it does not favour
/// depth residuals, which matters for a palm turned toward edge-on. `spread_m`: the RMS distance
/// of the readings to the plane. False with too few readings.
bool HandFinder::Impl::fit_plane(std::span<const std::uint16_t> raw, const Roi& roi, Plane& plane, double* spread_m) {
  const int rx0 = roi.x0, ry0 = roi.y0, rx1 = roi.x1, ry1 = roi.y1;
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (int y = ry0; y < ry1; ++y) {
    const std::uint16_t* row = raw.data() + static_cast<std::size_t>(y) * kDepthWidth;
    const auto* m = roi_mask.ptr<std::uint8_t>(y - ry0 + 1) + 1;
    for (int x = rx0; x < rx1; ++x) {
      if (!m[x - rx0]) continue;
      const Eigen::Vector3d q = model.back_project(x, y, model.metres(row[x]));
      outer += q * q.transpose();
      sum += q;
      ++count;
    }
  }
  return plane_through(outer, sum, count, plane, spread_m);
}

/// The total-least-squares plane of `count` points given their sum of outer products and their sum.
bool HandFinder::Impl::plane_through(const Eigen::Matrix3d& outer, const Eigen::Vector3d& sum, int count, Plane& plane,
                                     double* spread_m) {
  if (count < 50) return false;
  plane.centroid = sum / count;
  const Eigen::Matrix3d covariance = outer / count - plane.centroid * plane.centroid.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  if (eigen.info() != Eigen::Success) return false;
  plane.normal = eigen.eigenvectors().col(0);  // eigenvalues in increasing order
  if (spread_m) *spread_m = std::sqrt(std::max(0.0, eigen.eigenvalues()(0)));  // RMS distance to the plane
  if (plane.normal.z() > 0) plane.normal = -plane.normal;  // toward the sensor
  return plane.normal.allFinite();
}

/// roi_mask = the ROI's readings within `band` metres of `plane` (perpendicular distance).
void HandFinder::Impl::plane_band_mask(std::span<const std::uint16_t> raw, const Roi& roi, const Plane& plane, double band) {
  const auto& k = model.intrinsics();
  const Eigen::Vector3d& nrm = plane.normal;
  const double offset = plane.centroid.dot(nrm);
  roi_mask.setTo(0);
  for (int y = roi.y0; y < roi.y1; ++y) {
    const std::uint16_t* row = raw.data() + static_cast<std::size_t>(y) * kDepthWidth;
    auto* m = roi_mask.ptr<std::uint8_t>(y - roi.y0 + 1) + 1;
    const double ray_y = (y - k.cy) / k.fy;
    for (int x = roi.x0; x < roi.x1; ++x) {
      const std::uint16_t d = row[x];
      if (d >= kNoReading) continue;
      const double z = model.metres(d);
      const double off = z * (nrm.x() * (x - k.cx) / k.fx + nrm.y() * ray_y + nrm.z()) - offset;  // in front of the plane
      if (std::abs(off) <= band) m[x - roi.x0] = 255;
    }
  }
}

/// Selects the hand's readings within `band` metres of `plane`, and within `radius` of `centre` in
/// the plane when given: their indices in `selected`, and with `mark`, roi_mask set at them (and
/// only there).
void HandFinder::Impl::select_near_plane(const Plane& plane, double band, const Eigen::Vector3d* centre, double radius,
                                         bool mark) {
  const double offset = plane.centroid.dot(plane.normal);
  const double radius2 = radius * radius;
  selected.clear();
  if (mark) roi_mask.setTo(0);
  for (std::size_t i = 0; i < hand_points.size(); ++i) {
    const Eigen::Vector3d& q = hand_points[i].point;
    const double off = q.dot(plane.normal) - offset;
    if (std::abs(off) > band) continue;
    if (centre && ((q - off * plane.normal) - *centre).squaredNorm() > radius2) continue;
    selected.push_back(i);
    if (mark) roi_mask.data[hand_points[i].mask_offset] = 255;
  }
}

/// fit_plane over the selected hand readings.
bool HandFinder::Impl::fit_selected(Plane& plane, double* spread_m) const {
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const std::size_t i : selected) {
    const Eigen::Vector3d& q = hand_points[i].point;
    outer += q * q.transpose();
    sum += q;
  }
  return plane_through(outer, sum, static_cast<int>(selected.size()), plane, spread_m);
}

/// The palm of a hand turned more than ~30 degrees from the sensor, measured in its own plane.
/// The plane is fitted to the hand mask (least squares), the mask rebuilt as the readings within
/// kPlaneBandM of that plane connected to `seed` (so the palm's far side counts, the forearm and
/// the back of the hand behind it do not), the plane refitted, twice; the filled mask is then
/// resampled on a metric grid in the plane (a homography, H = K [e1 e2 p0]: Hartley & Zisserman,
/// Multiple View Geometry, 2nd ed., sec. 8.1.1, the plane-to-image map), which undoes the
/// foreshortening for the viewing ray's real angle. The palm centre is the centre of the largest
/// inscribed circle there, as for a palm facing the sensor, mapped back onto the plane in 3D.
/// False for a palm facing the sensor (tilt under ~30 degrees), one seen edge-on (beyond ~76), or
/// a mask that does not hold.
bool HandFinder::Impl::measure_turned_palm(std::span<const std::uint16_t> raw, const Roi& roi, cv::Point seed, Plane plane,
                                           Palm& palm) {
  const int rx0 = roi.x0, ry0 = roi.y0, rx1 = roi.x1, ry1 = roi.y1;
  // Turned: the normal more than ~30 degrees off the optical axis, not beyond ~76 (edge-on). From
  // 26 degrees, a palm turned 30 is tracked 64/64 rather than 55/64, but the other bundled
  // scenarios then cost 8.4% more instructions (callgrind) for the same output: not taken.
  const auto turned = [](const Plane& p) { return -p.normal.z() <= 0.86 && -p.normal.z() >= 0.24; };
  if (!turned(plane)) return false;
  // Seen beyond the most oblique palm placed (the fit of the band's region is within a few degrees
  // of the palm's plane): spare the rest, which the arm's-end search would repeat.
  const double rough_view_cos = -plane.normal.dot(plane.centroid.normalized());
  if (rough_view_cos < kMinEdgeOnViewCos - kViewCosSlack) return false;
  roi_hand = roi_hand_buffer(cv::Rect(0, 0, roi_mask.cols, roi_mask.rows));
  // The hand: readings within kTurnedHandBandM of the plane, connected to the seed.
  plane_band_mask(raw, roi, plane, kTurnedHandBandM);
  if (roi_mask.at<std::uint8_t>(seed) != 255) return false;
  cv::floodFill(roi_mask, seed, cv::Scalar(128));
  cv::compare(roi_mask, 128, roi_hand, cv::CMP_EQ);
  // From here on only the hand's readings matter: kept as points, so that each refit or band
  // below costs a pass over ~3k points rather than over the ROI.
  hand_points.clear();
  for (int y = ry0; y < ry1; ++y) {
    const std::uint16_t* row = raw.data() + static_cast<std::size_t>(y) * kDepthWidth;
    const auto* m = roi_hand.ptr<std::uint8_t>(y - ry0 + 1) + 1;
    const int offset = (y - ry0 + 1) * static_cast<int>(roi_hand.step[0]) + 1 - rx0;
    for (int x = rx0; x < rx1; ++x)
      if (m[x - rx0]) hand_points.push_back({model.back_project(x, y, model.metres(row[x])), offset + x});
  }
  select_near_plane(plane, kTurnedHandBandM, nullptr, 0.0, false);
  if (!fit_selected(plane)) return false;
  // Far beyond the most oblique palm whose flattest place can be trusted: placed by the hand's
  // shape instead.
  if (rough_view_cos < kMinPalmViewCos - kViewCosSlack) return measure_edge_on_palm(roi, plane, palm);
  const Plane hand_plane = plane;
  // The palm is the flat part of the hand: where a palm-sized square in the plane is well covered
  // by readings within kPalmBandM of it. Turned fingers overlap into a block as wide as the palm,
  // so the best-covered places are compared by their flatness (the RMS distance of their readings
  // to their own plane): the palm's is ~1-2 mm less than that of the round sides of the fingers
  // or of the wrist. The plane is then refitted to that palm alone.
  PlaneGrid hand_grid;
  Eigen::Vector3d palm_at = Eigen::Vector3d::Zero();
  const int side = static_cast<int>(std::lround(kPalmSquareM / kCellM));
  for (int pass = 0; pass < kPalmPlanePasses; ++pass) {
    select_near_plane(plane, kPalmBandM, nullptr, 0.0, true);
    if (!make_plane_grid(roi, plane, hand_grid)) return false;
    cv::warpPerspective(roi_mask, rectified_mask, hand_grid.grid_to_roi, hand_grid.size, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                        cv::BORDER_CONSTANT, cv::Scalar(0));
    cv::boxFilter(rectified_mask, rectified_cover, CV_32F, cv::Size(side, side), cv::Point(-1, -1), true, cv::BORDER_CONSTANT);
    Plane chosen;
    double chosen_spread = std::numeric_limits<double>::infinity();
    for (int candidate = 0; candidate < kPalmCandidates; ++candidate) {
      double best = 0;
      cv::Point best_at;
      cv::minMaxLoc(rectified_cover, nullptr, &best, nullptr, &best_at);
      if (best < kMinPalmCover * 255) break;
      cv::rectangle(rectified_cover, cv::Rect(best_at.x - side / 2, best_at.y - side / 2, side, side), cv::Scalar(0), cv::FILLED);
      const Eigen::Vector3d at = hand_grid.point(best_at.x, best_at.y);
      select_near_plane(plane, kPalmRefitBandM, &at, kPalmRefitRadiusM, false);
      Plane local;
      double spread = 0;
      if (fit_selected(local, &spread) && turned(local) && spread < chosen_spread) {
        chosen = local;
        chosen_spread = spread;
        palm_at = at;
      }
    }
    if (!std::isfinite(chosen_spread)) return false;
    plane = chosen;
  }
  // Its centre: the largest inscribed circle of the flat readings (holes filled) in the plane.
  PlaneGrid palm_grid;
  select_near_plane(plane, kPalmBandM, &palm_at, kPalmSearchM, true);
  fill_holes(roi_mask, roi_closed);
  if (!make_plane_grid(roi, plane, palm_grid)) return false;
  cv::warpPerspective(roi_closed, rectified_closed, palm_grid.grid_to_roi, palm_grid.size, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  double peak = 0;
  cv::Point peak_at;
  cv::Point2d c;
  if (!largest_inscribed_circle(rectified_closed, rectified_dist, peak, peak_at, c)) return false;
  const Eigen::Vector3d centre = palm_grid.point(c.x, c.y);
  if (centre.z() <= 0) return false;
  // Seen more obliquely than this, the palm is a strip narrower than the overlapping fingers and
  // the flattest place may be among them (measured: 6-7 cm off at 63-77 degrees): placed by the
  // hand's shape instead.
  if (-plane.normal.dot(centre.normalized()) < kMinPalmViewCos) return measure_edge_on_palm(roi, hand_plane, palm);
  // No palm-sized circle there: the flattest place was not the palm (measured: the wrist, 7 cm
  // below it, at 56 degrees with the palm turned 50): placed by the hand's shape instead, where the
  // palm is seen obliquely enough for turned fingers to mislead (a hand seen more squarely with no
  // palm-sized circle is no palm: placed, with the turned measurement from 26 degrees, a
  // descending frontal hand in `jitter` came 16 cm off).
  if (peak * kCellM < params.min_palm_radius_m && -hand_plane.normal.dot(hand_plane.centroid.normalized()) < kMaxPlacedViewCos)
    return measure_edge_on_palm(roi, hand_plane, palm);
  // Share of the circle with readings (before the holes were filled).
  cv::warpPerspective(roi_mask, rectified_mask, palm_grid.grid_to_roi, palm_grid.size, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  int inside = 0, with_reading = 0;
  const int r = static_cast<int>(std::ceil(peak));
  for (int j = std::max(0, peak_at.y - r); j < std::min(palm_grid.size.height, peak_at.y + r + 1); ++j)
    for (int i = std::max(0, peak_at.x - r); i < std::min(palm_grid.size.width, peak_at.x + r + 1); ++i) {
      if ((i - c.x) * (i - c.x) + (j - c.y) * (j - c.y) > peak * peak) continue;
      ++inside;
      if (rectified_mask.at<std::uint8_t>(j, i)) ++with_reading;
    }
  const Eigen::Vector2d pixel = model.project(centre);
  palm.u = pixel.x();
  palm.v = pixel.y();
  palm.z = static_cast<float>(centre.z());
  palm.radius_m = peak * kCellM;
  palm.valid_fraction = static_cast<double>(with_reading) / std::max(1, inside);
  return true;
}

/// The palm of a hand seen nearly edge-on (63-80 degrees from the line of sight), placed by the
/// hand's shape rather than found as its flattest place: there the palm is a strip a few pixels wide
/// beside turned fingers that are as flat to a 5 mm band. A hand model reduced to the proportions it
/// needs (palm, fingers and forearm in their places; model-based trackers such as Oikonomidis,
/// Kyriazis & Argyros, BMVC 2011, fit a whole articulated hand instead):
///  - along the hand (the major axis of its readings in `hand_plane`, Pearson 1901), the fingers
///    point away from the forearm (arm_centre); the palm centre lies kTipToPalmCentreM back from
///    the hand's far end (the synthetic hand's middle fingertip is 12.6 cm from the palm centre, an
///    adult's 12-13.5 cm; the readings' 99.5th percentile lies 5-7 mm short of the tip, measured on
///    turned_palm);
///  - across it, the palm's far edge is a silhouette against what is behind (the near one runs into
///    the hand's side): the centre lies a palm's half width in from it, measured on the readings of
///    the palm's stretch of the hand that lie within kPalmBandM of their own plane, slice by slice
///    along the hand, so that a thumb standing out on the far side does not move it;
///  - onto the plane of the palm's readings around it.
/// False when the hand leaves the image, the forearm is not seen (which end is the wrist is then
/// unknown), too few readings, or most flat readings lie outside the palm placed.
bool HandFinder::Impl::measure_edge_on_palm(const Roi& roi, const Plane& hand_plane, Palm& palm) {
  if (-hand_plane.normal.dot(hand_plane.centroid.normalized()) < kMinEdgeOnViewCos) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& h : hand_points) mean += h.point;
  mean /= static_cast<double>(hand_points.size());
  // A hand that leaves the image is not placed: the fingertips or the palm may be what is cut,
  // and what runs on beside it at the border need not be the arm (measured: on turned_palm's two
  // frames where it does, the palm is cut by the bottom border and a torso reading joins the hand).
  const int left = std::clamp(params.invalid_left_columns, 0, kDepthWidth - 1);
  int at_border = 0;
  for (const auto& h : hand_points) {
    const Eigen::Vector2d px = model.project(h.point);
    at_border += px.x() < left + 1.5 || px.x() > kDepthWidth - 2.5 || px.y() < 1.5 || px.y() > kDepthHeight - 2.5;
  }
  if (at_border >= kMinBorderReadings) return false;
  // The hand's axes: eigenvectors of the covariance of its readings (largest: along the hand).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& h : hand_points) covariance += (h.point - mean) * (h.point - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  if (eigen.info() != Eigen::Success) return false;
  Eigen::Vector3d toward_tips = eigen.eigenvectors().col(2);
  // Trimmed: the readings farthest from that axis (the thumb, which at yaw 60 points toward the sensor and
  // pulled the axis 13-45 degrees into depth on turned_palm) are left out, and the axis refitted.
  toward_tips = trimmed_major_axis(toward_tips, mean);
  // Which end is the wrist: the forearm's side.
  Eigen::Vector3d forearm;
  if (!arm_centre(roi, mean, toward_tips, forearm)) return false;
  if (toward_tips.dot(forearm - mean) > 0) toward_tips = -toward_tips;
  palm.tips_down = toward_tips.y();  // the camera's y runs down
  // Along the hand: the far end, robustly, and the palm centre kTipToPalmCentreM back from it.
  along.clear();
  for (const auto& h : hand_points) along.push_back((h.point - mean).dot(toward_tips));
  const auto tip_at = along.begin() + static_cast<std::ptrdiff_t>(kTipQuantile * static_cast<double>(along.size() - 1));
  std::nth_element(along.begin(), tip_at, along.end());
  const double centre_along = *tip_at - kTipToPalmCentreM;
  // The palm's stretch of the hand, and its flat readings: their own plane, refitted twice.
  selected.clear();
  for (std::size_t i = 0; i < hand_points.size(); ++i)
    if (std::abs((hand_points[i].point - mean).dot(toward_tips) - centre_along) <= kPalmHalfLengthM) selected.push_back(i);
  Plane palm_plane;
  if (!fit_selected(palm_plane)) return false;
  palm_stretch.assign(selected.begin(), selected.end());
  for (int pass = 0; pass < kPalmPlanePasses; ++pass) {
    const double offset = palm_plane.centroid.dot(palm_plane.normal);
    selected.clear();
    for (const std::size_t i : palm_stretch)
      if (std::abs(hand_points[i].point.dot(palm_plane.normal) - offset) <= kPalmBandM) selected.push_back(i);
    if (!fit_selected(palm_plane)) return false;
  }
  // Across the hand, in the palm's plane: which side is far (the distance from the sensor grows
  // toward it: the palm is turned), and that side's edge (kEdgeQuantile, robust to stray readings).
  const Eigen::Vector3d across = palm_plane.normal.cross(toward_tips).normalized();
  double sum_b = 0, sum_d = 0, sum_bd = 0;  // the covariance of across and distance gives the far side
  along.clear();
  for (const std::size_t i : selected) {
    const double b = (hand_points[i].point - mean).dot(across), d = hand_points[i].point.norm();
    along.push_back(b);
    sum_b += b;
    sum_d += d;
    sum_bd += b * d;
  }
  const double far_side = sum_bd * static_cast<double>(selected.size()) > sum_b * sum_d ? 1.0 : -1.0;
  // The centre across, from the far edge slice by slice along the palm. The palm's outline is
  // rounded (taken as an ellipse, palm_radius_m across by kPalmHalfLengthM along, the hand model's
  // proportions), so each slice's edge, less the outline's half width at that slice, is an estimate
  // of the centre. The thumb stands out beside the palm over part of its length, on the far side or
  // the near one as the hand and its turn have it, and a slice short of readings falls inside the
  // edge: the median of the slices' estimates holds against both. Taken as the whole stretch's edge
  // less palm_radius_m, a thumb on the far side put the centre 3-4 cm too far (seeds 48, 84, 138:
  // the palm turned 52 degrees away from its thumb), and the rounded outline a few mm short.
  sliced.clear();
  for (std::size_t j = 0; j < selected.size(); ++j) {
    const double t = (hand_points[selected[j]].point - mean).dot(toward_tips) - centre_along + kPalmHalfLengthM;
    sliced.emplace_back(std::clamp(static_cast<int>(t / kEdgeSliceM), 0, kEdgeSlices - 1), far_side * along[j]);
  }
  std::sort(sliced.begin(), sliced.end());
  slice_centres.clear();
  for (std::size_t first = 0; first < sliced.size();) {
    std::size_t last = first;
    while (last < sliced.size() && sliced[last].first == sliced[first].first) ++last;
    if (last - first >= static_cast<std::size_t>(kMinSliceReadings)) {
      // Sorted by (slice, coordinate): the slice's kEdgeQuantile reading is at its rank.
      const double edge = sliced[first + static_cast<std::size_t>(kEdgeQuantile * static_cast<double>(last - first - 1))].second;
      const double at = (sliced[first].first + 0.5) * kEdgeSliceM - kPalmHalfLengthM;  // the slice's middle, from the centre
      const double half_width = params.palm_radius_m * std::sqrt(std::max(0.0, 1.0 - (at / kPalmHalfLengthM) * (at / kPalmHalfLengthM)));
      slice_centres.push_back(edge - half_width);
    }
    first = last;
  }
  double centre_far = 0;  // the centre's coordinate, positive toward the far side
  if (slice_centres.size() >= static_cast<std::size_t>(kMinEdgeSlices)) {
    const auto mid = slice_centres.begin() + static_cast<std::ptrdiff_t>(slice_centres.size() / 2);
    std::nth_element(slice_centres.begin(), mid, slice_centres.end());
    centre_far = *mid;
  } else {
    // Too few slices seen for a median: the stretch's edge as a whole.
    for (double& b : along) b *= far_side;  // now the far edge is the largest
    const auto edge_at = along.begin() + static_cast<std::ptrdiff_t>(kEdgeQuantile * static_cast<double>(along.size() - 1));
    std::nth_element(along.begin(), edge_at, along.end());
    centre_far = *edge_at - params.palm_radius_m;
  }
  const double centre_across = far_side * centre_far;
  // The palm is most of the hand's width: its centre lies within a half width of the hand's axis
  // (measured: -21 to +14 mm on seeds 1-300's placed frames, the thumb's side pulling the axis).
  // Farther, the "far edge" is something else in the palm's plane that the hand's region ran into,
  // nearly along the line of sight for a palm seen edge-on (seed 990: placed 25 cm behind the hand).
  if (std::abs(centre_across) > params.palm_radius_m) return false;
  // A palm placed where the palm is: most of the stretch's flat readings lie within its half width
  // (measured: 62-79% on turned_palm; 38-49% where it was placed 2-6 cm off, at yaw 70 with the
  // palm face partly hidden by the fingers).
  int within = 0;
  for (const std::size_t i : selected)
    within += std::abs((hand_points[i].point - mean).dot(across) - centre_across) <= params.palm_radius_m;
  if (within < kMinPalmShare * static_cast<double>(selected.size())) return false;
  Eigen::Vector3d centre = mean + centre_along * toward_tips + centre_across * across;
  centre -= (centre - palm_plane.centroid).dot(palm_plane.normal) * palm_plane.normal;
  if (centre.z() <= 0) return false;
  // How whole the palm's stretch looks: the share of its length (in kCellM steps) with flat readings.
  constexpr int kSteps = static_cast<int>(2 * kPalmHalfLengthM / kCellM) + 1;
  std::array<bool, kSteps> covered{};
  for (const std::size_t i : selected) {
    const double t = (hand_points[i].point - mean).dot(toward_tips) - centre_along + kPalmHalfLengthM;
    covered[static_cast<std::size_t>(std::clamp(static_cast<int>(t / kCellM), 0, kSteps - 1))] = true;
  }
  // Onto the plane of the palm's own readings around the centre placed (as measure_turned_palm's
  // candidates): the stretch's plane holds the thumb's and the hand's rounded sides as well.
  select_near_plane(palm_plane, kPalmRefitBandM, &centre, kPalmRefitRadiusM, false);
  if (Plane local; fit_selected(local)) centre -= (centre - local.centroid).dot(local.normal) * local.normal;
  const Eigen::Vector2d pixel = model.project(centre);
  palm.u = pixel.x();
  palm.v = pixel.y();
  palm.z = static_cast<float>(centre.z());
  palm.radius_m = params.palm_radius_m;  // placed by the model, not measured
  palm.valid_fraction = static_cast<double>(std::count(covered.begin(), covered.end(), true)) / kSteps;
  palm.placed_by_model = true;
  return true;
}

/// The major axis of the hand's readings with its outliers trimmed: start from `axis` through
/// `mean`, keep the kAxisKeptShare of the readings nearest that line, refit the principal axis
/// (Pearson 1901) to them, kAxisPasses times (iteratively trimmed PCA, in the spirit of
/// Rousseeuw's least trimmed squares, 1984). A thumb or a stray reading beside the hand then no
/// longer turns the axis toward it.
Eigen::Vector3d HandFinder::Impl::trimmed_major_axis(Eigen::Vector3d axis, Eigen::Vector3d mean) {
  for (int pass = 0; pass < kAxisPasses; ++pass) {
    off_axis.clear();
    for (const auto& h : hand_points) {
      const Eigen::Vector3d q = h.point - mean;
      off_axis.push_back((q - q.dot(axis) * axis).squaredNorm());
    }
    along.assign(off_axis.begin(), off_axis.end());
    const auto limit_at = along.begin() + static_cast<std::ptrdiff_t>(kAxisKeptShare * static_cast<double>(along.size() - 1));
    std::nth_element(along.begin(), limit_at, along.end());
    const double limit = *limit_at;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
    int kept = 0;
    for (std::size_t i = 0; i < hand_points.size(); ++i) {
      if (off_axis[i] > limit) continue;
      sum += hand_points[i].point;
      outer += hand_points[i].point * hand_points[i].point.transpose();
      ++kept;
    }
    if (kept < 3) break;
    mean = sum / kept;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(outer / kept - mean * mean.transpose());
    if (eigen.info() != Eigen::Success) break;
    axis = eigen.eigenvectors().col(2);
  }
  return axis;
}

/// The centre of the forearm's readings near the hand: the grid cells on the surface that runs on,
/// without a depth jump (kSurfaceStepM), from the hand's cells (those under roi_hand), within
/// kArmSearchM of `hand_centre`. Beyond the fingertips, the palm's far edge and the thumb lies what
/// is behind the hand, across a depth jump; beyond the wrist, the forearm. False with fewer than
/// kMinArmCells such cells.
bool HandFinder::Impl::arm_centre(const Roi& roi, const Eigen::Vector3d& hand_centre, const Eigen::Vector3d& hand_axis,
                                  Eigen::Vector3d& centre) {
  if (++visit_generation == 0) {
    std::fill(visited.begin(), visited.end(), 0u);
    visit_generation = 1;
  }
  queue.clear();
  const auto at = [](cv::Point p) { return static_cast<std::size_t>(p.y) * kGridW + static_cast<std::size_t>(p.x); };
  for (int gy = roi.y0 / kStep; gy <= (roi.y1 - 1 - kStep / 2) / kStep; ++gy)
    for (int gx = roi.x0 / kStep; gx <= (roi.x1 - 1 - kStep / 2) / kStep; ++gx) {
      const int x = gx * kStep + kStep / 2, y = gy * kStep + kStep / 2;
      if (x < roi.x0 || y < roi.y0 || !roi_hand.at<std::uint8_t>(y - roi.y0 + 1, x - roi.x0 + 1)) continue;
      visited[at({gx, gy})] = visit_generation;
      queue.push_back({gx, gy});
    }
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const cv::Point c = queue[head];
    const Eigen::Vector3d pc = cell_point(c);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const cv::Point n{c.x + dx, c.y + dy};
        if (n.x < 0 || n.y < 0 || n.x >= kGridW || n.y >= kGridH || visited[at(n)] == visit_generation) continue;
        if (grid.at<std::uint16_t>(n) >= kNoReading) continue;
        const Eigen::Vector3d pn = cell_point(n);
        if (pn.z() <= 0 || std::abs(pn.z() - pc.z()) > kSurfaceStepM || (pn - hand_centre).norm() > kArmSearchM) continue;
        visited[at(n)] = visit_generation;
        queue.push_back(n);
        // Counted where a forearm can be: near the hand's axis. A palm seen nearly edge-on is a surface
        // that runs back in steps under kSurfaceStepM, and leads on to whatever is behind it (measured:
        // the torso 15 cm behind a hand rising at the image's bottom edge, its forearm out of view).
        const Eigen::Vector3d off = pn - hand_centre;
        if ((off - off.dot(hand_axis) * hand_axis).norm() > kArmAxisM) continue;
        sum += pn;
        ++count;
      }
  }
  if (count < kMinArmCells) return false;
  centre = sum / count;
  return true;
}

/// A metric grid (kCellM) in `plane` over the in-plane extent of the selected readings, and the
/// homography from its cells to ROI pixels: H = K [e1 e2 p0] (Hartley & Zisserman, Multiple View
/// Geometry, 2nd ed., sec. 8.1.1, the map from a world plane to the image), shifted to the ROI.
bool HandFinder::Impl::make_plane_grid(const Roi& roi, const Plane& plane, PlaneGrid& out) const {
  constexpr double kHalfExtentM = 0.25;  // at most this around the plane's centroid
  const auto& k = model.intrinsics();
  // In-plane axes: e1 the camera's x projected on the plane, e2 = e1 x n (down in the image).
  const Eigen::Vector3d& n = plane.normal;
  out.e1 = (Eigen::Vector3d::UnitX() - n.x() * n).normalized();
  out.e2 = out.e1.cross(n);
  double s0 = 1e9, s1 = -1e9, t0 = 1e9, t1 = -1e9;
  for (const std::size_t i : selected) {
    const Eigen::Vector3d q = hand_points[i].point - plane.centroid;
    s0 = std::min(s0, q.dot(out.e1));
    s1 = std::max(s1, q.dot(out.e1));
    t0 = std::min(t0, q.dot(out.e2));
    t1 = std::max(t1, q.dot(out.e2));
  }
  s0 = std::max(s0 - 0.01, -kHalfExtentM);
  t0 = std::max(t0 - 0.01, -kHalfExtentM);
  s1 = std::min(s1 + 0.01, kHalfExtentM);
  t1 = std::min(t1 + 0.01, kHalfExtentM);
  if (s1 <= s0 || t1 <= t0) return false;
  out.size = cv::Size(static_cast<int>(std::ceil((s1 - s0) / kCellM)) + 1, static_cast<int>(std::ceil((t1 - t0) / kCellM)) + 1);
  out.origin = plane.centroid + s0 * out.e1 + t0 * out.e2;
  Eigen::Matrix3d to_point;
  to_point << kCellM * out.e1, kCellM * out.e2, out.origin;
  Eigen::Matrix3d to_roi;
  to_roi << k.fx, 0, k.cx - (roi.x0 - 1), 0, k.fy, k.cy - (roi.y0 - 1), 0, 0, 1;
  const Eigen::Matrix3d h = to_roi * to_point;
  out.grid_to_roi = cv::Matx33d(h(0, 0), h(0, 1), h(0, 2), h(1, 0), h(1, 1), h(1, 2), h(2, 0), h(2, 1), h(2, 2));
  return true;
}

/// Breadth-first walk over the surface at grid cell `seed` on the grid: 8-neighbours with a
/// reading, less than kSurfaceStepM (with `depth_steps`, reaches_back's walk: or
/// HandFinderParams::surface_step_quanta of the Kinect's depth steps, where coarser) nearer or
/// farther than the cell they are reached from (one surface: no depth jump). `on_cell(cell, z)`
/// sees each cell taken, in order, and may end the walk (returns true: the walk returns true);
/// `on_step(cell, z)` decides for each neighbour: kTake, kSkip, or kAbort (the walk returns false).
/// Shared by reaches_back, is_joint and arm_end.
template <class OnCell, class OnStep>
bool HandFinder::Impl::walk_surface(cv::Point seed, OnCell&& on_cell, OnStep&& on_step, bool depth_steps) {
  if (++visit_generation == 0) {
    std::fill(visited.begin(), visited.end(), 0u);
    visit_generation = 1;
  }
  queue.clear();
  visited[grid_index(seed)] = visit_generation;
  queue.push_back(seed);
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const cv::Point c = queue[head];
    const std::uint16_t raw_c = grid.at<std::uint16_t>(c);
    const float zc = model.metres(raw_c);
    if (on_cell(c, zc)) return true;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const cv::Point n{c.x + dx, c.y + dy};
        if (n.x < 0 || n.y < 0 || n.x >= kGridW || n.y >= kGridH || visited[grid_index(n)] == visit_generation) continue;
        const std::uint16_t d = grid.at<std::uint16_t>(n);
        if (d >= kNoReading) continue;
        const float zn = model.metres(d);
        // The farther reading's depth step: the coarser of the two.
        const float max_step = depth_steps ? surface_step[std::max(d, raw_c)] : static_cast<float>(kSurfaceStepM);
        if (zn <= 0 || std::abs(zn - zc) > max_step) continue;
        const Step step = on_step(n, zn);
        if (step == Step::kAbort) return false;
        if (step == Step::kSkip) continue;
        visited[grid_index(n)] = visit_generation;
        queue.push_back(n);
      }
  }
  return false;
}

/// Whether the surface at grid cell `seed` continues, without a depth jump (walk_surface), to at
/// least `arm_protrusion_m` behind `near_raw`, and nowhere nearer: an arm's end reaching out of a
/// body. A head, a torso, a box or a person farther back has no such depth; the upper arm of a
/// hand out of view has its forearm nearer.
bool HandFinder::Impl::reaches_back(cv::Point seed, std::uint16_t near_raw, bool past_nearer) {
  const float z0 = model.metres(near_raw);
  const double protrusion = z0 > params.max_acquire_depth_m ? params.far_arm_protrusion_m : params.arm_protrusion_m;
  const float goal = z0 + static_cast<float>(protrusion);
  const auto nearer_floor = z0 - static_cast<float>(kSurfaceStepM);
  return walk_surface(
      seed, [&](cv::Point, float zc) { return zc >= goal; },
      // The surface goes on toward the sensor: a limb's middle, not its end.
      // `past_nearer`: a hand at an arm's geodesic end, whose forearm runs on nearer (an elbow).
      [&](cv::Point, float zn) { return zn < nearer_floor && !past_nearer ? Step::kAbort : Step::kTake; }, true);
}

/// Whether the candidate at grid cell `seed` (nearest reading `near_raw`) is a limb's joint rather
/// than its end: on the surface connected to it without a depth jump (walk_surface, up to 10 cm
/// behind it), the cells 5-10 cm behind it form two separate groups (an elbow pointing at the
/// camera, with the upper arm and the forearm running back from it), where a hand has one (its
/// forearm; the torso behind a hand held against it is one ring).
/// `reached_from`: the candidate is an arm's geodesic end (arm_end), reached from the arm's nearest
/// reading there (an elbow pointing at the camera). The walk does not go back over that joint
/// (within kJointRadiusM of it): from a raised hand whose fingertips are as near as the elbow, it
/// ran down the forearm, over the elbow and onto the upper arm behind it, a second group that is the
/// elbow's, not the hand's (tuning seed 138: a hand raised in front of a second person, 14 frames
/// refused as a new track).
bool HandFinder::Impl::is_joint(cv::Point seed, std::uint16_t near_raw, const cv::Point* reached_from) {
  const float z0 = model.metres(near_raw);
  const float slab_near = z0 + 0.05f, slab_far = z0 + 0.10f;
  const double joint_cells = reached_from == nullptr ? -1.0
                                                     : kJointRadiusM * model.intrinsics().fx /
                                                           model.metres(grid.at<std::uint16_t>(*reached_from)) / kStep;
  const auto at_joint = [&](cv::Point n) {
    return reached_from != nullptr && std::hypot(n.x - reached_from->x, n.y - reached_from->y) <= joint_cells;
  };
  slab.clear();
  walk_surface(
      seed,
      [&](cv::Point c, float zc) {
        if (zc >= slab_near) slab.push_back(c);
        return false;
      },
      [&](cv::Point n, float zn) { return zn > slab_far || at_joint(n) ? Step::kSkip : Step::kTake; });
  // Groups of the slab's cells (8-connected among themselves), those of 3 cells or more.
  if (visit_generation > 0xfffffff0u) {  // two more generations are used here; none may wrap to 0
    std::fill(visited.begin(), visited.end(), 0u);
    visit_generation = 0;
  }
  const std::uint32_t in_slab = ++visit_generation, grouped = ++visit_generation;
  for (const auto& c : slab) visited[grid_index(c)] = in_slab;
  int groups = 0;
  for (const auto& start : slab) {
    if (visited[grid_index(start)] != in_slab) continue;
    queue.clear();
    queue.push_back(start);
    visited[grid_index(start)] = grouped;
    for (std::size_t head = 0; head < queue.size(); ++head)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const cv::Point n{queue[head].x + dx, queue[head].y + dy};
          if (n.x < 0 || n.y < 0 || n.x >= kGridW || n.y >= kGridH || visited[grid_index(n)] != in_slab) continue;
          visited[grid_index(n)] = grouped;
          queue.push_back(n);
        }
    if (queue.size() >= 3 && ++groups >= 2) return true;
  }
  return false;
}

cv::Point HandFinder::Impl::geodesic_walk(const std::vector<cv::Point>& sources, float limit_m) {
  if (++geodesic_generation == 0) {
    std::fill(geodesic_pass.begin(), geodesic_pass.end(), 0u);
    geodesic_generation = 1;
  }
  const auto& k = model.intrinsics();
  const auto farther = [](const std::pair<float, int>& a, const std::pair<float, int>& b) { return a.first > b.first; };
  geodesic_heap.clear();
  for (const auto& c : sources) {
    const auto i = grid_index(c);
    geodesic_pass[i] = geodesic_generation;
    geodesic[i] = 0.0f;
    geodesic_heap.emplace_back(0.0f, static_cast<int>(i));
  }
  std::make_heap(geodesic_heap.begin(), geodesic_heap.end(), farther);
  cv::Point tip = sources.empty() ? cv::Point(-1, -1) : sources.front();
  float tip_m = 0.0f;
  while (!geodesic_heap.empty()) {
    std::pop_heap(geodesic_heap.begin(), geodesic_heap.end(), farther);
    const auto [d, i] = geodesic_heap.back();
    geodesic_heap.pop_back();
    if (d > geodesic[static_cast<std::size_t>(i)]) continue;  // a stale entry
    const cv::Point c{i % kGridW, i / kGridW};
    if (d > tip_m) {
      tip_m = d;
      tip = c;
    }
    const float zc = model.metres(grid.at<std::uint16_t>(c));
    const float cell_m = static_cast<float>(kStep) * zc / static_cast<float>(k.fx);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const cv::Point n{c.x + dx, c.y + dy};
        if ((dx == 0 && dy == 0) || n.x < 0 || n.y < 0 || n.x >= kGridW || n.y >= kGridH) continue;
        const auto j = grid_index(n);
        if (in_arm_region[j] != arm_generation) continue;
        const float dz = model.metres(grid.at<std::uint16_t>(n)) - zc;
        const float lateral = cell_m * ((dx != 0 && dy != 0) ? 1.41421356f : 1.0f);
        const float dn = d + std::sqrt(lateral * lateral + dz * dz);
        if (dn > limit_m || (geodesic_pass[j] == geodesic_generation && geodesic[j] <= dn)) continue;
        geodesic_pass[j] = geodesic_generation;
        geodesic[j] = dn;
        geodesic_heap.emplace_back(dn, static_cast<int>(j));
        std::push_heap(geodesic_heap.begin(), geodesic_heap.end(), farther);
      }
  }
  return tip;
}

/// The arm's end as its geodesic extremity (the farthest point along the surface, not the nearest
/// to the camera). The surface at grid cell `seed` (the arm's nearest reading `near_raw`) is
/// walked without a depth jump (kSurfaceStepM between neighbours) up to arm_end_window_m behind
/// it; where it runs on farther back is the body's side (the upper arm toward the shoulder, the
/// forearm toward the elbow). The end is the point farthest along the surface from there; its
/// hand, the cells within kEndHandM of it along the surface. An elbow pointing at the camera is
/// the arm's nearest reading but a joint in the middle of this path; the hand is at its end.
/// False when the surface never runs on farther back (no body side: nothing to measure from).
bool HandFinder::Impl::arm_end(cv::Point seed, std::uint16_t near_raw, ArmEnd& end) {
  constexpr float kEndHandM = 0.18f;    // a hand's length: fingertip to wrist ~19 cm
  constexpr float kJointFromTipM = 0.25f;  // an elbow is a hand and a forearm (~45 cm) along the surface from the
                                          // fingertips (0.28-0.57 m seen where the hand is partly out of view); a
                                          // hand's own readings lie within ~21 cm (its heel, at 0.7 m)
  constexpr float kJointToHandM = 0.10f;  // an elbow's to its hand's nearest reading: a forearm's length, ~26 cm
  constexpr float kBendSlackM = 0.25f;  // a path across a bent elbow cuts its corner: up to ~2 arm diameters (21 cm seen)
  const float z0 = model.metres(near_raw);
  const float z_far = z0 + static_cast<float>(params.arm_end_window_m), z_near = z0 - static_cast<float>(kSurfaceStepM);
  // The surface (walk_surface), each cell with a neighbour on it farther back than z_far a root.
  arm_roots.clear();
  cv::Point current;
  walk_surface(
      seed,
      [&](cv::Point c, float) {
        current = c;
        return false;
      },
      [&](cv::Point, float zn) {
        if (zn > z_far) {
          if (arm_roots.empty() || arm_roots.back() != current) arm_roots.push_back(current);
          return Step::kSkip;
        }
        return zn < z_near ? Step::kSkip : Step::kTake;
      });
  arm_region.assign(queue.begin(), queue.end());
  if (++arm_generation == 0) {
    std::fill(in_arm_region.begin(), in_arm_region.end(), 0u);
    arm_generation = 1;
  }
  for (const auto& c : arm_region) in_arm_region[grid_index(c)] = arm_generation;
  if (arm_roots.empty()) return false;
  const cv::Point tip = geodesic_walk(arm_roots, std::numeric_limits<float>::max());
  const float reach_m = geodesic[grid_index(tip)], nearest_from_body_m = geodesic[grid_index(seed)];
  // The nearest reading a joint on the way from the body to the end (an elbow): its distances
  // from both add up to the whole length, give or take the bend's corner. The end of another
  // branch (the other arm hanging, reached across the torso of a user whose hand is near the
  // body) is no hand of this arm: the nearest reading is then an end of its own. So the walk from
  // the end need go no farther than this.
  const float on_path_m = reach_m + kBendSlackM - nearest_from_body_m;
  end = ArmEnd{};
  if (on_path_m < kJointFromTipM) return true;  // the nearest reading is at the end
  geodesic_walk({tip}, on_path_m);
  end.near_raw = kNoReading;
  int x0 = kGridW, y0 = kGridH, x1 = -1, y1 = -1;
  for (const auto& c : arm_region) {
    if (geodesic_pass[grid_index(c)] != geodesic_generation || geodesic[grid_index(c)] > kEndHandM) continue;
    const std::uint16_t d = grid.at<std::uint16_t>(c);
    if (d < end.near_raw) {
      end.near_raw = d;
      end.seed = c;
    }
    x0 = std::min(x0, c.x);
    x1 = std::max(x1, c.x);
    y0 = std::min(y0, c.y);
    y1 = std::max(y1, c.y);
  }
  end.cells = cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  // On that way, past a hand's length from the tip; and the end's hand (its nearest reading) well
  // away from the joint along the surface: where the arm's nearest reading is just past a hand's
  // length from the fingertips (a forearm pointing at the camera), the one-sided band from it
  // holds the hand already.
  const bool on_path = geodesic_pass[grid_index(seed)] == geodesic_generation;
  const float nearest_to_end_m = geodesic[grid_index(seed)];
  end.elsewhere = on_path && nearest_to_end_m >= kJointFromTipM && nearest_to_end_m - geodesic[grid_index(end.seed)] >= kJointToHandM;
  return true;
}

/// Whether the candidate's front surface (the grid cells within kFrontSurfaceM of its nearest
/// reading `near_raw`, connected to `seed`: a palm and its fingers, or the face of a box) reaches the
/// image's border: what the border cuts may be anything, and a hand is reported only whole in view.
bool HandFinder::Impl::front_touches_border(cv::Point seed, std::uint16_t near_raw, bool two_sided) {
  cv::inRange(grid, two_sided ? end_band_near(near_raw) : 0, front_limit[near_raw], front_cells);
  cv::Rect front;
  cv::floodFill(front_cells, seed, cv::Scalar(128), &front, cv::Scalar(0), cv::Scalar(0), 8);
  return touches_border(front);
}

bool HandFinder::Impl::front_crosses_border_beyond_hand(cv::Point seed, std::uint16_t near_raw, bool two_sided,
                                                        const Palm& palm) {
  if (!params.front_in_view_beyond_hand || !front_touches_border(seed, near_raw, two_sided)) return false;  // front_cells: 128
  const double reach_px = (kTipToPalmCentreM * model.intrinsics().fx / palm.z) + kStep;
  const auto beyond = [&](int gx, int gy) {
    if (front_cells.at<std::uint8_t>(gy, gx) != 128) return false;
    const double du = gx * kStep + kStep / 2 - palm.u, dv = gy * kStep + kStep / 2 - palm.v;
    return du * du + dv * dv > reach_px * reach_px;
  };
  const int left = left_border_cell();
  for (int gx = left; gx < kGridW; ++gx)
    if (beyond(gx, 0) || beyond(gx, kGridH - 1)) return true;
  for (int gy = 0; gy < kGridH; ++gy)
    if (beyond(left, gy) || beyond(kGridW - 1, gy)) return true;
  return false;
}

void HandFinder::Impl::band_cells_at(cv::Point seed, std::uint16_t near_raw, bool two_sided, cv::Rect& box) {
  cv::inRange(grid, two_sided ? end_band_near(near_raw) : 0, band_limit[near_raw], band_cells);
  cv::floodFill(band_cells, seed, cv::Scalar(128), &box, cv::Scalar(0), cv::Scalar(0), 8);
  cv::compare(band_cells, 128, band_region, cv::CMP_EQ);
}

/// Acquisition without a background: first where a hand held still was last frame, then the nearest
/// readings of the grid in turn (up to `candidates` regions, `start_candidates` before any hand was
/// seen), each taken with its depth band as a hand if it is palm-shaped, clear of the border, and an
/// arm's end (reaches_back). Finds a hand held still since the first frame, which
/// the background holds; a box, a head or a torso fail the shape or the depth test.
bool HandFinder::Impl::find_arm_end(std::span<const std::uint16_t> raw, Palm& palm, cv::Point& seed_out) {
  candidate_mask.create(kGridH, kGridW, CV_8U);
  candidate_mask.setTo(0);
  // refused_regions is all zero whenever refused_count is 0: cleared only after a frame that refused some.
  if (refused_regions.empty()) {
    refused_regions.create(kGridH, kGridW, CV_8U);
    refused_regions.setTo(0);
  } else if (refused_count > 0) {
    refused_regions.setTo(0);
  }
  refused_count = 0;
  // One candidate: the grid cells within the depth band connected to the seed (masked as tried).
  const auto try_seed = [&](cv::Point seed, std::uint16_t near_raw) {
    cv::Rect box;
    band_cells_at(seed, near_raw, false, box);
    // Which arm ends refused nearer its band holds (refuse_arm_of_refused_palm): a palm that passes
    // here is one of them found again from its arm, or lies on that arm. Their palms are measured
    // only if it passes (on_arm_of_refused_palm).
    bool holds_refused = false;
    if (refused_count > 0 && overlaps(band_region, refused_regions, box))
      for (std::size_t i = 0; i < refused_count; ++i)
        holds_refused |= refused[i].overlapped = overlaps(band_region, refused[i].region, box);
    const auto on_its_arm = [&] { return holds_refused && on_arm_of_refused_palm(raw, palm); };
    candidate_mask.setTo(255, band_region);
    // The nearest reading is a joint (an elbow pointing at the camera) and the arm's geodesic end
    // lies elsewhere: the candidate is the hand there, in a band around its own nearest reading
    // (past the elbow, which came nearer: reaches_back's test of an arm's end, taken from the hand).
    // The joint itself is no candidate.
    ArmEnd end;
    const bool to_end = params.arm_end_window_m >= 0 && is_joint(seed, near_raw) && arm_end(seed, near_raw, end) && end.elsewhere;
    if (to_end) {
      cv::Rect end_box;
      band_cells_at(end.seed, end.near_raw, true, end_box);
      candidate_mask.setTo(255, band_region);
      if (!arm_end_candidate(raw, end.seed, end.near_raw, end_box, true, palm) || on_its_arm()) return false;
      seed_out = end.seed;
      return true;
    }
    if (!arm_end_candidate(raw, seed, near_raw, box, false, palm) || on_its_arm()) return false;
    seed_out = seed;
    return true;
  };
  // A hand found here last frame and held still since (so part of the background): tried first where it
  // was, whatever lies nearer to the camera elsewhere. Found by the nearest-first search below only, it
  // was lost again behind the nearer objects of the room (a box, a table edge, a side wall running back
  // give one candidate per depth band each), until it moved (measured on seeds 1-100: the hand held up
  // from the first frame untracked for its first 30 frames in 5 clips).
  // Where it was is last_seen_cell, not previous_cell: an object moved in this frame (a foreground
  // component, tried first and refused) leaves its own palm's cell there (seed 207 of the tuning
  // range: a still hand lost for its last 90 frames when a table edge entered the image's corner).
  if (params.still_hand_m > 0 && frames_since_seen == 1 && last_seen_cell.x >= 0) {
    constexpr int kNear = 3;  // grid cells (12 px): a still hand's nearest reading stays within its palm
    std::uint16_t near_raw = kNoReading;
    cv::Point seed{-1, -1};
    for (int gy = std::max(0, last_seen_cell.y - kNear); gy <= std::min(kGridH - 1, last_seen_cell.y + kNear); ++gy) {
      const auto* g = grid.ptr<std::uint16_t>(gy);
      for (int gx = std::max(0, last_seen_cell.x - kNear); gx <= std::min(kGridW - 1, last_seen_cell.x + kNear); ++gx)
        if (g[gx] != 0 && g[gx] < near_raw) {  // 0: no reading (as untried_row_minimum skips it)
          near_raw = g[gx];
          seed = {gx, gy};
        }
    }
    // Held still, or moving on as it did: the palm within still_hand_m of where it was, or of where its
    // last step carries it. A hand that starts to move in front of its own background, or slowly just
    // in front of the body, stays less than foreground_m nearer than what is behind it for many frames
    // (seed 207: pushing toward the camera at 1-2 cm a frame from rest; seed 298: a followed hand 10 cm
    // before the chest); held to where it was, it was lost at its first step. Where it was stays a
    // test of its own: a still hand's measured centre jitters by a few mm, which its "step" carries on.
    if (seed.x >= 0 && try_seed(seed, near_raw)) {
      const Eigen::Vector3d at = model.back_project(palm.u, palm.v, palm.z);
      if ((at - last_seen).norm() <= params.still_hand_m ||
          (step_known && (at - last_seen - last_step).norm() <= params.still_hand_m)) {
        continued_in_background = true;
        return true;
      }
    }
    candidate_mask.setTo(0);  // not there: the search below as if it had not been tried
    if (refused_count > 0) refused_regions.setTo(0);
    refused_count = 0;
  }
  // Otherwise the nearest readings first; before any hand was seen (a hand held up and still from the
  // first frame is part of the background), more of them.
  const int candidates = frames_since_seen >= (1 << 20) ? params.start_candidates : params.candidates;
  for (int attempt = 0; attempt < candidates; ++attempt) {
    // The nearest reading not tried yet, the first in row order among equals: each row's minimum
    // by masks (it vectorises), then the place of the best one.
    std::uint16_t near_raw = kNoReading;
    int seed_row = -1;
    for (int gy = 0; gy < kGridH; ++gy) {
      const std::uint16_t row_min = untried_row_minimum(grid.ptr<std::uint16_t>(gy), candidate_mask.ptr<std::uint8_t>(gy));
      if (row_min < near_raw) {
        near_raw = row_min;
        seed_row = gy;
      }
    }
    if (seed_row < 0) return false;
    cv::Point seed{0, seed_row};
    for (const auto* g = grid.ptr<std::uint16_t>(seed_row); g[seed.x] != near_raw || candidate_mask.at<std::uint8_t>(seed); ++seed.x) {
    }
    if (try_seed(seed, near_raw)) return true;
  }
  return false;
}

/// find_arm_end's tests of one candidate (its nearest grid reading `near_raw` at `seed`, its band's
/// cells in band_region, their box `box`); true: `palm` is the hand, `arm` its cells.
bool HandFinder::Impl::arm_end_candidate(std::span<const std::uint16_t> raw, cv::Point seed, std::uint16_t near_raw,
                                         const cv::Rect& box, bool two_sided, Palm& palm) {
  const auto& k = model.intrinsics();
  // A hand with a stretch of forearm inside the band spans 5-35 cm; a box front or a torso more.
  const double z = model.metres(near_raw);
  const double w_m = box.width * kStep * z / k.fx, h_m = box.height * kStep * z / k.fy;
  if (std::max(w_m, h_m) < 0.05 || std::min(w_m, h_m) > 0.35) return false;
  if (z > params.max_track_depth_m) return false;  // nor here: beyond the room a user stands in
  // What the border cuts is not taken: the candidate's front surface (within kFrontSurfaceM of
  // its nearest reading: a palm and its fingers, or the face of a box) must be whole in view. A
  // hand held against the chest keeps the torso out of it (4-8 cm behind).
  // The grid test first: it is cheap, the full-resolution measure is not.
  if (front_touches_border(seed, near_raw, two_sided)) return false;
  if (!reaches_back(seed, near_raw, two_sided)) {
    // Whole in view but no arm's end (a hand held still before the chest, say): what lies behind it
    // on the same region may be its arm (refuse_arm_of_refused_palm). Kept for a later candidate.
    if (params.refuse_arm_of_refused_palm) {
      if (refused.size() == refused_count) refused.emplace_back();
      RefusedArmEnd& r = refused[refused_count++];
      r.box = box;
      r.near_raw = near_raw;
      r.seed = seed;
      r.two_sided = two_sided;
      band_region.copyTo(r.region);
      r.measured = r.is_palm = r.overlapped = false;
      refused_regions.setTo(255, band_region);
    }
    return false;
  }
  if (!measure(raw, box, near_raw, seed, palm, two_sided, Candidate::kNewTrack)) return false;
  // The hand at this nearest reading: its palm within max_new_palm_from_nearest_m of it.
  const Eigen::Vector3d nearest_m = cell_point(seed);
  const auto new_palm = [&](const Palm& p) {
    return new_track_palm(p, near_raw) &&
           (params.max_new_palm_from_nearest_m <= 0 ||
            (model.back_project(p.u, p.v, p.z) - nearest_m).norm() <= params.max_new_palm_from_nearest_m);
  };
  if (!new_palm(palm)) {
    if (!params.second_look_near_nearest || params.palm_from_nearest_m <= 0) return false;
    // The band's widest place was a limb (a tube: its ridge runs on), round, or more than a hand's length from the
    // nearest reading (an elbow below a raised hand, at its depth): a hand held up beside
    // the head with its forearm and upper arm at its depth has its widest place at the elbow, 15-25 cm
    // below the palm. The palm is then sought where a followed one is, near the nearest reading (the
    // fingertips); the same tests decide (seed 86 of the tuning range: its first 15 frames).
    // Only a palm elsewhere is a second look: the same place, its ridge counted the other way, would
    // overturn the first verdict on a hair (seed 66: a shoulder refused at 9.1 cm of ridge, taken at 8.6).
    Palm near_seed;
    if (!measure(raw, box, near_raw, seed, near_seed, two_sided, Candidate::kNewTrackNearSeed) ||
        std::hypot(near_seed.u - palm.u, near_seed.v - palm.v) * palm.z <= palm.radius_m * model.intrinsics().fx ||
        !new_palm(near_seed))
      return false;
    palm = near_seed;
  }
  band_region.copyTo(arm);
  cv::dilate(arm, arm, kernel3);
  return true;
}

bool HandFinder::Impl::on_arm_of_refused_palm(std::span<const std::uint16_t> raw, const Palm& palm) {
  // Every refused palm is measured now (each once a frame): the candidate is taken when it is
  // measured at any of them that passes a new track's tests, held or not.
  bool holds_palm = false;
  for (std::size_t i = 0; i < refused_count; ++i) {
    RefusedArmEnd& r = refused[i];
    if (!r.measured) {
      r.measured = true;
      r.palm = Palm{};  // a measure does not set every field
      r.is_palm = measure(raw, r.box, r.near_raw, r.seed, r.palm, r.two_sided, Candidate::kNewTrack) && new_track_palm(r.palm, r.near_raw);
    }
    holds_palm |= r.is_palm && r.overlapped;
  }
  if (!holds_palm) return false;
  const Eigen::Vector3d at = model.back_project(palm.u, palm.v, palm.z);
  for (std::size_t i = 0; i < refused_count; ++i) {
    const RefusedArmEnd& r = refused[i];
    if (r.is_palm && (model.back_project(r.palm.u, r.palm.v, r.palm.z) - at).norm() <= r.palm.radius_m) return false;
  }
  return true;
}

/// Continuity: a hand that has just left (across an edge, say) does not reappear far away at
/// once; what does is another part of the arm. A frame after a palm, it is measured from that palm
/// (a hand does not leap max_jump_m in a frame). Later, with jump_from_kept_course, from the last
/// palm that kept its course, and a glimpse since (a palm that never did: a one- or two-frame
/// track) only widens what is let through: it does not hold the hand away. A glimpse is the hand
/// seen once while it moves fast, then lost to other tests while it moves on (tuning seeds 4, 118),
/// or something else taken for a frame or two (seeds 14, 139, 196: 18-32 cm from the hand); measured
/// from it, the hand was refused until reacquire_frames had passed (12-15 frames each).
bool HandFinder::Impl::jumped(const Palm& palm) const {
  if (frames_since_seen == 0 || frames_since_seen > params.reacquire_frames) return false;
  const Eigen::Vector3d at = model.back_project(palm.u, palm.v, palm.z);
  const bool far_from_last = (at - last_seen).norm() > params.max_jump_m;
  // Across a gap of missed frames (course_gap_frames): where k of the last step carry the hand, within k
  // steps' slack, when the last palm reported kept its course (its step checked a frame before: a two-frame
  // track's step may be from the hand to an arm, tuning seeds 32 and 140). Not a frame on (k = 1): that is
  // off_course's, for a followed palm; the still hand's own test (still_hand_m) holds a hand within the
  // background, whose tremor departs from its step by more.
  if (params.course_gap_frames > 0 && params.max_off_course_m > 0 && step_known && frames_since_on_course == frames_since_seen &&
      frames_since_seen >= 2 && frames_since_seen <= params.course_gap_frames) {
    const double k = static_cast<double>(frames_since_seen);
    if ((at - (last_seen + k * last_step)).norm() > k * params.max_off_course_m) return true;
  }
  if (!params.jump_from_kept_course || frames_since_seen == 1 || frames_since_on_course == frames_since_seen) {
    return far_from_last;
  }
  return far_from_last && frames_since_on_course <= params.reacquire_frames && (at - last_on_course).norm() > params.max_jump_m;
}

/// A followed palm found in the last two frames is where its last step carries it, within
/// max_off_course_m: a hand's own motion departs from that by a·dt²/2 (about 1 cm a frame at 30 Hz
/// for the 50 m/s² of a fast reversal), its measured centre by a few mm more; a palm measured on
/// the forearm or the upper arm of the same component departs by 10-30 cm.
bool HandFinder::Impl::off_course(const Palm& palm) const {
  if (params.max_off_course_m <= 0 || !step_known || frames_since_seen != 1) return false;
  return (model.back_project(palm.u, palm.v, palm.z) - (last_seen + last_step)).norm() > params.max_off_course_m;
}

bool HandFinder::Impl::palm_accepted(const Palm& palm) const {
  const double expected_px = params.palm_radius_m * model.intrinsics().fx / palm.z + params.edge_margin_px;
  const bool inside = palm.u - expected_px >= params.invalid_left_columns && palm.u + expected_px <= kDepthWidth - 1 &&
                      palm.v - expected_px >= 0 && palm.v + expected_px <= kDepthHeight - 1;
  return inside && palm_sized(palm) && palm.valid_fraction >= 0.5 && !palm.cut_by_border &&
         !(palm.placed_by_model && palm.tips_down > params.max_palm_tips_down);  // a hand hanging at rest
}

/// Steps 2-4 for one foreground component: its hand (the part within the band of its nearest
/// reading, or at its geodesic end), measured; whether it is the hand (a followed one when
/// `continuing`, else a new track's tests). Sets the arm's cells (arm), previous_cell, tracking.
/// `take_over`: a new track that is to replace a followed one: it must be an arm's end
/// (reaches_back) at any depth, and it may appear anywhere (no max_jump_m).
bool HandFinder::Impl::follow_component(std::span<const std::uint16_t> raw, int component, bool continuing, bool take_over,
                                        Palm& palm) {
  std::uint16_t near_raw = nearest[static_cast<std::size_t>(component)];
  const cv::Point arm_nearest = nearest_at[static_cast<std::size_t>(component)];
  cv::Point seed = arm_nearest;
  const std::uint16_t far_raw = band_limit[near_raw];
  // The hand's cells: the component within the depth band; their bounding box is the ROI.
  int x0 = kGridW, y0 = kGridH, x1 = -1, y1 = -1;
  for (int gy = 0; gy < kGridH; ++gy) {
    const int* l = labels.ptr<int>(gy);
    const auto* g = grid.ptr<std::uint16_t>(gy);
    for (int gx = 0; gx < kGridW; ++gx)
      if (l[gx] == component && g[gx] <= far_raw) {
        x0 = std::min(x0, gx);
        x1 = std::max(x1, gx);
        y0 = std::min(y0, gy);
        y1 = std::max(y1, gy);
      }
  }
  cv::compare(labels, component, arm, cv::CMP_EQ);
  cv::dilate(arm, arm, kernel3);
  excluded = true;
  cv::Rect cells(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  // The arm's nearest reading lies on its way from the body to its geodesic end (an elbow pointing
  // at the camera): the hand is at the end, measured around its own nearest reading; the nearest
  // reading is not measured (where the end holds no palm, the hand has left the image, say). The
  // geodesic test alone decides, for a followed arm and a new track alike: is_joint flickers as an
  // elbow turns (seed 90: the elbow was followed while the hand rose out of the image). A new track
  // asked is_joint too, and was measured at the nearest reading when that was no joint: the hand at
  // the end was found later (seeds 8, 86, 168: 4-12 points of tracked frames) or the arm taken
  // (seed 146: 68 -> 2.9 mm RMS; 126: 40 -> 12 captured frames). Without that condition, seeds
  // 1-100: tracked 88.47 -> 88.69 %, phantom frames 80 -> 79, captured 74 -> 73; seeds 101-200:
  // 89.72 -> 89.98 %, 187 -> 159, 192 -> 161, clips <= 1 cm 87 -> 88.
  ArmEnd end;
  const bool at_end =
      params.arm_end_window_m >= 0 && arm_end(seed, near_raw, end) && end.elsewhere;
  if (at_end) {
    near_raw = end.near_raw;
    seed = end.seed;
    cells = end.cells;
  }
  const bool measured = measure(raw, cells, near_raw, seed, palm, at_end, continuing ? Candidate::kFollowed : Candidate::kNewTrack);
  if (measured) {
    previous_cell = {static_cast<int>(palm.u) / kStep, static_cast<int>(palm.v) / kStep};
    tracking = palm_sized(palm);  // keep following an arm whose palm is at the edge
    // A new track does not start on a person walking by behind the user, nor where its front surface runs
    // out of the image beyond a hand's reach of the palm (front_in_view_beyond_hand). Fingers cut by the
    // border are within that reach (seed 10, a user at 0.67 m); find_arm_end refuses any front surface
    // at the border, where there is no background to go by.
    // Cut by the border, measured against the hand's own palm (own_palm_shrink_m): a followed palm whose
    // circle is as large as the track's largest, within the tolerance, is whole, its fingers or wrist
    // across the border; what the border cuts off a palm takes its circle down more than that. A new
    // track has no palm of its own yet: the fixed size (whole_palm_radius_m) alone, so the end of an arm
    // the border cuts does not start one.
    if (continuing && palm.cut_by_border && params.own_palm_shrink_m > 0 &&
        palm.radius_m >= own_palm_radius_m - params.own_palm_shrink_m) {
      palm.cut_by_border = false;
    }
    const bool jump = !take_over && (jumped(palm) || (continuing && off_course(palm)));
    const auto palm_shaped = [&] { return new_track_shape(palm, params.max_foreground_new_palm_ridge_m); };
    // The second palm of a track begun a frame ago: no step to hold it to (max_unproven_step_m).
    const bool unproven = continuing && params.max_unproven_step_m > 0 && !step_known && frames_since_seen == 1 &&
                          (model.back_project(palm.u, palm.v, palm.z) - last_seen).norm() > params.max_unproven_step_m;
    const bool found =
        palm_accepted(palm) && !jump &&
        (continuing ? !unproven || palm_shaped()
                    : palm_shaped() && !set_in_static_surface(palm) &&
                          ((palm.z <= params.max_acquire_depth_m && !take_over) ||
                           (palm.z <= params.max_track_depth_m && reaches_back(seed, near_raw, at_end))) &&
                          !is_joint(seed, near_raw, at_end ? &arm_nearest : nullptr) && !nearest_at_border(arm_nearest) &&
                          !behind_band(palm, near_raw) &&
                          !front_crosses_border_beyond_hand(seed, near_raw, at_end, palm));
    // Refused as unproven, it is not followed on either: the next frame would take it as the same hand.
    if (jump || (!found && (!continuing || unproven))) tracking = false;
    if (!found && !continuing && came_to_rest(component)) excluded = false;
    return found;
  }
  tracking = false;
  if (!continuing && came_to_rest(component)) excluded = false;
  return false;
}

/// Whether at least rest_share of a component's grid cells have read steady for rest_frames frames:
/// a thing that came to rest, which the background may learn although it was measured.
bool HandFinder::Impl::came_to_rest(int component) const {
  if (params.rest_frames <= 0) return false;
  // The user's body and arm lie behind the hand, or an elbow's few cm before it: a thing nearer than
  // where the hand was last seen by rest_nearer_than_hand_m is not the arm that holds it, paused.
  // No hand seen yet: nothing tells the two apart, and nothing is learned.
  if (frames_since_seen >= (1 << 20) ||
      model.metres(nearest[static_cast<std::size_t>(component)]) + params.rest_nearer_than_hand_m > last_seen.z())
    return false;
  // Only the component's bounding box: the whole grid was scanned for each refused component (19,200
  // cells, where a refused thing holds a few hundred).
  const cv::Rect& b = component_box[static_cast<std::size_t>(component)];
  int cells = 0, steady = 0;
  for (int gy = b.y; gy < b.y + b.height; ++gy) {
    const int* l = labels.ptr<int>(gy);
    const std::size_t base = static_cast<std::size_t>(gy) * kGridW;
    for (int gx = b.x; gx < b.x + b.width; ++gx) {
      if (l[gx] != component) continue;
      ++cells;
      steady += run_length[base + gx] >= params.rest_frames ? 1 : 0;
    }
  }
  return cells > 0 && steady >= params.rest_share * cells;
}

HandObservation HandFinder::Impl::find(std::span<const std::uint16_t> raw) {
  HandObservation out;
  if (frames_since_seen < (1 << 20)) ++frames_since_seen;
  if (frames_since_on_course < (1 << 20)) ++frames_since_on_course;
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
  // Labels only: OpenCV's statistics cost 3x the labelling (65 against 22 us here); the one used,
  // the area, is counted below with the nearest reading.
  const int n = cv::connectedComponents(fg_open, labels, 8, CV_32S);

  // 2. Per component: nearest reading; the component under the previous hand, else the nearest.
  nearest.assign(static_cast<std::size_t>(n), kNoReading);
  nearest_at.assign(static_cast<std::size_t>(n), cv::Point());
  area.assign(static_cast<std::size_t>(n), 0);
  // Corners (x0, y0) and (x1, y1), inclusive, held in a Rect's fields until made one below.
  component_box.assign(static_cast<std::size_t>(n), cv::Rect(kGridW, kGridH, -1, -1));
  for (int gy = 0; gy < kGridH; ++gy) {
    const int* l = labels.ptr<int>(gy);
    const auto* g = grid.ptr<std::uint16_t>(gy);
    for (int gx = 0; gx < kGridW; ++gx) {
      if (l[gx] == 0) continue;
      const auto c = static_cast<std::size_t>(l[gx]);
      ++area[c];
      cv::Rect& b = component_box[c];
      b.x = std::min(b.x, gx);
      b.width = std::max(b.width, gx);
      b.y = std::min(b.y, gy);
      b.height = std::max(b.height, gy);
      if (g[gx] < nearest[c]) {
        nearest[c] = g[gx];
        nearest_at[c] = {gx, gy};
      }
    }
  }
  for (cv::Rect& b : component_box) {
    b.width = b.width - b.x + 1;
    b.height = b.height - b.y + 1;
  }
  int chosen = 0;
  const bool continuing = tracking;
  if (tracking) {
    // Continuity: the big-enough component nearest (on the grid) to the previous palm.
    double best = 12.0 * 12.0;
    for (int gy = std::max(0, previous_cell.y - 12); gy < std::min(kGridH, previous_cell.y + 13); ++gy) {
      const int* l = labels.ptr<int>(gy);
      for (int gx = std::max(0, previous_cell.x - 12); gx < std::min(kGridW, previous_cell.x + 13); ++gx) {
        if (l[gx] == 0 || area[static_cast<std::size_t>(l[gx])] < params.min_component_cells) continue;
        const double d2 = (gx - previous_cell.x) * (gx - previous_cell.x) + (gy - previous_cell.y) * (gy - previous_cell.y);
        if (d2 < best) {
          best = d2;
          chosen = l[gx];
        }
      }
    }
  }
  int reaching = 0;  // the big-enough component that reaches nearest
  std::uint16_t best = kNoReading;
  for (int c = 1; c < n; ++c)
    if (area[static_cast<std::size_t>(c)] >= params.min_component_cells && nearest[static_cast<std::size_t>(c)] < best) {
      best = nearest[static_cast<std::size_t>(c)];
      reaching = c;
    }
  if (chosen == 0) chosen = reaching;

  Palm palm;
  bool found = false;
  continued_in_background = false;
  bool followed = false;  // found as the hand followed last frame (not a new track)
  // A followed track that is no arm's end (a second person's head, taken while the user's hand was
  // down, seed 53) gives way to a component that reaches an arm's protrusion nearer than it, is an
  // arm's end and passes a new track's tests (the user's hand, raised): the followed one would
  // otherwise hold the track, and for reacquire_frames after it is lost, the jump test would
  // refuse the hand. (A user's own elbow, a few cm nearer than a far hand, is not nearer by that.)
  const auto nearer_by_protrusion = [&](int a, int b) {
    return model.metres(nearest[static_cast<std::size_t>(a)]) + params.arm_protrusion_m <= model.metres(nearest[static_cast<std::size_t>(b)]);
  };
  const bool take_over = params.take_over_by_arm_end && continuing && chosen != 0 && reaching != 0 && reaching != chosen &&
                         nearer_by_protrusion(reaching, chosen) &&
                         !reaches_back(nearest_at[static_cast<std::size_t>(chosen)], nearest[static_cast<std::size_t>(chosen)]) &&
                         follow_component(raw, reaching, false, true, palm);
  if (take_over) {
    found = true;
    tracking = true;
  } else if (chosen != 0) {
    found = follow_component(raw, chosen, continuing, false, palm);
    followed = found && continuing;
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
  // Kept its course: found as the same hand a third frame running, where off_course (or, within the
  // background, still_hand_m) held it to its step.
  if ((followed || continued_in_background) && step_known && frames_since_seen == 1) {
    last_on_course = p;
    frames_since_on_course = 0;
  }
  // A new track's step would be a jump between two things; a hand found where it was (or where its
  // step carried it) within the background is the same hand.
  step_known = (followed || continued_in_background) && frames_since_seen == 1;
  own_palm_radius_m = followed || continued_in_background ? std::max(own_palm_radius_m, palm.radius_m) : palm.radius_m;
  last_step = p - last_seen;
  last_seen = p;
  last_seen_cell = {static_cast<int>(palm.u) / kStep, static_cast<int>(palm.v) / kStep};
  frames_since_seen = 0;
  out.tracked = true;
  // Reported: the palm face's centre. The track above keeps the silhouette's circle, which every
  // test was tuned on; the two differ only for a palm turned from the sensor.
  const Eigen::Vector3d face =
      !params.report_palm_face || palm.in_own_plane || palm.placed_by_model ? p : palm_face_centre(raw, palm, p);
  out.position_m = face.cast<float>();
  out.u = static_cast<float>(palm.u);
  out.v = static_cast<float>(palm.v);
  if (face != p) {
    const Eigen::Vector2d face_px = model.project(face);
    out.u = static_cast<float>(face_px.x());
    out.v = static_cast<float>(face_px.y());
  }
  out.palm_radius_m = static_cast<float>(palm.radius_m);
  const double size_score = std::exp(-std::pow((palm.radius_m - params.palm_radius_m) / 0.02, 2));
  out.confidence = static_cast<float>(std::clamp(palm.valid_fraction, 0.0, 1.0) * (0.5 + 0.5 * size_score));
  // An edge-on palm's centre is placed by the hand's shape (measured: ~6 mm off, against ~2 mm for
  // a measured circle): half the confidence.
  if (palm.placed_by_model) out.confidence *= 0.5f;
  return out;
}

}  // namespace tachi::sensor
