// The P1 per-line visitor for the shared sweep driver (sweep/sweep_lines.hpp): the convex-hull stack of
// Algorithm 1 run over a line's terrain samples, and the exact near field each texel marches itself.
//
// How a texel's horizon is formed (near / far split; measured in tests/p1/measure_p1.cpp and the closing
// note): the sweep's receivers lie on the texel's column up to one texel aside (two lines blended), and the
// surface between columns has kinks (row and diagonal crossings of the reference's triangulation) that
// the column samples miss. Both errors live almost entirely in the first texels along the ray, so:
// * near field (distance <= near radius R, texels): marched exactly from the texel center itself over
//   every column, row and diagonal crossing of the ray (points on triangle edges: exact heights of the
//   triangulated surface, which agrees with the bilinear one on cell edges). The crossings are the same
//   for every texel of a direction (near_field_stencil), so this is a fixed stencil per direction.
// * far field (distance >= R): the line worker's hull stack lags R behind each receiver, so a receiver
//   gets the steepest caster among the samples at least R away ([dz above the sample, run]); the texel
//   visitor sees that caster from the texel (far_elevation: the tap's height above the texel's plane,
//   with a minmod gradient, is added to the caster's) and blends the two taps; the horizon of each tap
//   is the larger of the near and the far elevation.
// With far_radius = 0 the worker gives each receiver its overall caster, as Algorithm 1.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "methods/p1/fast_math.hpp"
#include "methods/p1/hull_stack.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake::p1 {

// Elevation of a caster dz above a sample at horizontal distance run (+inf: nothing behind: -pi/2).
inline float caster_elevation(float dz, float run) {
  return run == std::numeric_limits<float>::infinity() ? -kHalfPiF : fast_atan2_pos(dz, run);
}
// A tap's far caster seen from the texel: the tap sample lies `lift` above the texel's tangent plane
// (z_sample - z_texel - grad h . offset), so the caster rises dz + lift above the texel at the same run.
// -pi/2 when nothing lies behind.
inline float far_elevation(float dz, float run, float lift) {
  const float e = fast_atan2_pos(dz + lift, run);
  return run == std::numeric_limits<float>::infinity() ? -kHalfPiF : e;
}

// Samples a receiver's far caster must lie behind it: the smallest count whose distance is >= radius.
inline int far_lag(double radius, double step) {
  if (radius <= 0) return 0;
  return std::max(1, int(std::ceil(radius / step - 1e-9)));
}

struct HorizonLineWorker {
  HullStack stack;
  double far_radius = 0;  // world units; 0: every sample casts (Algorithm 1), else only those >= it behind

  static constexpr int channels() { return 2; }

  void operator()(const SweepLine& line, float* out) {
    stack.reset(line.count);
    const float step = float(line.step);
    const bool has_terrain = line.inside_end > line.inside_begin;
    auto mark = [&](int n0, int n1) {
      for (int n = std::max(n0, line.first_receiver); n < n1; ++n) {
        float* o = out + std::size_t(n - line.first_receiver) * 2;
        o[0] = 0.0f;
        o[1] = std::numeric_limits<float>::infinity();
      }
    };
    mark(0, has_terrain ? line.inside_begin : line.count);
    if (!has_terrain) return;
    mark(line.inside_end, line.count);
    const int lag = far_lag(far_radius, line.step);
    if (lag == 0) {
      for (int n = line.inside_begin; n < line.inside_end; ++n) {
        const HorizonCaster c = stack.add(n, line.z[n]);
        if (n < line.first_receiver) continue;
        write(out + std::size_t(n - line.first_receiver) * 2, c, step);
      }
      return;
    }
    // The stack holds the terrain samples at least `lag` behind the receiver (the hull of a prefix).
    int fed = line.inside_begin;
    for (int n = std::max(line.inside_begin, line.first_receiver); n < line.inside_end; ++n) {
      for (; fed <= n - lag; ++fed) stack.add(fed, line.z[fed]);
      write(out + std::size_t(n - line.first_receiver) * 2, stack.query(n, line.z[n]), step);
    }
  }

 private:
  static void write(float* o, const HorizonCaster& c, float step) {
    o[0] = float(c.dz);
    o[1] = c.n < 0 ? std::numeric_limits<float>::infinity() : float(c.dn) * step;
  }
};

// One crossing of a direction's ray from a texel center with a column, row or diagonal of the
// triangulation, within the near radius: its height is (1 - w) z[texel + a] + w z[texel + b].
struct NearCrossing {
  int ai = 0, aj = 0, bi = 0, bj = 0;  // texel offsets of the edge's end points
  float w = 0;                         // weight of b
  float x = 0, y = 0;                  // the crossing relative to the texel center (texels)
  float inv_s = 0;                     // 1 / horizontal world distance
};

// The crossings of the ray from (0, 0) towards (dx, dy) with x = int, y = int and x + y = int (the
// reference's quad split, (i+1, j)-(i, j+1)) at distances 0 < s <= radius texels, ordered by s.
std::vector<NearCrossing> near_field_stencil(double dx, double dy, double radius, double texel_size);

}  // namespace hfbake::p1
