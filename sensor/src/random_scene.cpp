#include "tachi/sensor/random_scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>

namespace tachi::sensor {
namespace {

using Vec3 = Eigen::Vector3d;

/// Draws through our own mapping of mt19937_64's output (its sequence is fixed by the standard;
/// the library's distributions are not), so a seed is the same clip everywhere.
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(seed * 0x9E3779B97F4A7C15ULL + 0x632BE59BD9B4E5ULL) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(rng_() >> 11) * 0x1.0p-53; }
  bool chance(double p) { return uniform(0, 1) < p; }
  int integer(int lo, int hi) { return std::min(hi, lo + static_cast<int>(uniform(0, hi - lo + 1))); }
  double sign() { return chance(0.5) ? 1.0 : -1.0; }
  /// Normal by Box-Muller.
  double normal(double sigma) {
    const double u1 = std::max(uniform(0, 1), 1e-300), u2 = uniform(0, 1);
    return sigma * std::sqrt(-2 * std::log(u1)) * std::cos(2 * 3.14159265358979323846 * u2);
  }

 private:
  std::mt19937_64 rng_;
};

// The image's extent at depth z (Burrus' intrinsics, 640 x 480): x from -0.571 z to 0.507 z, y
// from -0.41 z to 0.403 z.
constexpr double kLeftPerZ = -0.571, kRightPerZ = 0.507, kTopPerZ = -0.410, kBottomPerZ = 0.403;

/// A box's rectangle on the image plane z = 1 (x/z, y/z), conservatively from its corners.
struct ImageRect {
  double x0, y0, x1, y1;
  bool overlaps(const ImageRect& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
};
ImageRect image_rect(const Vec3& lo, const Vec3& hi) {
  ImageRect r{1e9, 1e9, -1e9, -1e9};
  for (int c = 0; c < 8; ++c) {
    const Vec3 p((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
    const double z = std::max(p.z(), 0.3);
    r.x0 = std::min(r.x0, p.x() / z);
    r.x1 = std::max(r.x1, p.x() / z);
    r.y0 = std::min(r.y0, p.y() / z);
    r.y1 = std::max(r.y1, p.y() / z);
  }
  return r;
}

struct Path {
  std::vector<Keyframe> keys;
  double t = 0;
  Vec3 at = Vec3::Zero();
  void go(const Vec3& p, double dt) {
    t += std::max(dt, 0.12);
    at = p;
    keys.push_back({t, p, false});
  }
};

}  // namespace

ScenarioSpec random_scenario(std::uint64_t seed, bool hanging_rest) {
  Draw d(seed);
  ScenarioSpec s;
  s.name = "random_" + std::to_string(seed);
  s.seed = seed;
  s.fps = 30;
  s.distractor = false;
  s.hashed_noise = true;
  // With `hanging_rest` the hand rests at the end of the arm, fingers down (synthetic.hpp; session 34):
  // the floating resting pose beyond the arm's reach was 58% of the tuning range's phantom frames.
  s.hanging_rest = hanging_rest;

  // The user. Torso at 0.8-2.5 m (the range), sideways within the image, height +-12 cm
  // about the camera's, 1 in 8 left handed, arms 0.88-1.1x the renderer's 31 + 28 cm.
  const double torso_z = d.uniform(0.8, 2.5);
  const double user_x = d.uniform(-0.18, 0.18) * torso_z;
  s.user_offset = Vec3(user_x, d.uniform(-0.12, 0.12), torso_z - 1.47);
  s.left_handed = d.chance(0.125);
  s.arm_scale = d.uniform(0.88, 1.1);
  const double side = s.left_handed ? 1.0 : -1.0;
  const Vec3 shoulder = Vec3(side * 0.19, 0.0, 1.44) + s.user_offset;
  s.wall_z = std::min(3.5, torso_z + d.uniform(0.5, 1.4));

  // Where the hand works: in front of the body, 25-55 cm out (nearer than 0.5 m the Kinect sees
  // nothing, so never nearer than 0.55 m), a forearm's length either side of the shoulder.
  const double z_far = torso_z - 0.25, z_near = std::max(0.55, torso_z - 0.55 * s.arm_scale);
  const auto workspace = [&](Draw& r) {
    return Vec3(shoulder.x() - side * r.uniform(-0.12, 0.40), shoulder.y() + r.uniform(-0.30, 0.28), r.uniform(z_near, z_far));
  };
  const auto in_image = [](const Vec3& p, double margin) {
    return p.x() / p.z() > kLeftPerZ + margin && p.x() / p.z() < kRightPerZ - margin && p.y() / p.z() > kTopPerZ + margin &&
           p.y() / p.z() < kBottomPerZ - margin;
  };
  const auto workspace_in_image = [&](Draw& r) {
    Vec3 p = workspace(r);
    for (int i = 0; i < 20 && !in_image(p, 0.12); ++i) p = workspace(r);
    return p;
  };

  // Start: 40% up from the first frame, 48% raised later, 12% never raised.
  const double start_draw = d.uniform(0, 1);
  const HandStart start = start_draw < 0.40 ? HandStart::kUpFromFirstFrame
                          : start_draw < 0.88 ? HandStart::kRaisedLater
                                              : HandStart::kNeverRaised;
  const double duration = d.uniform(2.5, 4.0);
  Path path;
  if (start == HandStart::kNeverRaised) {
    path.keys = {{0.0, Vec3::Zero(), true}, {duration, Vec3::Zero(), true}};
  } else {
    if (start == HandStart::kUpFromFirstFrame) {
      path.at = workspace_in_image(d);
      path.keys.push_back({0.0, path.at, false});
      if (d.chance(0.5)) path.go(path.at, d.uniform(0.3, 1.2));  // held still at first (still_start)
    } else {
      path.keys.push_back({0.0, Vec3::Zero(), true});
      path.t = d.uniform(0.2, 1.2);
      path.keys.push_back({path.t, Vec3::Zero(), true});
      path.go(workspace_in_image(d), d.uniform(0.35, 0.6));
    }
    // Segments until the clip's length: each one kind of movement at 0.25-1.2 m/s.
    while (path.t < duration - 0.3) {
      const double speed = d.uniform(0.25, 1.2);
      const auto move = [&](const Vec3& p) { path.go(p, (p - path.at).norm() / speed); };
      switch (d.integer(0, 6)) {
        case 0:  // sweep across
          move(Vec3(shoulder.x() - side * d.uniform(-0.12, 0.40), path.at.y() + d.uniform(-0.08, 0.08), path.at.z() + d.uniform(-0.05, 0.05)));
          break;
        case 1: {  // curve: three points on an arc
          const Vec3 to = workspace(d);
          const Vec3 mid = 0.5 * (path.at + to) + Vec3(0, -d.uniform(0.05, 0.2), 0);
          const Vec3 a = path.at;
          for (const double f : {0.33, 0.67, 1.0}) {
            const Vec3 q = (1 - f) * (1 - f) * a + 2 * f * (1 - f) * mid + f * f * to;
            move(q);
          }
          break;
        }
        case 2: {  // push toward the camera and back (a far hand pushing in included)
          const Vec3 near(path.at.x() + d.uniform(-0.1, 0.1), path.at.y() + d.uniform(-0.06, 0.06), z_near);
          move(near);
          if (d.chance(0.6)) move(Vec3(near.x() + d.uniform(-0.1, 0.1), near.y(), d.uniform(z_near, z_far)));
          break;
        }
        case 3: {  // zig-zag
          const double dy = d.uniform(0.05, 0.12), dx = d.uniform(0.04, 0.1) * -side * d.sign();
          for (int k = 0; k < 4; ++k) move(path.at + Vec3(dx, (k % 2 ? -2 : 2) * dy * (k == 0 ? 0.5 : 1.0), 0));
          break;
        }
        case 4:  // pause
          path.go(path.at, d.uniform(0.2, 0.8));
          break;
        case 5: {  // out of the image across its nearest side edge (or the top), and back
          const double z = path.at.z();
          const int edge = d.integer(0, 2);
          Vec3 out = path.at;
          if (edge == 0) out.x() = (kLeftPerZ - 0.1) * z;
          if (edge == 1) out.x() = (kRightPerZ + 0.1) * z;
          if (edge == 2) out.y() = (kTopPerZ - 0.1) * z;
          move(out);
          path.go(out, d.uniform(0.1, 0.5));
          move(workspace_in_image(d));
          break;
        }
        default:  // a point anywhere in reach
          move(workspace(d));
          break;
      }
    }
    if (d.chance(0.5)) {  // lowered at the end
      path.go(Vec3::Zero(), d.uniform(0.4, 0.6));
      path.keys.back().rest = true;
      path.go(Vec3::Zero(), 0.3);
      path.keys.back().rest = true;
    }
  }
  s.path = path.keys;
  for (std::size_t i = 1; i < s.path.size(); ++i)  // keyframe times strictly increase (go() adds >= 0.12 s)
    s.path[i].t = std::max(s.path[i].t, s.path[i - 1].t + 0.05);

  // Tremor in half the clips: 1-8 mm RMS at 3-11 Hz (a 2 Hz band around a drawn frequency).
  if (d.chance(0.5)) {
    s.jitter_m = d.uniform(0.001, 0.008);
    const double hz = d.uniform(4, 10);
    s.jitter_min_hz = hz - 1;
    s.jitter_max_hz = hz + 1;
  }
  // The palm: 70% held about square to the sensor, 30% turned up to 60 degrees either way.
  s.palm_yaw_deg = d.chance(0.3) ? d.uniform(-60, 60) : std::clamp(d.normal(6), -15.0, 15.0);
  s.palm_pitch_deg = std::clamp(d.normal(5), -12.0, 12.0);
  s.palm_roll_deg = std::clamp(d.normal(8), -20.0, 20.0);
  s.fingers_together = d.chance(0.25);

  // Kinect v1 noise.
  s.noise_raw = d.uniform(0.2, 0.6);
  s.edge_dropout = d.uniform(0.15, 0.5);
  s.dropout_blobs = d.uniform(0, 14);

  // The hand's region on the image (every keyframe, and the tremor's reach), grown by a hand
  // and a forearm: objects nearer than the hand are placed where they do not cover it (a user
  // cuts in free space; a covered hand is not visible, so it is not an error not to see it).
  ImageRect hand{1e9, 1e9, -1e9, -1e9};
  double hand_min_z = 10;
  for (const auto& k : s.path) {
    if (k.rest) continue;
    const double z = k.p.z();
    hand_min_z = std::min(hand_min_z, z);
    const double grow = 0.16 / z;
    hand.x0 = std::min(hand.x0, k.p.x() / z - grow);
    hand.x1 = std::max(hand.x1, k.p.x() / z + grow);
    hand.y0 = std::min(hand.y0, k.p.y() / z - grow);
    hand.y1 = std::max(hand.y1, k.p.y() / z + grow);
  }
  // The arm that raises the hand from its rest runs from the shoulder down: keep it clear too. (The
  // floating rest's place, kept for the hanging one so that every seed draws the same room: it lies
  // 2 cm farther out and 8 cm lower, so the region holds the hanging hand too.)
  const Vec3 rest = Vec3(side * 0.27, 0.72, 1.40) + s.user_offset;
  hand.x0 = std::min(hand.x0, std::min(shoulder.x(), rest.x()) / shoulder.z() - 0.08);
  hand.x1 = std::max(hand.x1, std::max(shoulder.x(), rest.x()) / shoulder.z() + 0.08);
  hand.y1 = std::max(hand.y1, rest.y() / rest.z());

  const int objects = d.integer(0, 4);
  for (int i = 0; i < objects; ++i) {
    SceneObject o;
    const int kind = d.integer(0, 4);
    static constexpr std::array<const char*, 5> kKinds{"box", "table_edge", "chair_back", "monitor", "side_wall"};
    o.kind = kKinds[static_cast<std::size_t>(kind)];
    // Nearer than the hand (by >= 12 cm) where there is room before it, else beside or behind the user.
    const bool near = hand_min_z - 0.12 > 0.6 && d.chance(0.6);
    const double z_front = near ? d.uniform(0.55, hand_min_z - 0.12) : d.uniform(std::max(0.6, torso_z - 0.3), s.wall_z - 0.1);
    Vec3 size;
    switch (kind) {
      case 0: size = Vec3(d.uniform(0.1, 0.45), d.uniform(0.1, 0.45), d.uniform(0.1, 0.45)); break;
      case 1: size = Vec3(d.uniform(0.8, 1.6), d.uniform(0.03, 0.05), d.uniform(0.5, 0.8)); break;
      case 2: size = Vec3(d.uniform(0.38, 0.5), d.uniform(0.35, 0.6), d.uniform(0.03, 0.06)); break;
      case 3: size = Vec3(d.uniform(0.45, 0.65), d.uniform(0.28, 0.4), d.uniform(0.03, 0.07)); break;
      default: size = Vec3(0.02, 3.0, s.wall_z - z_front); break;
    }
    bool placed = false;
    for (int attempt = 0; attempt < 30 && !placed; ++attempt) {
      // Across an image edge in half the cases: its centre drawn over the image widened by half its size.
      const bool at_edge = kind == 4 || d.chance(0.5);
      const double zc = z_front + 0.5 * size.z();
      const double widen = at_edge ? 1.0 : 0.0;
      Vec3 c(d.uniform(kLeftPerZ * z_front - widen * 0.5 * size.x(), kRightPerZ * z_front + widen * 0.5 * size.x()),
             d.uniform(kTopPerZ * z_front - widen * 0.5 * size.y(), kBottomPerZ * z_front + widen * 0.5 * size.y()), zc);
      if (kind == 1) c.y() = d.uniform(0.15, 0.5);  // a table top below the camera
      if (kind == 4) {
        c.x() = (d.chance(0.5) ? kLeftPerZ : kRightPerZ) * z_front * d.uniform(0.8, 1.0);
        c.y() = 0;
      }
      o.min = c - 0.5 * size;
      o.max = c + 0.5 * size;
      o.min.z() = z_front;
      o.max.z() = z_front + size.z();
      if (near) {
        if (image_rect(o.min, o.max).overlaps(hand)) continue;
      } else {
        // Beside or behind the user: clear of the user's body and arm (the torso spans +-0.25 m).
        const Vec3 body = Vec3(0, 0.3, 1.47) + s.user_offset;
        const bool clear_x = o.max.x() < body.x() - 0.7 || o.min.x() > body.x() + 0.7;
        if (!clear_x && o.min.z() < body.z() + 0.2) continue;
      }
      placed = true;
    }
    if (!placed) continue;
    // 30% are moved in during the take: they slide 0.6 m in from the side over 0.4-0.8 s.
    if (d.chance(0.3)) {
      o.slide_s = d.uniform(0.4, 0.8);
      o.from_s = d.uniform(0.3 + o.slide_s, std::max(0.4 + o.slide_s, duration - 0.3));
      o.slide_from = Vec3(d.sign() * 0.6, 0, 0);
      // The slide's path must not cover the hand either.
      if (near) {
        const ImageRect a = image_rect(o.min + o.slide_from, o.max + o.slide_from), b = image_rect(o.min, o.max);
        const ImageRect swept{std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1), std::max(a.y1, b.y1)};
        if (swept.overlaps(hand)) o.slide_s = 0, o.from_s = 0, o.slide_from = Vec3::Zero();
      }
    }
    s.objects.push_back(o);
  }

  // A second person: 20% walk behind, 15% stand behind, where there is room before the wall.
  const double who = d.uniform(0, 1);
  const double behind_z = d.uniform(torso_z + 0.5, torso_z + 1.2);
  if (who < 0.35 && behind_z < s.wall_z - 0.2) {
    s.second_person = true;
    s.second_person_z = behind_z;
    s.second_person_standing = who >= 0.20;
    s.second_person_x = d.uniform(-0.4, 0.4) * behind_z;
  }
  return s;
}

HandStart random_start(const ScenarioSpec& spec) {
  const bool any_raised = std::any_of(spec.path.begin(), spec.path.end(), [](const Keyframe& k) { return !k.rest; });
  if (!any_raised) return HandStart::kNeverRaised;
  return spec.path.front().rest ? HandStart::kRaisedLater : HandStart::kUpFromFirstFrame;
}

}  // namespace tachi::sensor
