// The projections the solver's sweeps are made of, one constraint or four at a time (SSE, x86-64 baseline):
// a distance constraint (Mueller et al. 2007, eq. 10-11, with the XPBD factor of Macklin et al. 2016,
// eq. 18 with lambda = 0), near rest without a square root (Jakobsen 2001), and a unilateral tether
// (long-range attachment, Kim, Chentanez, Mueller 2012). The four-wide versions do the same arithmetic per
// lane as the scalar ones, so a sweep stays Gauss-Seidel in a fixed order, bit for bit. Private to tachi_sim.
#pragma once

#include "solver_common.hpp"
#include "tachi/sim/solver.hpp"

#include <emmintrin.h>
#include <xmmintrin.h>

#include <cmath>
#include <cstddef>

namespace tachi::sim::solver_detail {

enum class Length { Exact, NearRest };

/// Projection of one distance constraint C = |xa - xb| - target (Mueller et al. 2007, eq. 10-11), scaled
/// by the XPBD factor 1 / (wa + wb + alpha~) (Macklin et al. 2016, eq. 18 with lambda = 0).
/// Length::NearRest replaces |d| by its first-order expansion around the target, |d| ~ (|d|^2 + L^2) / 2L
/// (Jakobsen 2001, "Advanced Character Physics"): no square root, the same fixed point |d| = L, and a
/// correction that stays bounded (< |d|) however far the spring is compressed or stretched.
template <Length kLength>
inline void project_distance(Vec4& pa, Vec4& pb, float target, float alpha) {
  const float wa = pa.w(), wb = pb.w();
  const float wsum = wa + wb;
  if (wsum == 0.0F) return;
  const Vec4 d = (pb - pa).cwiseProduct(kXyz);
  const float len2 = d.squaredNorm();
  float c = 0.0F;
  if constexpr (kLength == Length::Exact) {
    if (len2 < 1e-18F) return;  // coincident particles: no direction to correct along
    const float len = std::sqrt(len2);
    c = (len - target) / (len * (wsum + alpha));
  } else {
    const float target2 = target * target;
    c = (len2 - target2) / ((len2 + target2) * (wsum + alpha));
  }
  pa += (wa * c) * d;
  pb -= (wb * c) * d;
}

/// project_distance<Length::NearRest> on four independent springs at once (SSE, x86-64 baseline):
/// the same arithmetic per lane, so the sweep is still Gauss-Seidel in the same fixed order.
inline void sweep_near_rest(Vec4* x, const Solver::SpringQuad* first, const Solver::SpringQuad* last, float alpha) {
  const __m128 alpha4 = _mm_set1_ps(alpha);
  const __m128 zero = _mm_setzero_ps();
  for (const Solver::SpringQuad* it = first; it != last; ++it) {
    const Solver::SpringQuad& g = *it;
    __m128 a0 = _mm_load_ps(x[g.a[0]].data()), a1 = _mm_load_ps(x[g.a[1]].data());
    __m128 a2 = _mm_load_ps(x[g.a[2]].data()), a3 = _mm_load_ps(x[g.a[3]].data());
    __m128 b0 = _mm_load_ps(x[g.b[0]].data()), b1 = _mm_load_ps(x[g.b[1]].data());
    __m128 b2 = _mm_load_ps(x[g.b[2]].data()), b3 = _mm_load_ps(x[g.b[3]].data());
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);  // a0 = x of the four a's, a1 = y, a2 = z, a3 = inverse mass
    _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
    const __m128 dx = _mm_sub_ps(b0, a0), dy = _mm_sub_ps(b1, a1), dz = _mm_sub_ps(b2, a2);
    const __m128 len2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    const __m128 rest2 = _mm_load_ps(g.rest2);
    const __m128 wsum = _mm_add_ps(a3, b3);
    const __m128 denominator = _mm_mul_ps(_mm_add_ps(len2, rest2), _mm_add_ps(wsum, alpha4));
    // Both ends fixed (wsum = 0, alpha = 0) would divide by zero: such lanes get c = 0.
    const __m128 c = _mm_and_ps(_mm_div_ps(_mm_sub_ps(len2, rest2), denominator), _mm_cmpgt_ps(wsum, zero));
    const __m128 ca = _mm_mul_ps(a3, c), cb = _mm_mul_ps(b3, c);
    a0 = _mm_add_ps(a0, _mm_mul_ps(ca, dx));
    a1 = _mm_add_ps(a1, _mm_mul_ps(ca, dy));
    a2 = _mm_add_ps(a2, _mm_mul_ps(ca, dz));
    b0 = _mm_sub_ps(b0, _mm_mul_ps(cb, dx));
    b1 = _mm_sub_ps(b1, _mm_mul_ps(cb, dy));
    b2 = _mm_sub_ps(b2, _mm_mul_ps(cb, dz));
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
    _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
    _mm_store_ps(x[g.a[0]].data(), a0);
    _mm_store_ps(x[g.a[1]].data(), a1);
    _mm_store_ps(x[g.a[2]].data(), a2);
    _mm_store_ps(x[g.a[3]].data(), a3);
    _mm_store_ps(x[g.b[0]].data(), b0);
    _mm_store_ps(x[g.b[1]].data(), b1);
    _mm_store_ps(x[g.b[2]].data(), b2);
    _mm_store_ps(x[g.b[3]].data(), b3);
  }
}

/// One tether (step 2): the particle is brought back onto the sphere of its reach around the anchor.
template <typename Tether>
inline void apply_tether(Vec4* x, const Tether& a) {
  Vec4& p = x[a.particle];
  if (p.w() == 0.0F) return;
  const Vec4& anchor = x[a.anchor];
  const Vec4 d = (p - anchor).cwiseProduct(kXyz);
  const float len2 = d.squaredNorm();
  if (len2 > a.reach2) p.head<3>() = anchor.head<3>() + d.head<3>() * std::sqrt(a.reach2 / len2);
}

/// apply_tether on four tethers at once (SSE, x86-64 baseline), in order: the same arithmetic per lane
/// (|d|^2 summed as Eigen sums a 4-vector, (x^2 + z^2) + y^2), so the same positions bit for bit. Four whose
/// particles or anchors overlap (one's particle is another's particle or anchor: behind a cut an anchor is a
/// particle with tethers of its own) go one by one. Most tethers are slack: a quad none of which is taut is
/// only read. `at(k)` is the k-th tether in the order they are applied.
template <typename At>
void sweep_tethers(Vec4* x, std::size_t count, const At& at) {
  std::size_t k = 0;
  for (; k + 4 <= count; k += 4) {
    const auto& t0 = at(k);
    const auto& t1 = at(k + 1);
    const auto& t2 = at(k + 2);
    const auto& t3 = at(k + 3);
    const __m128i particles = _mm_setr_epi32(static_cast<int>(t0.particle), static_cast<int>(t1.particle),
                                             static_cast<int>(t2.particle), static_cast<int>(t3.particle));
    const __m128i anchors = _mm_setr_epi32(static_cast<int>(t0.anchor), static_cast<int>(t1.anchor),
                                           static_cast<int>(t2.anchor), static_cast<int>(t3.anchor));
    // Every pair of lanes (i != j): particle i against particle j, particle i against anchor j.
    const __m128i p1 = _mm_shuffle_epi32(particles, _MM_SHUFFLE(0, 3, 2, 1));
    const __m128i p2 = _mm_shuffle_epi32(particles, _MM_SHUFFLE(1, 0, 3, 2));
    const __m128i a1 = _mm_shuffle_epi32(anchors, _MM_SHUFFLE(0, 3, 2, 1));
    const __m128i a2 = _mm_shuffle_epi32(anchors, _MM_SHUFFLE(1, 0, 3, 2));
    const __m128i a3 = _mm_shuffle_epi32(anchors, _MM_SHUFFLE(2, 1, 0, 3));
    const __m128i overlap = _mm_or_si128(
        _mm_or_si128(_mm_cmpeq_epi32(particles, p1), _mm_cmpeq_epi32(particles, p2)),
        _mm_or_si128(_mm_cmpeq_epi32(particles, a1),
                     _mm_or_si128(_mm_cmpeq_epi32(particles, a2), _mm_cmpeq_epi32(particles, a3))));
    if (_mm_movemask_epi8(overlap) != 0) {
      apply_tether(x, t0);
      apply_tether(x, t1);
      apply_tether(x, t2);
      apply_tether(x, t3);
      continue;
    }
    __m128 px = _mm_load_ps(x[t0.particle].data()), py = _mm_load_ps(x[t1.particle].data());
    __m128 pz = _mm_load_ps(x[t2.particle].data()), pw = _mm_load_ps(x[t3.particle].data());
    __m128 ax = _mm_load_ps(x[t0.anchor].data()), ay = _mm_load_ps(x[t1.anchor].data());
    __m128 az = _mm_load_ps(x[t2.anchor].data()), aw = _mm_load_ps(x[t3.anchor].data());
    _MM_TRANSPOSE4_PS(px, py, pz, pw);  // px = x of the four particles, ..., pw = inverse mass
    _MM_TRANSPOSE4_PS(ax, ay, az, aw);
    const __m128 dx = _mm_sub_ps(px, ax), dy = _mm_sub_ps(py, ay), dz = _mm_sub_ps(pz, az);
    const __m128 len2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dz, dz)), _mm_mul_ps(dy, dy));
    const __m128 reach2 = _mm_setr_ps(t0.reach2, t1.reach2, t2.reach2, t3.reach2);
    const __m128 taut = _mm_and_ps(_mm_cmpgt_ps(len2, reach2), _mm_cmpneq_ps(pw, _mm_setzero_ps()));
    if (_mm_movemask_ps(taut) == 0) continue;
    const __m128 scale = _mm_sqrt_ps(_mm_div_ps(reach2, len2));
    const auto pick = [&](__m128 moved, __m128 kept) {
      return _mm_or_ps(_mm_and_ps(taut, moved), _mm_andnot_ps(taut, kept));
    };
    px = pick(_mm_add_ps(ax, _mm_mul_ps(dx, scale)), px);
    py = pick(_mm_add_ps(ay, _mm_mul_ps(dy, scale)), py);
    pz = pick(_mm_add_ps(az, _mm_mul_ps(dz, scale)), pz);
    _MM_TRANSPOSE4_PS(px, py, pz, pw);
    _mm_store_ps(x[t0.particle].data(), px);
    _mm_store_ps(x[t1.particle].data(), py);
    _mm_store_ps(x[t2.particle].data(), pz);
    _mm_store_ps(x[t3.particle].data(), pw);
  }
  for (; k < count; ++k) apply_tether(x, at(k));
}

}  // namespace tachi::sim::solver_detail
