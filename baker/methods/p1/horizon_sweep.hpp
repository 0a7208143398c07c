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
// * far field (distance >= R): HorizonLineWorker's hull stack lags R behind each receiver (the steepest
//   caster among the line's points at least R away). A neighbour line's caster is not on the texel's ray
//   (on terrain rough at the texel scale it can be far off), so compute_p1 runs FarHorizonWorker
//   (far_horizons.hpp) instead: the texel's own ray, searched exactly within its strip's hull.
// With far_radius = 0 the worker gives each receiver its overall caster, as Algorithm 1.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "field/edge_crossings.hpp"
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

// The triangulation's edge that a line's step crosses at `e` (edge_crossings in field coordinates; the
// major axis' integers are the line's samples, so e is a minor-axis integer or a diagonal), u the major
// coordinate of the crossing: its texels (ua, va) and (ub, vb) in (major, minor) coordinates, the weight w of
// b, and the crossing's minor coordinate v. Diagonal u + v = m: the edge (cu + 1, fv)-(cu, fv + 1) of cell
// (cu, fv), the field's split.
struct LineEdge {
  int ua, va, ub, vb;
  double w, v;
};
inline LineEdge line_edge(const EdgeCrossing& e, double u) {
  if (e.family == EdgeFamily::diagonal) {
    const double v = e.m - u;
    const int fv = floor_int(v), cu = e.m - fv - 1;
    return {cu + 1, fv, cu, fv + 1, v - fv, v};
  }
  const int fu = floor_int(u);
  return {fu, e.m, fu + 1, e.m, u - fu, double(e.m)};
}

struct HorizonLineWorker {
  HullStack stack;
  double far_radius = 0;  // world units; 0: every sample casts (Algorithm 1), else only those >= it behind
  // With far_radius > 0: also the points where the line crosses rows and the quads' diagonals (the kinks
  // of the reference's triangulated surface between columns; heights from this field) are occluders.
  const HeightField* crossings = nullptr;

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
    if (crossings) {
      with_crossings(line, out);
      return;
    }
    // The stack holds the terrain samples at least `lag` behind the receiver (the hull of a prefix).
    int fed = line.inside_begin;
    for (int n = std::max(line.inside_begin, line.first_receiver); n < line.inside_end; ++n) {
      for (; fed <= n - lag; ++fed) stack.add(fed, line.z[fed]);
      write(out + std::size_t(n - line.first_receiver) * 2, stack.query(n, line.z[n]), step);
    }
  }

  // The terrain points of a line with its row and diagonal crossings: positions in steps from sample 0
  // (column samples at integers), heights; exposed for the exactness test.
  void terrain_points(const SweepLine& line, std::vector<double>& pos, std::vector<float>& z) const {
    pos.clear(), z.clear();
    const SweepDirection& d = *line.dir;
    const HeightField& f = *crossings;
    const bool wrap = f.wrap == Wrap::repeat;
    // Heights at (major, minor) texel coordinates. A clamp line's crossings between two samples on the
    // field lie on the field, but an edge's far corner can be one texel off it (a crossing on the border
    // row or column, weight 0 on that corner): clamped like HeightField::at (AddressSanitizer found the
    // read one row before the field).
    const float* Z = f.z.data();
    const std::ptrdiff_t su_stride = d.x_major ? 1 : f.width, sv_stride = d.x_major ? f.width : 1;
    const int nu = d.x_major ? f.width : f.height, nv = d.x_major ? f.height : f.width;
    auto at = [&](int uu, int vv) {
      if (wrap) return d.x_major ? f.at(uu, vv) : f.at(vv, uu);
      uu = uu < 0 ? 0 : (uu >= nu ? nu - 1 : uu);
      vv = vv < 0 ? 0 : (vv >= nv ? nv - 1 : vv);
      return Z[uu * su_stride + vv * sv_stride];
    };
    for (int n = line.inside_begin; n < line.inside_end; ++n) {
      pos.push_back(n), z.push_back(line.z[n]);
      if (n + 1 >= line.inside_end) break;
      const int u0 = d.u(n), u1 = d.u(n + 1);
      const double v0 = d.v(line.line, n), v1 = d.v(line.line, n + 1);
      // The step's crossings with the triangulation's edges (field/edge_crossings.hpp, field coordinates):
      // the minor axis' integers and the diagonals; the major axis' integers are the samples.
      EdgeCrossing e[kMaxEdgeCrossings];
      const int m = d.x_major ? edge_crossings(u0, v0, u1, v1, e) : edge_crossings(v0, u0, v1, u1, e);
      double cs[kMaxEdgeCrossings];
      float cz[kMaxEdgeCrossings];
      for (int c = 0; c < m; ++c) {
        const LineEdge g = line_edge(e[c], u0 + d.su * e[c].t);
        const float a = at(g.ua, g.va), b = at(g.ub, g.vb);
        cs[c] = n + e[c].t, cz[c] = float(a + (b - a) * g.w);
      }
      // A crossing on or below the chord of its neighbours (a valley kink) is never on the upper hull:
      // left out (it is inside the hull of the points kept, so no horizon changes).
      for (int c = 0; c < m; ++c) {
        if (!(cs[c] > n && cs[c] < n + 1)) continue;
        const double ps = pos.back(), pzv = z.back();
        const double ns = c + 1 < m ? cs[c + 1] : n + 1, nzv = c + 1 < m ? cz[c + 1] : line.z[n + 1];
        if ((double(cz[c]) - pzv) * (ns - ps) <= (nzv - pzv) * (cs[c] - ps)) continue;
        pos.push_back(cs[c]), z.push_back(cz[c]);
      }
    }
  }

 private:
  HullStackF fstack;
  std::vector<double> pos_;
  std::vector<float> pz_;

  void with_crossings(const SweepLine& line, float* out) {
    terrain_points(line, pos_, pz_);
    fstack.reset(int(pos_.size()));
    const double reach = far_radius / line.step;  // in steps
    std::size_t fed = 0;
    for (int n = std::max(line.inside_begin, line.first_receiver); n < line.inside_end; ++n) {
      for (; fed < pos_.size() && pos_[fed] <= n - reach + 1e-9; ++fed) fstack.add(pos_[fed], pz_[fed]);
      const HorizonCasterF c = fstack.query(n, line.z[n]);
      float* o = out + std::size_t(n - line.first_receiver) * 2;
      o[0] = float(c.dz);
      o[1] = c.any ? float(c.dist * line.step) : std::numeric_limits<float>::infinity();
    }
  }

  static void write(float* o, const HorizonCaster& c, float step) {
    o[0] = float(c.dz);
    o[1] = c.any ? float(c.dist) * step : std::numeric_limits<float>::infinity();
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

// The near field's radius in texels for direction d: near_radius, or one line step if that is longer (the
// far field starts at least one step behind each texel: FarHorizonWorker).
inline double near_radius_of(const SweepDirection& d, double near_radius) {
  return std::max(near_radius, d.step / d.texel_size);
}

// Steepest near-field slope (rise / run) from texel (i, j) over `stencil` and its crossing (-1: none; the
// slope is then -1e30), with the border rules (clamp: crossings off the field are not terrain; repeat:
// wrapped). Texels whose crossings are all on the field get the same bits from any loop that takes the
// largest of ((za - z) + (zb - za) w) inv_s over the stencil (the rise first: its rounding is the rise's,
// not the heights').
float near_slope(const HeightField& f, const std::vector<NearCrossing>& stencil, int i, int j, int* which);

// A direction's near field: near_field_stencil at near_radius_of(d, near_radius), and its crossings'
// texels as index offsets from the texel, valid for texels at least `margin` texels inside the field (all
// their crossings on it).
struct NearStencil {
  std::vector<NearCrossing> crossings;
  std::vector<std::ptrdiff_t> a, b;
  int margin = 0;
};
NearStencil near_stencil(const HeightField& f, const SweepDirection& d, double near_radius);
// out[x] = near_slope(f, s.crossings, i0 + x, j, .) for x in [0, w): the interior run by the index
// offsets, one crossing at a time over the run (vectorised), the texels near the border one by one.
void near_slopes_row(const HeightField& f, const NearStencil& s, int i0, int j, int w, float* out);
// The same for one texel (the worker's per-texel call; same bits).
float near_slope_at(const HeightField& f, const NearStencil& s, int i, int j);

}  // namespace hfbake::p1
