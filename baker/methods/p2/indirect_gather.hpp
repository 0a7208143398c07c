// Indirect light from the visible stretches of one line (P2 §10.1, method 3: exact per-point gathering).
//
// A receiver R looks along the line towards the azimuth phi_k (unit horizontal vector a). The terrain it
// sees in that direction covers the elevations between its nearest sample and its global horizon; each
// elevation e belongs to the first sample stretch the ray hits. The wedge of azimuths
// [phi_k - D/2, phi_k + D/2], D = 2 pi / K, with the constant-azimuth elevation profile, weighs an
// elevation interval [e0, e1] by
//     W(e0, e1) = F(e1) - F(e0),
//     F(e) = D n_p (e + sin e cos e) / 2 + D n_z sin^2(e) / 2,   n_p = n . a,
// the integral of (n . w) over the wedge's solid angle, with the azimuthal integral of n_p by the
// midpoint rule (D instead of 2 sin(D/2)) exactly like P1 (p1.hpp), so that P1's sky part and this
// terrain part add up to the same cosine lobe (a plane of any slope gives 1). With t = tan e (a slope):
//     F = D n_p (atan t + t / (1 + t^2)) / 2 + D n_z t^2 / (2 (1 + t^2)).
// Directions below the receiver's tangent plane (t < t_n = -n_p / n_z) are clipped. The contribution of
// direction k to E / pi at R is (1/pi) * sum over visible segments of L_segment * W(segment), where
//   * a fully visible segment between samples j and j+1 has the mean of their exit radiances,
//   * the partially visible segment at the end of a stretch (down to the next horizon's line of sight)
//     has the radiance at the middle of its visible part (linear along the segment),
//   * below the nearest sample, down to the tangent plane, the ray meets the receiver's own surface
//     (a crease): radiance L(R).
// These intervals tile [t_n, global horizon] exactly, so a uniform L gives L * (1 - sky part): the
// white-furnace identity direct + indirect = 1 holds up to P1's own integration of the sky part.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "core/vec.hpp"
#include "methods/p1/fast_math.hpp"
#include "methods/p2/hull_tree.hpp"

namespace hfbake {

// 1 when the sign bit of v is set, else 0.
inline float sign_bit(float v) {
  return float(std::bit_cast<std::uint32_t>(v) >> 31);
}

// Per receiver and direction.
struct WedgeWeights {
  double a_p = 0;  // D n_p
  double a_z = 0;  // D n_z
  double t_n = 0;  // tangent-plane slope in the look direction, -n_p / n_z

  // n: the receiver's unit normal (n_z > 0); look: unit horizontal look direction; wedge: D.
  static WedgeWeights make(Vec3 n, double look_x, double look_y, double wedge) {
    WedgeWeights w;
    const double np = n.x * look_x + n.y * look_y, nz = std::max(n.z, 1e-9);
    w.a_p = wedge * np;
    w.a_z = wedge * nz;
    w.t_n = -np / nz;
    return w;
  }
  // F at world slope t (see the header comment). atan by P1's fast_atan (error < 4e-8 rad, far below the
  // method's error; the weights of adjacent intervals share their F values, so they still tile exactly).
  double F(double t) const {
    const double q = 1 / (1 + t * t);
    return 0.5 * (a_p * (double(p1::fast_atan(float(t))) + t * q) + a_z * t * t * q);
  }
  // F at n slopes in single precision (a branch-free loop the compiler vectorises; gather_stretches).
  // Relative error about 1e-7 of the wedge's lobe: far below the method's error, and the intervals
  // still tile exactly since adjacent ones share their boundary values.
  // n is rounded up to a multiple of 4 (t and out must have room; the extra inputs are read as they are),
  // so the whole loop runs in vector lanes.
  void F_many(const float* __restrict t, float* __restrict out, int n) const {
    const float hp = float(0.5 * a_p), hz = float(0.5 * a_z);
    const int n4 = (n + 3) & ~3;
    for (int i = 0; i < n4; ++i) {
      // atan(x) as p1::fast_atan (the same reduction and series), with the selects written as
      // arithmetic so that the loop has no control flow and vectorises.
      // (Comparisons as sign bits: GCC keeps a branch for a float compare under -ftrapping-math.)
      const float x = t[i], x2 = x * x, q = 1.0f / (1.0f + x2);
      const float a = std::fabs(x), swap = sign_bit(1.0f - a), neg = sign_bit(x);  // swap: a > 1
      const float lo = a * (1 - swap) + swap, hi = a * swap + (1 - swap);          // min, max(a, 1)
      const float big = sign_bit(0.41421356f * hi - lo);                           // lo > tan(pi/8) hi
      const float num = lo - big * hi, den = hi + big * lo;
      float r = p1::atan_small(num / den) + big * p1::kQuarterPiF;
      r += swap * (p1::kHalfPiF - 2 * r);
      r *= 1 - 2 * neg;
      out[i] = hp * (r + x * q) + hz * x2 * q;
    }
  }
};

// (1/pi) * the sum over the visible segments of L_segment * W(segment) for receiver r of a line: its E/pi
// from direction k. h: sample heights (world units), L: exit radiance per sample, r: the receiver (an
// index into h and L), terrain_end: samples 0..terrain_end-1 are the terrain behind it (terrain_end <= r;
// equal to r except for receivers beyond a clamp field's border), horizons: the starts of the visible
// runs (run_starts), inv_step: 1 / (world distance between samples).
// weight (optional) receives (1/pi) * the sum of the W(segment): the terrain part of the wedge's cosine
// lobe, (F(global horizon) - F(t_n)) / pi when the horizon is above the tangent plane, else 0.
// inv_dist (optional): inv_dist[d] = inv_step / d for d >= 1 (a per-line table that saves a division per
// visible sample).
// Scratch of gather_stretches (grown on demand; keep one per thread and line to avoid allocation): the
// visible elevation intervals are collected first (their boundary slopes and radiances, a branchy walk)
// and their weights evaluated afterwards in a branch-free loop.
struct GatherScratch {
  std::vector<float> t;  // interval boundaries (world slopes), descending
  std::vector<float> F;  // F at the boundaries
  std::vector<Rgb> L;    // radiance per interval
  void reserve(std::size_t points) {
    points += 3;  // F_many's rounding up to whole vectors
    if (t.size() < points) t.resize(points), F.resize(points), L.resize(points);
  }
};

Rgb gather_stretches(const double* h, const Rgb* L, int r, int terrain_end, std::span<const int> horizons,
                     double inv_step, const WedgeWeights& w, double* weight = nullptr,
                     const double* inv_dist = nullptr, GatherScratch* scratch = nullptr);

// The exit radiance of a line given per segment instead of per sample: segment j runs from sample j to
// sample j+1 and radiates mean[j] + slope[j] * (u - 1/2) at its parameter u in [0, 1] (u = 0 at sample j),
// so that its visible part [0, u] has the mean radiance mean[j] + slope[j] * (u - 1) / 2. crease: the
// radiance the receiver sees below its nearest sample (its own surface). Per-sample radiance L is the
// special case mean = (L_j + L_j+1) / 2, slope = L_j+1 - L_j, crease = L_r (gather_stretches above).
// has_crease = false: the elevations below the nearest terrain sample are not gathered at all (a far-field
// gather over the samples 0..terrain_end-1 only; the texel's exact near field covers the rest).
struct SegmentRadiance {
  const Rgb* mean = nullptr;
  const Rgb* slope = nullptr;
  Rgb crease;
  bool has_crease = true;
};

// x (optional): the samples' positions in steps of 1 / inv_step world units (increasing; null: sample j at
// j). Then inv_dist is not read: distances are x[r] - x[j].
// horizon_slopes (optional): visibility_slope(h, x, horizons[k], r) for every k (the hull tree's numbers,
// run_starts' out_slopes), read instead of computed again.
Rgb gather_segments(const double* h, const SegmentRadiance& L, int r, int terrain_end,
                    std::span<const int> horizons, double inv_step, const WedgeWeights& w,
                    double* weight = nullptr, const double* inv_dist = nullptr,
                    GatherScratch* scratch = nullptr, const double* x = nullptr,
                    const double* horizon_slopes = nullptr);

// (F(e) - F(e_t)) / pi for the wedge of direction phi (cos_phi, sin_phi) of K, normal n, horizon elevation e
// (radians): the part of the cosine lobe between the tangent plane and the horizon, in the form of P1's
// per-direction sky term, so that the two add up to P1's lobe (p1.hpp).
// The same with the horizon's sine and cosine given (se = sin e, ce = cos e).
inline double terrain_weight(Vec3 n, double cos_phi, double sin_phi, int K, double e, double se, double ce) {
  const double np = n.x * cos_phi + n.y * sin_phi, nz = n.z;
  const double inv = 1 / (np * np + nz * nz);
  const double et = -double(p1::fast_atan(float(np / nz)));  // tangent plane elevation (n_z > 0)
  if (!(e > et)) return 0;
  // cos^2 e_t = nz^2 / (np^2 + nz^2), sin e_t cos e_t = -np nz / (np^2 + nz^2)
  return (np * (e - et + se * ce + np * nz * inv) + nz * (nz * nz * inv - ce * ce)) / K;
}

inline double terrain_weight(Vec3 n, double cos_phi, double sin_phi, int K, double e) {
  float sf, cf;
  p1::fast_sincos(float(e), sf, cf);
  return terrain_weight(n, cos_phi, sin_phi, K, e, sf, cf);
}

// The horizons that start a visible run: the tree's root children minus a permanent leaf whose farther
// neighbour is visible too (the only kind of redundant root child). Filters `horizons` into `out`.
void run_starts(const double* h, int r, std::span<const int> horizons, std::vector<int>& out,
                const double* x = nullptr);
// The same from the horizons' slopes seen from r (HullTree::horizon_slopes, HullTree::query): the kept
// horizons to out and their slopes to out_slopes (room for m each); returns their count. One slope is
// computed per horizon (its farther neighbour's) instead of two.
int run_starts(const double* h, int r, const int* horizons, const double* slopes, int m, int* out,
               double* out_slopes, const double* x = nullptr);

// The same from the naive visible set (increasing indices).
void run_starts_of_visible(std::span<const int> visible, std::vector<int>& out);

}  // namespace hfbake
