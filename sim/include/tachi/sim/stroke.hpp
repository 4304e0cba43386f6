// From a hand stroke to cuts of the cloth, progressively, as the samples arrive (seed 000 sections 3.1-3.2
// and the failures of its section 4, fixed):
//  * each sample (world metres) maps to the nearest particle of the cloth in its current shape; its grid
//    coordinate (u, v) is a cut-line point (seed 000 section 3.2). The sample's offset from that particle,
//    in the local frame of the deformed grid, also gives a continuous (u, v), which says whether the
//    hand is beyond the cloth's edge;
//  * jitter and complex trajectories (Figure 8): the stroke is simplified in (u, v) before rasterising.
//    A point joins the cut only once the samples since the last one stop fitting a straight chord (more
//    than `tolerance_cells` off it, or going back) or the chord reaches `max_lag_cells`: the cut lags the
//    hand by at most that, and a hand trembling around one particle cuts nothing;
//  * a stroke that runs past the boundary (Figures 6-7) is clipped to the grid rectangle in (u, v): the cut
//    goes straight to where the stroke crosses the edge instead of following the edge through the
//    nearest boundary particles; a swipe that starts and ends outside cuts straight through;
//  * the cut reaches the stroke's end point (Figure 5): the last sample always joins the cut at stroke end;
//  * the blade's force drags the neighbourhood of each particle as it is cut (seed 001, blade.hpp).
#pragma once

#include "tachi/common/hand_speed.hpp"
#include "tachi/sim/blade.hpp"
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/cut_line.hpp"
#include "tachi/sim/cutting.hpp"
#include "tachi/sim/exact_cut.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <istream>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace tachi::sim {

struct StrokeSample {
  double t = 0.0;  ///< seconds
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< world metres
};

/// A stroke read from CSV, or why it could not be.
struct StrokeFile {
  static constexpr std::size_t kMaxProblems = 20;
  std::vector<StrokeSample> samples;
  std::size_t skipped_rows = 0;  ///< rows with a wrong field count, a non-number, a value out of range, or time going back
  std::vector<std::string> problems;  ///< "line N: why" of the first kMaxProblems skipped rows, for the log
  std::string error;             ///< set when the file is unusable (no header `t,x,y,z`, no sample)
};

/// A stroke row beyond these is a corrupt file, not a hand: |t| in seconds, |x|, |y|, |z| in metres
/// (the same 100 m the live simulator rejects hand samples beyond).
inline constexpr double kMaxStrokeTime_s = 1e6;
inline constexpr double kMaxStrokeCoordinate_m = 100.0;

/// Whether a stroke sample at time `t_s` is due before solver step `step` (step k starts at k dt): a sample
/// goes to the step that starts nearest its time, t in [(k - 1/2) dt, (k + 1/2) dt). Rounding, not
/// "the step whose interval holds t": hand samples come on a 30 or 60 Hz clock, i.e. exactly on step
/// starts, where a time rounded to 6 decimals fell one step later than the unrounded one and the blade
/// then met the cloth one step apart (the worn blade's cut: 3 or 21 pieces). Half-way between steps no
/// such clock ticks.
[[nodiscard]] bool stroke_sample_due(double t_s, long long step, double dt_s);

/// Removes the samples a hand cannot have made: faster than `params.max_hand_speed_mps` (10 m/s) from the
/// last accepted sample, with the filter's rule and threshold (common/hand_speed.hpp), so a stroke CSV
/// (tachi-sim --stroke) is held to what live samples are. Such a sample is never cut along (a row 2 m off
/// the cloth in 1/60 s would otherwise cut a straight chord out to it and back). Rows with the same time
/// count `nominal_dt_s` apart. Returns how many were removed.
std::size_t drop_impossible_samples(std::vector<StrokeSample>& samples, const common::OutlierParams& params = {},
                                    double nominal_dt_s = 1.0 / 60.0);

/// Parses `t,x,y,z` CSV (header required; blank lines ignored; bad rows skipped and counted).
[[nodiscard]] StrokeFile parse_stroke_csv(std::istream& in);

/// Where a world point falls on the cloth.
struct ClothPoint {
  std::uint32_t particle = 0;          ///< nearest particle
  GridCoord grid;                      ///< its grid coordinate
  Eigen::Vector2d uv{0.0, 0.0};        ///< continuous grid coordinate of the point itself
  float distance_m = 0.0F;             ///< to the nearest particle
  bool inside = false;                 ///< uv within the grid rectangle (+ margin)
};

/// Nearest-particle search with a warm start (a hand moves little between samples): greedy descent over
/// live springs from the previous answer, falling back to a full scan when the point does not project onto
/// the sheet within a cell of where the descent ended.
class ClothLocator {
 public:
  /// `lips_meet`: a cut's two lips are one place in rest coordinates (the exact and grid cuts split the cloth
  /// along a line), so a point over an opened cut is on the cut; not where cutting deletes triangles (its
  /// hole has an extent of its own).
  explicit ClothLocator(double inside_margin_cells = 0.5, bool lips_meet = true)
      : margin_(inside_margin_cells), lips_meet_(lips_meet) {}
  [[nodiscard]] ClothPoint locate(const Cloth& cloth, const Eigen::Vector3f& point);
  void reset() { hint_.reset(); }

 private:
  double margin_;
  bool lips_meet_;
  std::optional<std::uint32_t> hint_;
};

/// How a stroke cuts: exact = along the stroke's own path (exact_cut.hpp); grid = seed 000's cut line
/// along grid lines, eqs. (1)-(4) (cutting.hpp); delete = seed 001 section 4, the triangles the blade
/// passes through are deleted, then completeCUT.
enum class CutMode : std::uint8_t { Exact, Grid, Delete };
/// "exact", "grid", "delete"; nothing for anything else.
[[nodiscard]] std::optional<CutMode> parse_cut_mode(std::string_view name);
[[nodiscard]] std::string_view to_string(CutMode mode);

struct StrokeOptions {
  /// Grid here so that the library reproduces seed 000 unless asked; the product (tachi-sim's --cut-mode,
  /// offline and live) defaults to exact.
  CutMode mode = CutMode::Grid;
  Blade blade = Blade::Scalpel;
  BladeDrag drag;
  double tolerance_cells = 0.75;  ///< simplification: largest deviation from a chord, grid cells (grid mode)
  /// The same in exact and delete modes, where the cut follows the path exactly: only samples within this
  /// of a straight chord are dropped (the cut stays within this + the snap distance of the samples)...
  double exact_tolerance_cells = 0.25;
  /// ... and a hand going back along its own path by less than this does not make the cut double back:
  /// a path crossing itself cuts out slivers (measured on the straight_cut recording: a hand slowing down
  /// at the end of its stroke, cut with 0.02 cells, left 17 pieces instead of one slit).
  double exact_backtrack_cells = 0.75;
  /// Exact and delete modes: a point of the path that would close a loop shorter than this around (in cells,
  /// and at least exact_min_loop_m) does not join the cut: a hand wobbling at the end of its stroke would
  /// cut out islands (straight_cut recording at 64 x 64: 3 pieces instead of one slit). Larger loops cut out
  /// their patch as drawn.
  double exact_min_loop_cells = 4.0;
  double exact_min_loop_m = 0.06;
  /// ... and a point closer than this to where the cut ends (cells, and at least exact_min_step_m) waits for
  /// the hand to move on, unless it is on the cloth's edge.
  double exact_min_step_cells = 1.0;
  double exact_min_step_m = 0.01;
  /// Exact and delete modes: a sample whose point on the cloth moved more than ratio x the hand's motion +
  /// this many cells since the previous sample is the locator's mistake (another layer of a folded cloth),
  /// and is skipped.
  double exact_max_jump_ratio = 2.0;
  double exact_max_jump_cells = 3.0;
  double max_lag_cells = 2.0;     ///< simplification: longest chord before it joins the cut
  /// Grid mode: a sample's grid point is its (u, v) rounded, but it keeps the previous sample's row (column)
  /// until it is more than 0.5 + this many cells from it: a stroke along the middle between two rows (y = 0
  /// on an even grid) otherwise flipped between them on a 1e-6 m wobble, and its cut with them. 0 here (seed
  /// 000's rounding, what the library's tests pin down); the session (tachi-sim) uses kGridHysteresisCells.
  double grid_hysteresis_cells = 0.0;
  double inside_margin_cells = 0.5;
};

/// The grid mode's hysteresis in tachi-sim (Session), cells: a quarter cell, not tuned (the filed stroke lies
/// exactly between two rows; any margin keeps it on one).
inline constexpr double kGridHysteresisCells = 0.25;

/// Exact and delete modes: a stretch of a stroke within this of the samples a cut was already made along
/// (cells; plus the simplification's tolerance for the path) runs along that cut and does not cut again,
/// when it is at least kRecutMinRunCells long (a shorter one is where the path crosses or leaves the cut).
/// Sampled every kRecutStepCells.
inline constexpr double kRecutCells = 0.1;
inline constexpr double kRecutMinRunCells = 1.0;
inline constexpr double kRecutStepCells = 0.05;
/// A blade back in its slit: a sample whose hand is within kRecutCells (in metres on the cloth) of where the
/// hand already was while it cut, and whose material is within this many cells of that cut, is on the cut, where
/// the hand cut then (StrokeCutter::in_slit). Chosen on the razor re-cut of development strokes 1-300
/// (cut_stability --recut; docs/cutting.md section 10): session 39 (the cut's point nearest the material) 1 cell
/// left 23 exact-mode strokes differing, 1.5 16, 2 and 3 14, 50 without; session 41 (where the hand cut), all
/// modes: 2 cells 8, 3 5, 4 3, 6 3, unbounded 3. A flap swings by a few cells; a piece that fell or a cloth
/// that moved as a whole lies farther. Beyond StrokeOptions::exact_max_jump_cells (3) the first sample moved onto
/// the cut from material that far is taken for the locator's jump and dropped, as such a jump is.
inline constexpr double kSlitCells = 4.0;
/// The current line's last stretch that in_slit leaves out (a hand going on is not coming back), in cells.
inline constexpr double kSlitTailCells = 2.0;
/// Grid mode: how many of the line's particles before a new staircase may begin a stretch along a cut made
/// already (StrokeCutter::along_cut_made): a ring of one cell closes within a step or two.
inline constexpr std::size_t kGridLookBack = 3;

/// What a stroke did so far.
struct StrokeReport {
  std::vector<GridCoord> cut_line;   ///< every cut line of the stroke, concatenated (an exit and re-entry starts a new one);
                                     ///< exact/delete modes: the grid points nearest the points of the path.
                                     ///< A line that changed nothing (it went over cuts already made) is not kept
  std::size_t lines = 0;             ///< how many separate cut lines (that changed the cloth)
  std::size_t particles_duplicated = 0;
  float cut_length_m = 0.0F;         ///< rest length of the cut lines
};

/// Receives the samples of strokes one at a time and cuts the cloth progressively. One per cloth (it
/// owns the cloth's ClothCutter); the same object serves the live simulator and the offline driver.
class StrokeCutter {
 public:
  StrokeCutter(Cloth& cloth, StrokeOptions options);

  /// Gate opened: a new stroke. Ends an open stroke first.
  TopologyChange begin_stroke();
  /// A sample of the open stroke (opens one if none is). Non-finite positions are skipped. `touching`: whether
  /// the blade is at the cloth (the session's BladeContact). A sample away from it cuts nothing, wherever its
  /// (u, v) falls: extrapolated from the nearest particle's frame, a hand 30 cm from a swinging flap can map into
  /// the grid rectangle. It ends the cut at the sample before (or at the edge, when it is beyond it).
  TopologyChange add_sample(const StrokeSample& sample, bool touching = true);
  /// The same for a sample whose point on the cloth was found earlier (`locate`): where the blade met the cloth,
  /// located before it dragged the cloth along (the session's BladeContact), is where the cut begins.
  TopologyChange add_sample(const StrokeSample& sample, const ClothPoint& at, bool touching = true);
  /// Where a world point falls on the cloth as it is now (the locator add_sample uses, warm-started).
  [[nodiscard]] ClothPoint locate(const Eigen::Vector3f& point) { return locator_.locate(*cloth_, point); }
  /// Gate closed: the cut reaches the last sample, the line's end is tidied. Nothing if no stroke is open.
  TopologyChange end_stroke();

  [[nodiscard]] bool stroke_open() const { return open_; }
  /// The current (or last) stroke.
  [[nodiscard]] const StrokeReport& report() const { return report_; }
  /// Totals over every stroke.
  [[nodiscard]] const StrokeReport& total() const { return total_; }
  [[nodiscard]] const ClothCutter& cutter() const { return cutter_; }
  /// The exact cutter (exact and delete modes), or nullptr in grid mode.
  [[nodiscard]] const ExactCutter* exact() const { return exact_ ? &*exact_ : nullptr; }
  /// Every point the exact/delete cut went through, per line (rest coordinates, cells), for pattern.svg.
  [[nodiscard]] const std::vector<std::vector<Eigen::Vector2f>>& paths() const { return paths_; }
  [[nodiscard]] const StrokeOptions& options() const { return options_; }

 private:
  struct Point {
    Eigen::Vector2d uv;
    GridCoord grid;
    Eigen::Vector3f world;
    bool inside;  // on the cloth: touching it, and (u, v) within the grid rectangle (+ margin)
    bool beyond;  // (u, v) beyond the grid rectangle (+ margin)
    bool in_slit = false;  // moved onto a cut already made (in_slit)
  };
  void commit(GridCoord g, const Eigen::Vector2d& uv, const Eigen::Vector3f& direction, TopologyChange& change);
  void start_line(GridCoord g, const Eigen::Vector2d& uv, const Eigen::Vector3f& direction, TopologyChange& change);
  void close_line();
  /// A closed line that changed nothing leaves no history: its track, path, cut-line cells, count and length
  /// are taken back (see line_start_).
  void forget_line();
  /// Whether the cut from `from` to `to` would meet the current line's path and close a loop shorter than
  /// the options' minimum.
  [[nodiscard]] bool closes_small_loop(const Eigen::Vector2d& from, const Eigen::Vector2d& to) const;
  /// Exact and delete modes: the parts of the segment from `from` to `to` (rest cells) that do not run along
  /// a cut already made (within kRecutCells for at least kRecutMinRunCells): going over a cut again
  /// changes nothing. `direction`: the hand's motion (whether it turned back along the line it is cutting).
  [[nodiscard]] std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> recut_parts(
      const Eigen::Vector2d& from, const Eigen::Vector2d& to, const Eigen::Vector3f& direction) const;
  /// Whether `p` lies within `radius` cells of the samples of the cut so far (tracks_), without the current
  /// line's last `tail_cells`, unless a segment of that last stretch runs against `against` (a path moving that
  /// way has turned back along it). Tracks whose box is farther are skipped and the search stops at the first
  /// segment near enough: a session's cut history grows with every pass (an hour of the same stroke looped
  /// is ~800 tracks), and this runs for every sample.
  [[nodiscard]] bool near_track(const Eigen::Vector2d& p, double radius, double tail_cells,
                                const Eigen::Vector2d& against = Eigen::Vector2d::Zero()) const;
  /// Grid mode: the first stretch run[i..j] (j after `first`, where the part not yet cut begins) between two
  /// particles on cuts, or on the cloth's edge, that those already join within one cell of it (cut_path_beside).
  [[nodiscard]] std::optional<std::pair<std::size_t, std::size_t>> along_cut_made(std::span<const GridCoord> run,
                                                                                std::size_t first) const;
  /// Whether cut edges (or the cloth's edge) join run's first particle to its last by a shortest path through
  /// particles within one cell of `run`, with every particle of `run` within one cell of that path.
  [[nodiscard]] bool cut_path_beside(std::span<const GridCoord> run) const;
  /// Appends a sample to the current line's track and grows the track's box.
  void extend_track(const Eigen::Vector2f& sample);
  /// Appends where the hand was for a sample that joined the track (the track's hand path, in the world), and
  /// the point of the cloth it cut there (`uv`, rest cells).
  void extend_blade_track(const Eigen::Vector3f& hand, const Eigen::Vector2d& uv);
  /// A hand moving by `motion` at `hand`: Earlier when within `radius_m` of where it was while a cut so far was
  /// made (blade_tracks_) without the current line's last `tail_m` of hand path; TurnedBack when only near that
  /// last stretch while moving against it. `uv`: where the blade cut when the hand was at the nearest point of
  /// that hand path.
  enum class BladeTrackMatch { None, Earlier, TurnedBack };
  struct BladeTrackHit {
    BladeTrackMatch match = BladeTrackMatch::None;
    Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  };
  [[nodiscard]] BladeTrackHit near_blade_track(const Eigen::Vector3f& hand, const Eigen::Vector3f& motion,
                                               double radius_m, double tail_m) const;
  /// `uv` moved onto the cut when the blade is back in its slit (kSlitCells), else `uv`.
  [[nodiscard]] Eigen::Vector2d in_slit(const Eigen::Vector2d& uv, const Eigen::Vector3f& hand,
                                        const Eigen::Vector3f& motion) const;
  /// Where a stroke crosses the cloth's edge next to a sample in the slit: onto the cut too, when within kSlitCells.
  [[nodiscard]] Eigen::Vector2d edge_in_slit(const Eigen::Vector2d& at_edge) const;
  /// The nearest point of the cut paths so far (paths_; without the segment being cut when `cutting`).
  [[nodiscard]] Eigen::Vector2d nearest_on_cut(const Eigen::Vector2d& p, bool cutting = false) const;
  /// A length in cells: `cells`, or `metres` on this cloth if that is more.
  [[nodiscard]] double at_least(double cells, double metres) const;
  void add_line_to_report(const std::vector<GridCoord>& line);
  [[nodiscard]] GridCoord boundary_point(const Eigen::Vector2d& uv) const;
  /// Grid mode: uv rounded to a grid point, with hysteresis against the previous sample's.
  [[nodiscard]] GridCoord grid_point(const Eigen::Vector2d& uv) const;
  [[nodiscard]] Eigen::Vector2d clamp_uv(const Eigen::Vector2d& uv) const;
  [[nodiscard]] bool follows_path() const { return options_.mode != CutMode::Grid; }

  Cloth* cloth_;
  StrokeOptions options_;
  ClothCutter cutter_;
  std::optional<ExactCutter> exact_;
  std::optional<Eigen::Vector2d> path_end_;  // exact/delete: where the open line's cut ends
  std::vector<std::vector<Eigen::Vector2f>> paths_;
  std::vector<char> path_cuts_;  // exact/delete: per point of the open line's path, whether the segment to it cut
  std::vector<std::vector<Eigen::Vector2f>> tracks_;  // exact/delete: the samples (uv) the cuts so far were made along
  std::vector<Eigen::AlignedBox2f> track_boxes_;       // ... the box of each track's samples
  std::vector<Eigen::Vector2f> recent_;               // ... and those since the last point that joined the cut
  std::vector<std::vector<Eigen::Vector3f>> blade_tracks_;  // ... where the hand was for each track sample (world)
  std::vector<std::vector<Eigen::Vector2f>> blade_uvs_;     // ... and where on the cloth it cut then (uv)
  std::vector<Eigen::AlignedBox3f> blade_boxes_;            // ... the box of each
  std::vector<Eigen::Vector3f> recent_hands_;               // ... and for each of recent_
  // Where the open line's history begins, and whether its cuts changed the cloth. A pass over cuts already made
  // changes nothing, and keeping its samples would let the going-over-a-cut zone creep sideways pass by pass (each
  // pass within kRecutCells of the last) and grow without bound in a long session (the soak: a stroke looped for
  // an hour, ~1.2 KB of history a pass).
  struct LineStart {
    std::size_t tracks = 0, paths = 0, report_cells = 0, total_cells = 0, report_lines = 0, total_lines = 0;
    float report_length_m = 0.0F, total_length_m = 0.0F;
  };
  LineStart line_start_;
  bool line_changed_ = false;
  bool ending_ = false;          // end_stroke's commit: the last step joins however short
  bool arrived_on_cut_ = false;  // the current line's path got to its end along an earlier cut (or starts there)
  ClothLocator locator_;
  double backtrack_cells_;
  bool open_ = false;
  std::optional<CutLineBuilder> line_;      // while the stroke is inside the cloth
  Eigen::Vector2d anchor_{0.0, 0.0};        // uv of the last point that joined the cut
  std::vector<Point> pending_;              // samples since the anchor, not yet in the cut
  std::optional<Point> previous_;           // the stroke's previous sample
  Eigen::Vector3f last_direction_ = Eigen::Vector3f::Zero();  // hand motion, for the blade's drag
  StrokeReport report_;
  StrokeReport total_;
  BladeScratch drag_scratch_;
};

}  // namespace tachi::sim
