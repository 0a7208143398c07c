// One receiver, one azimuth: NS09 §5.2's exponential steps over the height pyramid (Eq. 14-15), the
// B-spline interpolant of the blocking angles (Eq. 16) and the casting set (Eq. 17).
//
// Steps: knot k (k = 0..n-1) lies d_k = 2^(k / k_v) texels from the receiver (Eq. 14 in texel units; the
// paper's tau_i is d_k over the field size), n covers the field: d_(n-1) >= its diagonal (clamp) or its
// larger side (repeat). Knot k reads pyramid level l(k) = clamp(k - k_v o_v, 0, levels - 1): the filter grows
// with distance, its width about d_k / 2^(o_v) (the level offset o_v sharpens: NS09 "increasing o_v reduces
// the blurring"). Eq. 15 compares the sample with the receiver's height in the same level. In clamp mode the
// march ends at the border with a last knot on the border (the field is a solid that ends there: a ray
// below the border height is blocked, one above escapes).
//
// The blocking-angle curve: the uniform cubic B-spline with the knot angles as control points (end points
// repeated), evaluated at the knots and midpoints (2n - 1 points, Eq. 16); omega_max is its maximum, and the
// casting set (Eq. 17) are the points whose angle exceeds every earlier one, starting from omega_min.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "methods/nlp/pyramid.hpp"

namespace hfbake::nlp {

// |error| <= 1.2e-5 rad (Abramowitz & Stegun 4.4.49 with octant reduction), plain arithmetic.
inline float fast_atan(float x) {
  // Branch-free (selects), so loops over arrays of slopes vectorise (with -fno-trapping-math, which lets the
  // compiler run the division for every lane: nlp's CMakeLists).
  const float ax = std::abs(x);
  const bool inv = ax > 1;
  const float t = inv ? 1 / ax : ax, t2 = t * t;
  const float p =
      t * (0.9998660f + t2 * (-0.3302995f + t2 * (0.1801410f + t2 * (-0.0851330f + t2 * 0.0208351f))));
  const float r = inv ? 1.57079632679f - p : p;
  return std::copysign(r, x);
}

struct MarchSetup {
  int steps = 0;                // n knots
  std::vector<float> dist;      // d_k, texels
  std::vector<float> inv_dist;  // 1 / (d_k * texel_size)
  std::vector<int> level;       // height level per knot
  std::vector<int> rlevel;      // radiance level per knot (o_u)
  float texel_size = 1;
  bool repeat = false;
  int width = 0, height = 0;
  // > 0: where a knot reads level 0 (the field itself) and lies more than this many texels beyond the knot
  // before it, the stretch between them is sampled at most this far apart and the knot takes the largest
  // blocking angle (a peak between two knots is not missed). 0: NS09, one sample a knot.
  float near_spacing = 0;
};

// levels: the height pyramid's level count is steps - k_v * o_v (at least 1); likewise radiance.
MarchSetup make_march_setup(int width, int height, double texel_size, Wrap wrap, int levels_per_octave,
                            int level_offset, int radiance_level_offset);
int height_levels(const MarchSetup& s);
int radiance_levels(const MarchSetup& s);

// One ray. Fills omega[0..n) (knot blocking angles, radians), dist[0..n) (knot distances, texels), lev[0..n)
// (knot index into MarchSetup::level / rlevel) and returns n (0: the receiver is on the border and the ray
// leaves the field at once). recv[l]: the receiver's height in level l.
int march(const MarchSetup& s, const Pyramid& heights, int i, int j, float cx, float cy, const float* recv,
          float* omega, float* dist, int* lev);

// The row form of march (the kernels' form): one azimuth, receivers (xs[t], j), t < cnt, the knots of all
// receivers at once, knot-major (omega[k * stride + t]) so each knot is a loop over the row. Where a level
// has the field's own grid (level 0 and the levels up to about 4 texels of blur), the offset of knot k from
// its receiver, d_k (cx, cy), is split once into whole texels and a fraction shared by the whole row, so a
// run of receivers reads contiguous texels with one set of bilinear (or, for near_spacing, triangle)
// weights; coarser levels, repeat fields and the border ring read as march does. The results equal march's
// to float rounding (the fraction is taken from d_k cx instead of i + d_k cx), and they depend only on the
// receiver and the azimuth: the same bits for any row length, thread or tile.
struct RowMarch {
  int stride = 0;
  std::vector<float> omega;  // [k * stride + t]: slopes (tan of the blocking angle); angles after row_angles
  std::vector<int> n;        // knots of receiver t (the border knot, if any, last)
  std::vector<float> exit;   // receiver t's border knot distance (texels); infinite when it has none
  int max_n = 0;             // max of n over the row
  std::vector<float> tmp;    // per-row scratch (triangle samples)
  RowMarch() = default;
  RowMarch(int steps, int width)
      : stride(width),
        omega(std::size_t(steps + 1) * std::size_t(width)),
        n(std::size_t(width)),
        exit(std::size_t(width)),
        tmp(std::size_t(width)) {}
  // Distance of knot k of receiver t (k < n[t]).
  float dist(const MarchSetup& s, int k, int t) const {
    return k + 1 == n[t] && exit[t] < std::numeric_limits<float>::infinity() ? exit[t] : s.dist[k];
  }
};

// recv[l * recv_stride + t]: receiver t's height in level l. contiguous: xs[t] == xs[0] + t (enables the
// shared-fraction loads; otherwise every receiver is gathered, with the same arithmetic and bits).
void march_row(const MarchSetup& s, const Pyramid& heights, const int* xs, int cnt, bool contiguous, int j,
               float cx, float cy, const float* recv, int recv_stride, RowMarch& out);
// fast_atan of every knot slope (k < max_n) in place.
void row_angles(RowMarch& r, int cnt);
// Per receiver, the largest knot slope's angle (the knots horizon), or `none` where n[t] == 0: out[t].
void row_knot_max(const RowMarch& r, int cnt, float* out);

// B-spline curve of the knots at knots and midpoints: out[2k] at knot k, out[2k + 1] between k and k + 1.
// Returns 2n - 1 (0 when n == 0).
inline float bspline_knot(const float* w, int n, int k) {
  const float a = w[k > 0 ? k - 1 : 0], b = w[k], c = w[k + 1 < n ? k + 1 : n - 1];
  return (a + 4 * b + c) * (1.0f / 6);
}
inline float bspline_mid(const float* w, int n, int k) {  // between k and k + 1 (k + 1 < n)
  const float a = w[k > 0 ? k - 1 : 0], b = w[k], c = w[k + 1], d = w[k + 2 < n ? k + 2 : n - 1];
  return (a + 23 * b + 23 * c + d) * (1.0f / 48);
}
inline int bspline_curve(const float* w, int n, float* out) {
  if (n <= 0) return 0;
  if (n < 4) {
    for (int k = 0; k < n; ++k) {
      out[2 * k] = bspline_knot(w, n, k);
      if (k + 1 < n) out[2 * k + 1] = bspline_mid(w, n, k);
    }
    return 2 * n - 1;
  }
  out[0] = bspline_knot(w, n, 0);
  out[1] = bspline_mid(w, n, 0);
  for (int k = 1; k + 2 < n; ++k) {  // interior: no clamping
    out[2 * k] = (w[k - 1] + 4 * w[k] + w[k + 1]) * (1.0f / 6);
    out[2 * k + 1] = (w[k - 1] + 23 * w[k] + 23 * w[k + 1] + w[k + 2]) * (1.0f / 48);
  }
  out[2 * n - 4] = bspline_knot(w, n, n - 2);
  out[2 * n - 3] = bspline_mid(w, n, n - 2);
  out[2 * n - 2] = bspline_knot(w, n, n - 1);
  return 2 * n - 1;
}

// The maximum of bspline_curve(w, n) (n >= 1), bit for bit, evaluating only the curve points near the
// largest knots: every curve point is a convex combination of at most 4 consecutive knots, so (up to a few
// ulps of rounding, covered by the margin) it cannot exceed the largest of them; points whose knots all lie
// below the curve's value at the largest knot, minus the margin, cannot be the maximum.
inline float bspline_max(const float* w, int n) {
  int km = 0;
  for (int k = 1; k < n; ++k)
    if (w[k] > w[km]) km = k;
  float best = bspline_knot(w, n, km);
  const float thr = best - 4e-6f;
  for (int k = 0; k < n; ++k) {
    if (!(w[k] >= thr)) continue;
    // Curve points whose support contains knot k: knots k-1..k+1, midpoints k-2..k+1.
    for (int q = k - 1; q <= k + 1; ++q)
      if (q >= 0 && q < n) best = std::max(best, bspline_knot(w, n, q));
    for (int q = k - 2; q <= k + 1; ++q)
      if (q >= 0 && q + 1 < n) best = std::max(best, bspline_mid(w, n, q));
  }
  return best;
}

// omega_min along azimuth (cx, cy) for normal n: the elevation of the tangent plane in that vertical plane,
// atan2(-(n . d), n_z). (NS09 writes -asin(n . d), equal only along and across the slope.)
inline float omega_min(float nx, float ny, float nz, float cx, float cy) {
  return std::atan2(-(nx * cx + ny * cy), nz);
}

}  // namespace hfbake::nlp
