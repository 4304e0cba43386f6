// Depth frame -> 3D palm centre of the hand reaching toward the sensor.
//
// The hand is the end of the arm that reaches toward the sensor, not simply the nearest blob:
//  1. segmentation on a 160x120 grid of raw disparity: a per-cell background (the farthest
//     reading seen, so static things - furniture nearer than the hand included - are background
//     and a moving arm reveals what is behind it) gives the foreground (nearer than the background
//     by `foreground_m`); an opening removes the thin strips a swaying body leaves;
//  2. the foreground component is chosen by temporal continuity (the one under the previous hand;
//     one that is no arm's end gives way to an arm's end reaching 15 cm nearer), else the one
//     reaching nearest; its hand is the part within `hand_depth_band_m` of its
//     nearest point (the arm's far end), unless that point is a joint (an elbow pointing at the
//     camera) on the way to the arm's geodesic end (the point farthest along the surface from
//     the body): then the hand is at that end, in a depth band around its own nearest point;
//  3. at full resolution, in that region only: the hand mask (dropouts inside it filled), its
//     distance transform; the palm centre is the distance-transform maximum (the centre of the
//     largest inscribed circle, i.e. the palm), back-projected at the median depth of the palm
//     circle. A palm turned 31-63 degrees away is measured in its own plane instead: the hand's
//     readings near a total-least-squares plane, the flattest palm-sized place on a metric grid in
//     that plane (fingers are round, the palm flat), resampled through the plane-to-image
//     homography K [e1 e2 p0] (Hartley & Zisserman, Multiple View Geometry, sec. 8.1.1). Seen
//     63-80 degrees from the line of sight (the fingers as flat as the palm there), the centre is
//     placed by the hand's shape instead: 12 cm back from the fingertips along the hand, away from
//     the forearm, a palm's half width in from the palm's far edge (half the confidence).
// All thresholds are raw-disparity lookups built once from metric parameters.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include <Eigen/Core>

#include "tachi/sensor/depth_frame.hpp"
#include "tachi/sensor/depth_model.hpp"

namespace tachi::sensor {

/// Tuning. Metric values are converted to raw-disparity tables at construction.
struct HandFinderParams {
  double foreground_m = 0.08;       ///< nearer than the background by this = foreground (> sway, < arm)
  double hand_depth_band_m = 0.07;  ///< the hand: component pixels within this of its nearest point
  double narrow_band_above_m = 0.055; ///< a circle larger than this is measured again in a band ...
  double narrow_band_m = 0.035;     ///< ... this deep, then half that (a hand against the chest: the torso 4-8 cm behind)
  double palm_radius_m = 0.042;     ///< expected palm radius: the palm circle must fit in the image
  double min_palm_radius_m = 0.032; ///< a smaller inscribed circle is a forearm (~2.8 cm) or fingers, not a palm
  double max_palm_radius_m = 0.075; ///< a larger one is a body, not a palm
  /// A followed hand's palm circle is sought within this distance (a square of this half-width in
  /// the image) of the hand's nearest reading: every reading of a hand lies within ~12 cm of its
  /// palm's centre (the middle fingertip). The depth band around a hand held 15-30 cm in front of
  /// the body takes in the forearm, the upper arm or the shoulder, whose wider circles took the
  /// palm's place 20-40 cm away, and the jump test then dropped the hand (seeds 16, 18, 34: a third
  /// of their visible frames). Where no palm-sized circle lies there (a forearm nearer than the
  /// hand, leaving the image), the band's widest place is taken if it is this near where the palm
  /// was. A new track keeps the band's widest place (its candidates are tested in turn; near the
  /// nearest reading, a hand held against the chest was measured on the torso). <= 0: the band's
  /// widest place always. Chosen on seeds 1-100.
  double palm_from_nearest_m = 0.15;
  int min_component_cells = 10;     ///< on the 160x120 grid
  int edge_margin_px = 3;           ///< the palm circle must clear the image edge by this
  int invalid_left_columns = 8;     ///< Kinect's band without readings at the left edge
  double max_jump_m = 0.2;          ///< a hand lost this many frames ago does not reappear farther away...
  int reacquire_frames = 15;        ///< ... within this many frames (0.5 s at 30 Hz)
  /// ... farther from the last palm that kept its course (found a third frame running on its step,
  /// max_off_course_m): a glimpse since (a one- or two-frame track: the hand seen once while it moves
  /// fast, or an arm or a body taken for a frame) does not hold the hand away, it only lets through
  /// what lies within max_jump_m of it too; with no such palm within reacquire_frames, no test. A
  /// frame after a palm, the test is from that palm still. false: from the last palm, whatever it was.
  bool jump_from_kept_course = true;
  /// A followed palm found in the last two frames must lie within this of where its last step
  /// carries it (constant velocity, one frame on): the hand's acceleration moves it ~1 cm off that
  /// at 30 Hz, a palm measured on the arm behind it 10-30 cm (max_jump_m let those through:
  /// 0.2 m is a hand's reach in a frame from rest, not from its own course). The track is then
  /// refused as a jump is. Chosen on seeds 1-100 (4 cm lost tracked frames); <= 0: no such test.
  double max_off_course_m = 0.06;
  /// ... and a palm found again 2 to this many frames (k) after the last palm reported, where that one kept
  /// its course (found a third frame running on its step; missed frames between), by any path, must lie
  /// within k * max_off_course_m of where k of that step carry it. A hand lowered out of view with its arm attached (the randomized world's
  /// hanging rest, session 34) leaves its forearm in the component; a frame or two after the hand was
  /// last seen, a palm-sized place on that forearm or the upper arm, 15-40 cm above where the hand went
  /// (tuning seed 24: 3 frames 31-43 cm off), was followed: within max_jump_m of the last palm, with
  /// no course known across the missed frame. 0: no such test (the course is tested on consecutive
  /// frames of a followed hand only).
  int course_gap_frames = 4;
  /// A new track starts only on an arm's end: the surface must continue without a depth jump to
  /// this far behind the hand (a hand at 1 m reaches 35-45 cm out of the body; a head, a torso or a
  /// person walking behind span ~10 cm).
  double arm_protrusion_m = 0.15;
  /// A hand that crosses the image border this wide within a palm diameter of its circle, with a
  /// circle smaller than whole_palm_radius_m, is a palm cut by the border: not reported (its circle
  /// sits 3-5 cm inward of the real centre). A forearm crossing below a whole palm is narrower.
  double border_cut_width_m = 0.045;
  /// The circle a whole palm holds: >= 3.95 cm in every visible frame of the bundled recordings;
  /// the remains of a cut palm 1.1-3.8 cm.
  double whole_palm_radius_m = 0.039;
  /// A followed palm is measured against its own hand too: its circle within this of the largest one the
  /// track has reported is the whole palm, even below whole_palm_radius_m. A palm turned 15-30 degrees from
  /// the line of sight holds a 3.6-3.9 cm circle, and with its fingers or its wrist across the border it
  /// was refused as cut (tuning seeds 1-300: 144 visible frames, the circle within 2 cm of the truth); the
  /// border takes a palm's circle down more (the remains measured 0.9-3.4 cm, 6 of 47 3.5-3.8 cm). <= 0:
  /// the fixed size alone.
  double own_palm_shrink_m = 0.002;
  /// A new track starts only on a hand nearer than this: the user cuts at ~1 m in front of a body at
  /// ~1.45 m; a person walking by behind is not followed.
  double max_acquire_depth_m = 1.8;
  /// Farther than max_acquire_depth_m, a new track starts only on an arm's end (the grid test of
  /// arm_protrusion_m), up to this depth: a user standing 2-2.5 m away reaches out of the body, a
  /// person walking behind the user does not (their arms hang).
  double max_track_depth_m = 2.6;
  /// ... and there the surface must run back this far (a far user's hand is 25-55 cm in front of
  /// the torso; a person walking behind spans ~11 cm, or ~15 cm together with the user's arm).
  double far_arm_protrusion_m = 0.22;
  /// A new track starts only on a palm circle up to this radius (a whole palm holds 3.95-4.45 cm;
  /// the front of a box, a monitor or a chair back holds more); a followed hand keeps
  /// max_palm_radius_m.
  double max_new_palm_radius_m = 0.052;
  /// A palm is a compact blob: the place where its region stays nearly as wide as the inscribed
  /// circle (>= 85% of its radius) reaches at most this far from the circle's centre (a whole palm,
  /// fingers beside it included: 1-2 cm, at most ~8 cm seen in the tuning range). A limb is a tube
  /// of constant width: the upper arm (4.5 cm in radius) holds a palm-sized circle all along it,
  /// and an elbow or a shoulder at the hand's depth took the track (chosen on seeds 1-100). Since
  /// session 38 this limit is the search without a background's (find_arm_end); a new track from the
  /// foreground has the tighter max_foreground_new_palm_ridge_m below.
  double max_palm_ridge_m = 0.09;
  /// A new track from the foreground (follow_component, also the take-over) holds its palm to this
  /// tighter ridge instead. A near user's upper arm taken against the wall after the hand left the
  /// image's side (tuning seeds 70, 251: runs of 12 and 15 frames) measured 8.8-8.9 cm, refused and
  /// taken again as its ridge flickered about max_palm_ridge_m; no good foreground new track of tuning
  /// seeds 1-300 measured over 8 cm (session 37's log). The search without a background keeps
  /// max_palm_ridge_m: lowering that too lost a hand it finds within the background (seed 207, 81 of
  /// 113 tracked frames). Chosen on seeds 1-300, checked on 301-600 (session 38, docs/sensor.md).
  double max_foreground_new_palm_ridge_m = 0.08;
  /// A palm is flat (or cupped); a head, an elbow or a shoulder's round end seen from the front fills
  /// the depth band's disc as a palm does, but bulges toward the sensor along every direction, its
  /// apex facing the sensor. A new track does not start on a palm circle whose readings bulge so:
  /// significantly (the fit's mean curvature over its standard error above dome_significance), by
  /// more than dome_min_curvature_per_m along its flattest direction (1 / (2 R): 3 is a sphere of
  /// R = 17 cm), and facing the sensor within acos(dome_min_view_cos) (a palm turned 45-60 degrees,
  /// its rims rolling off at two sides, bulges as much). Chosen on seeds 1-100 (measure_bulge).
  /// dome_significance <= 0: no such test.
  double dome_significance = 12.0;
  double dome_min_curvature_per_m = 3.0;
  double dome_min_view_cos = 0.9;
  /// A new track from the foreground does not start on a component whose nearest reading is within
  /// this many grid cells (4 px) of the image border: what is nearer still is out of view, and an
  /// arm leaving the image across a side shows a palm-sized place at its bend (chosen on seeds
  /// 1-100). Negative: no such test.
  int nearest_border_cells = 1;
  /// A new track from the foreground does not start where its front surface (within 2 cm of its
  /// nearest reading) meets the image border farther from the palm than a hand's fingertips reach
  /// (12 cm): an arm running out of the image at its side or bottom, whose junction with the shoulder
  /// or bend holds a palm-sized place (tuning seed 156: 48 frames, 30 cm off). Fingers cut by the
  /// border are within that reach. false: no such test (the search without a background refuses any
  /// front surface at the border).
  bool front_in_view_beyond_hand = true;
  /// The arm's end is its geodesic extremity: the surface reached from the arm's nearest reading
  /// without a depth jump and no farther back than this is walked, from where it runs on farther
  /// back (toward the body) to the point farthest along it. Where that end's hand does not hold the
  /// nearest reading and the nearest reading lies on the way to it (an elbow pointing at the camera,
  /// 5-9 cm nearer than a hand raised high), the hand is measured at the end, in a depth band
  /// around its own nearest reading: for a followed and a new track from the foreground alike; the
  /// search without a background asks is_joint first. Negative: the nearest reading is the hand.
  double arm_end_window_m = 0.2;
  /// The arm's-end test (arm_protrusion_m, far_arm_protrusion_m) walks one surface on the grid,
  /// stepping between neighbouring cells by at most 3 cm, or by this many of the Kinect's depth
  /// steps where those are coarser. One raw unit of disparity is 0.0031 z^2 m (3 mm at 1 m, 1 cm at
  /// 1.8 m, 1.5 cm at 2.2 m), and two readings of one surface differ by their slope's step plus up
  /// to a unit of rounding and 0.3-0.85 units of noise: at 2.2 m a forearm running back from the
  /// hand (1.5 cm between cells) read in steps of 3 cm and more, and a far user's raised hand was
  /// refused as no arm's end (tuning seed 6: 20 frames). 3 units is 3 cm at 1.8 m: nearer, nothing
  /// changes. Not for the joint and geodesic walks: with it there, the geodesic end of a far arm
  /// moved onto the body (seed 321: a new track 28 cm from the hand). <= 0: 3 cm at every depth.
  double surface_step_quanta = 3.0;
  /// A followed track that is no arm's end (the surface does not run back arm_protrusion_m from
  /// it: a second person's head) gives way to a nearer foreground component that is one and passes
  /// a new track's tests.
  bool take_over_by_arm_end = true;
  /// No hand where the background says (find_arm_end): the nearest readings tried as new hands, a frame...
  int candidates = 6;
  /// ... and before any hand was seen: a hand held up and still from the first frame is part of the
  /// background, and a room's nearer things (a box, a table edge, a side wall running back: one candidate
  /// per depth band each) used up the 6 before it (tuning seeds 1-100: 5 clips untracked ~30 frames).
  int start_candidates = 12;
  /// A hand found last frame and not foreground now (held still, part of the background, or moving on
  /// less than foreground_m in front of what is behind it) is tried first where it was, taken if its
  /// palm is within this of where it was or of where its last step carries it (0.45 m/s at 30 Hz,
  /// from rest or from its last step). 0: off (the nearest-first search only, which lost it behind
  /// nearer things until it moved).
  double still_hand_m = 0.015;
  /// A new track without a background whose band's widest place is no palm (a limb's tube, a dome) is
  /// looked at again near its nearest reading, as a followed palm is (palm_from_nearest_m), counting
  /// only the ridge through that circle: a hand held up beside the head with its forearm and upper arm
  /// at its depth has its widest place at the elbow. Tuning seeds 1-100 and 101-200: visible frames
  /// tracked 91.78 -> 92.39 % and 92.69 -> 93.27 %, nothing else changed. false: the first look only.
  bool second_look_near_nearest = true;
  /// A new track without a background is a hand at the candidate's nearest reading: its palm's centre
  /// lies within a hand's length of that reading (fingertips 12-13 cm from it at most; tuning seeds
  /// 1-80, 554 good new tracks: at most 12.8 cm). A palm measured farther off is some other
  /// palm-sized place in the depth band: a far user's elbow held forward 1 cm behind a hand raised
  /// beside the head, 39 cm below it (tuning seed 495: 4 frames captured). It is looked at again near
  /// the nearest reading (second_look_near_nearest), else refused. <= 0: no such limit.
  double max_new_palm_from_nearest_m = 0.2;
  /// A head is no hand: a new track does not start on a palm circle with a body's shoulders beneath
  /// it, i.e. readings within head_depth_m of the palm's depth that span head_shoulders_half_m to
  /// each side of its column along some grid row 25-45 cm below its centre (a head's centre is
  /// 20-30 cm above the shoulder line; an adult's chest is >= 30 cm wide). Below a raised hand lies
  /// its forearm (~6 cm wide) and, bent, the upper arm running to one side only; a hand held in front
  /// of the chest is >= 8 cm before it to be foreground at all. A second person walking behind the
  /// user, whose head was taken as a new track before the user's hand was up (tuning seeds 53, 320,
  /// 459, 466: runs of 8-21 frames). <= 0: no such test.
  double head_shoulders_half_m = 0.10;
  double head_depth_m = 0.06;
  /// A new track from the foreground does not start on a palm circle set in the static scene at its
  /// own depth: of the readings 8-12 cm from its centre (body_ring_*_m), more than this share are
  /// background (not foreground) within body_depth_m of the palm's depth. A near user's upper arm or
  /// shoulder, moving as the hand is lowered or leaves the image, is foreground beside a torso that
  /// stood still: it is set in the torso at its depth; a hand reaches out of what is behind it, which
  /// lies >= foreground_m farther, and its own forearm and fingers in the ring move with it. Tuning
  /// seeds 1-300 (session 37): 16 of the 22 new tracks 10+ cm off the hand had 38-78 % of their ring so,
  /// 327 of the 329 good ones at most 23 % (the other two 35 and 49 %: a hand rising past the hip, taken
  /// 1-3 frames later). <= 0 or > 1: no such test.
  double body_surround_share = 0.3;
  double body_ring_inner_m = 0.08;
  double body_ring_outer_m = 0.12;
  double body_depth_m = 0.04;
  /// A thing that came to rest becomes background although it was measured: a component refused as
  /// a new track (follow_component, not followed) at least rest_share of whose grid cells have read
  /// steady for rest_frames frames is not kept from the background's learning, as a followed arm or a
  /// hand found is. Without it a thing that slid in and stopped nearer than the hand (a box at the
  /// border, tuning seeds 15 and 160) was measured and refused every frame, never learned, and the
  /// hand behind it never measured. rest_frames <= 0: no such rule (every measured component kept).
  int rest_frames = 15;
  double rest_share = 0.8;
  /// ... and only where its nearest reading lies nearer than where the hand was last seen by this
  /// much (arm_protrusion_m's 15 cm: the user's own elbow is a few cm nearer than the hand at most;
  /// the body and arm are behind it). A hand that pauses is at rest too, and so is the user who
  /// stepped after a hand reaching out of the image (tuning seed 133: the whole user, at the hand's
  /// depth, learned while the hand paused beyond the image's side; stepping back, the arm moved out
  /// of the learned background and was taken 29 cm from the hand). No hand seen yet: nothing learned.
  double rest_nearer_than_hand_m = 0.15;
  /// A new track's palm lies no farther than this behind its candidate's nearest reading: the hand
  /// is the near end of a candidate (hand_depth_band_m). Applies to the search's candidates (the
  /// search without a background, and its second look), a new track from the foreground and the
  /// take-over; a followed track is not asked it. Why: a palm measured in its own plane (a turned
  /// palm) follows that plane's readings across the ROI, and where the candidate is the near end of
  /// an arm running back (the forearm of a hand refused nearer, a lowered arm) that plane is the
  /// arm's: its palm lies on the forearm or upper arm 8-19 cm behind the candidate's nearest
  /// reading, 16-31 cm from the hand (seeds 73, 307, 407, 497: captured runs of 4-15 frames, all
  /// from the search without a background). Why 0.10 and not the band's 0.07: good turned palms
  /// (turned toward edge-on, thumb ahead, plus the depth step at 2 m) sit up to 8.2 cm behind theirs
  /// (seeds 120, 296, 396), and 0.07 refused them. 0.10 removes the long runs of 73 and 497 and
  /// shortens 407's to 1 frame; 307's palm, 7.9 cm behind, is not told from a good one by this.
  /// Chosen on seeds 1-300, checked on 301-600 (docs/sensor.md, session 41). <= 0: no such test.
  double max_new_palm_behind_nearest_m = 0.10;
  /// The search without a background (find_arm_end) refuses a candidate whose band region (the
  /// cells within hand_depth_band_m of its nearest untried reading, and every nearer cell joined to
  /// them) holds a candidate refused earlier in the same frame as no arm's end (reaches_back) that
  /// would have passed a new track's palm tests, where the candidate's palm is measured elsewhere
  /// than that palm (its centre farther from the refused one's than that one's radius): the refused
  /// palm is the front of the region, and the candidate lies behind it on the same thing, its arm. A
  /// hand held still before the chest is no arm's end (its surface does not run arm_protrusion_m
  /// back); its forearm, the next nearest, reaches back and was measured as a turned palm on the
  /// upper arm (seed 307 of session 41's check range: a run of 15 captured frames). Measured at that
  /// palm (the hand found again from its forearm, which reaches back), the candidate is taken as
  /// before (seeds 179, 290: one and two good frames lost without that exception). The refused
  /// palms are measured only when a candidate that holds one has passed every other test (measuring
  /// each as it was refused tripled the bundled bench's p90). false: no such test.
  bool refuse_arm_of_refused_palm = true;
  /// A track found a frame ago as a new one has no step yet, so off_course cannot hold its second
  /// palm to a course: a followed palm farther than this from the first must be palm-shaped as a new
  /// track's is (max_new_palm_radius_m, max_foreground_new_palm_ridge_m, no dome, no shoulders below),
  /// and is otherwise refused and no longer followed. A hand moves a few cm a frame (1.2 m/s: 4 cm at
  /// 30 Hz); a palm measured on the arm of a hand just acquired lay 10-20 cm from it, its ridge running
  /// 10-22 cm along the arm (tuning seeds 3, 65, 126, 164, 181: one captured frame each, after which the
  /// track was lost). Only the shape: held to every new-track test (is_joint, the acquisition depth),
  /// fast hands' second palms (6-8 cm steps, ridges under 2 cm: seeds 41, 138, 259) were refused and
  /// their tracks lost for up to 7 frames. <= 0: no such test.
  double max_unproven_step_m = 0.06;
  /// No palm seen edge-on (placed by the hand's shape) is reported whose fingers point down by more
  /// than this sine of the angle below the camera's level (0.707: 45 degrees): that is a hand hanging
  /// at rest beside the body, or turning into that pose as it is lowered, not a hand held up to cut.
  /// Edge-on with its fingers down, a hanging hand reaches out of the surface behind it as a raised
  /// one does, and it was taken as a new track, or followed down into its rest (tuning seeds 68, 186,
  /// 200, 263, 272: captured runs of 1-6 frames while the hand was not raised; its fingers 72-90
  /// degrees down). A raised hand holds its fingers up or level: on seeds 1-300 the good placed palms
  /// pointed at most 40 degrees down (0.64). A palm measured as a circle (not edge-on) has no fingers'
  /// direction to test. A Kinect tilted by its motor (up to 27 degrees) brings a hand hanging straight
  /// down (84 degrees in the randomized world, placed at 72-90) to 57-63 degrees below its level, the
  /// lowest estimates to ~45: untested, as the randomized world's camera is level. > 1: no such test.
  double max_palm_tips_down = 0.707;
  /// Report the centre of the palm's face rather than of the hand's silhouette (palm_face_centre in
  /// hand_finder.cpp). A palm turned from the sensor shows the hand's side beside it, and the
  /// silhouette's widest place lay typically 5-10 mm toward that side at 30-60 degrees of turn (seeds 1-300).
  /// Only the reported position changes: the track's tests keep the silhouette's circle. false: as
  /// before session 44.
  bool report_palm_face = true;
};

struct HandObservation {
  bool tracked = false;
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();  ///< palm centre, camera frame
  float u = 0.0f;                   ///< palm centre pixel (640x480)
  float v = 0.0f;
  float confidence = 0.0f;          ///< 0..1; 0 when not tracked
  float palm_radius_m = 0.0f;       ///< radius of the palm's inscribed circle
};

/// Runs OpenCV's work in the calling thread. The finder's per-frame calls (a 160x120 grid, a
/// palm-sized ROI) are too small to split, and OpenCV's idle pool workers spin on sched_yield
/// against the other pipeline processes (81k calls over 1,330 frames were measured). Call once at
/// start-up; it is process-wide.
void use_one_opencv_thread();

class HandFinder {
 public:
  explicit HandFinder(const DepthModel& model, const HandFinderParams& params = {});
  ~HandFinder();
  HandFinder(HandFinder&&) noexcept;
  HandFinder& operator=(HandFinder&&) noexcept;

  /// Processes one 640x480 frame of raw disparity (kDepthPixels values). Frames must come in
  /// order: the background and the previous hand carry over. A frame of the wrong size gives an
  /// untracked observation.
  HandObservation find(std::span<const std::uint16_t> raw);
  HandObservation find(const DepthFrame& frame) { return find(frame.raw); }

  /// Forgets the background and the previous hand (e.g. after the sensor moved).
  void reset();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tachi::sensor
