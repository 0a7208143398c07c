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
//   caster among the line's points at least R away). Before issue 19 compute_p1 lifted each tap's caster
//   by the tap's height above the texel's plane and blended the two taps: wrong on terrain rough at the
//   texel scale (the neighbour line's caster is not on the texel's ray). compute_p1 now runs
//   RayLineWorker: the hull only guides, and the texel's own ray is evaluated exactly (see there).
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
    // Per step the minor coordinate v moves by dv = su * slope and w = u + v by dw = su * (1 + slope).
    const double dv = d.su * d.slope, dw = d.su * (1 + d.slope);
    const double inv_dv = dv != 0 ? 1 / dv : 0, inv_dw = dw != 0 ? 1 / dw : 0;
    for (int n = line.inside_begin; n < line.inside_end; ++n) {
      pos.push_back(n), z.push_back(line.z[n]);
      if (n + 1 >= line.inside_end) break;
      const int u0 = d.u(n);
      const double v0 = d.v(line.line, n), v1 = v0 + dv, w0 = u0 + v0, w1 = w0 + dw;
      double cs[3];
      float cz[3];
      int m = 0;
      // Row crossings: v integer strictly between v0 and v1 (at most one: |slope| <= 1).
      if (dv != 0) {
        const int k = dv > 0 ? floor_int(v0) + 1 : -floor_int(-v0) - 1;  // the next integer beyond v0
        if (dv > 0 ? k < v1 : k > v1) {
          const double t = (k - v0) * inv_dv;  // fraction of the step
          const double u = u0 + d.su * t;
          const int fu = floor_int(u);
          const float a = at(fu, k), b = at(fu + 1, k);
          cs[m] = n + t, cz[m] = float(a + (b - a) * (u - fu)), ++m;
        }
      }
      // Diagonal crossings: u + v integer strictly between w0 and w1 (at most two).
      if (dw != 0) {
        for (int k = dw > 0 ? floor_int(w0) + 1 : -floor_int(-w0) - 1; dw > 0 ? k < w1 : k > w1;
             k += dw > 0 ? 1 : -1) {
          const double t = (k - w0) * inv_dw;
          const double u = u0 + d.su * t, v = k - u;
          const int fv = floor_int(v);
          const int cu = k - fv - 1;  // the cell (cu, fv): its diagonal runs (cu+1, fv)-(cu, fv+1)
          const float a = at(cu + 1, fv), b = at(cu, fv + 1);
          cs[m] = n + t, cz[m] = float(a + (b - a) * (v - fv)), ++m;
        }
      }
      if (m > 1 && cs[1] < cs[0]) std::swap(cs[0], cs[1]), std::swap(cz[0], cz[1]);
      if (m > 2) {
        if (cs[2] < cs[1]) std::swap(cs[1], cs[2]), std::swap(cz[1], cz[2]);
        if (cs[1] < cs[0]) std::swap(cs[0], cs[1]), std::swap(cz[0], cz[1]);
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

// The far field seen from the texel centres themselves (what compute_p1 runs). A receiver sample n of line
// l at (u, v) lies between the texels A = (u, floor v) and B = (u, floor v + 1) of its column, delta_A =
// floor v - v and delta_B = delta_A + 1 texels from it along the minor axis. Each texel's own ray (towards
// phi_k) is the line shifted by its delta: parallel to it, never more than one texel aside. For each of A
// and B the worker queries the line's lagging hull (points >= far_radius behind, as HorizonLineWorker)
// from the texel's own height, and evaluates the texel's ray itself on the reference's triangulated
// surface (every column, row and diagonal crossing, exact heights) in a window of `half_window` steps
// around the supporting hull vertex and its `neighbours` hull neighbours on either side: the steepest of
// those points is the texel's far caster. Every point evaluated lies on the texel's ray, so the result
// never exceeds the exact horizon; it equals it when the ray's caster lies in a window (the two lines
// beside a texel see the same crests, a little shifted). A texel on the line (delta 0: the axis and
// diagonal directions) takes the hull's caster itself (exact).
// Per receiver: [dz_A, run_A, dz_B, run_B] (world units; run +inf: none, or the texel is off a clamp field).
// The texel combines its two lines (compute_p1): B of the line below and A of the line above, the larger.
struct RayLineWorker {
  double far_radius = 0;               // world units (> 0)
  const HeightField* field = nullptr;  // the field the sweep samples (heights of the rays' crossings)
  bool hull_crossings = true;          // the hull also over the line's row and diagonal crossings
  int neighbours = 1;                  // hull vertices each side of the supporting one whose windows count
  double half_window = 1.0;            // steps each side of a vertex whose ray crossings are evaluated
  double flat_tolerance = 0.003;       // see operator()

  static constexpr int channels() { return 4; }

  void operator()(const SweepLine& line, float* out) {
    const float inf = std::numeric_limits<float>::infinity();
    for (int n = line.first_receiver; n < line.count; ++n) {
      float* o = out + std::size_t(n - line.first_receiver) * 4;
      o[0] = 0.0f, o[1] = inf, o[2] = 0.0f, o[3] = inf;
    }
    if (line.inside_end <= line.inside_begin) return;
    const SweepDirection& d = *line.dir;
    const HeightField& f = *field;
    if (hull_crossings) {
      HorizonLineWorker pts;
      pts.crossings = field;
      pts.terrain_points(line, pos_, pz_);
    } else {
      pos_.clear(), pz_.clear();
      for (int n = line.inside_begin; n < line.inside_end; ++n) pos_.push_back(n), pz_.push_back(line.z[n]);
    }
    // clamp: where the line leaves the field through a side, the surface goes on to the border within the
    // step past the last sample on the field; its row and diagonal crossings there (the border point among
    // them) are terrain too.
    if (f.wrap == Wrap::clamp) {
      auto partial = [&](int m, std::vector<double>& ps, std::vector<float>& zs) {
        Window w{line, d, f, 0.0, 0.0f, line.count + 1, true};
        w.points = &ps, w.heights = &zs;
        const double v0 = line.line + d.u_start * d.slope, dvs = d.su * d.slope;
        w.family(v0, dvs, m + 1e-9, m + 1 - 1e-9);
        w.family(v0 + d.u_start, dvs + d.su, m + 1e-9, m + 1 - 1e-9);
        for (std::size_t a = 1; a < ps.size(); ++a)  // at most three, by position
          for (std::size_t b = a; b > 0 && ps[b] < ps[b - 1]; --b)
            std::swap(ps[b], ps[b - 1]), std::swap(zs[b], zs[b - 1]);
      };
      if (line.inside_begin > 0) {
        std::vector<double> ps;
        std::vector<float> zs;
        partial(line.inside_begin - 1, ps, zs);
        pos_.insert(pos_.begin(), ps.begin(), ps.end());
        pz_.insert(pz_.begin(), zs.begin(), zs.end());
      }
      if (line.inside_end < line.count) {
        std::vector<double> ps;
        std::vector<float> zs;
        partial(line.inside_end - 1, ps, zs);
        pos_.insert(pos_.end(), ps.begin(), ps.end());
        pz_.insert(pz_.end(), zs.begin(), zs.end());
      }
    }
    stack_.reset(int(pos_.size()));
    const double reach = far_radius / line.step;
    const bool clamp = f.wrap == Wrap::clamp;
    const int nv = d.x_major ? f.height : f.width;
    const double dv = d.su * d.slope;  // minor coordinate per step
    std::size_t fed = 0;
    for (int n = std::max(line.inside_begin, line.first_receiver); n < line.inside_end; ++n) {
      for (; fed < pos_.size() && pos_[fed] <= n - reach + 1e-9; ++fed) stack_.add(pos_[fed], pz_[fed]);
      float* o = out + std::size_t(n - line.first_receiver) * 4;
      if (stack_.size() == 0) continue;
      const int u = d.u(n);
      const double v = d.v(line.line, n);
      const int fl = floor_int(v);
      for (int slot = 0; slot < 2; ++slot) {
        const int vt = fl + slot;
        if (clamp && (vt < 0 || vt >= nv)) continue;
        const float zt = d.x_major ? f.at(u, vt) : f.at(vt, u);
        const double delta = double(vt) - v;
        int q = stack_.query_index(n, zt);
        // clamp: the ray is on the field from position p_on on (up to its receiver); hull vertices
        // before it (where the line is still on the field) cast nothing on it: the first vertex at or after
        // p_on guides instead, with a window at p_on itself.
        double p_on = -1e300;
        if (clamp && dv != 0) {
          const double a = line.line + d.u_start * d.slope + delta;
          p_on = (dv > 0 ? -a : nv - 1 - a) / dv - 1e-9;
        }
        const bool shifted = stack_.position(q) < p_on;
        while (q + 1 < stack_.size() && stack_.position(q) < p_on) ++q;
        double best_dz = 0, best_run = 0;
        bool any = false;
        if (delta == 0 && !shifted) {  // the texel's ray is the line: the hull's caster is exact
          best_dz = double(stack_.height(q)) - zt, best_run = (n - stack_.position(q)) * line.step,
          any = true;
        } else {
          Window w{line, d, f, delta, zt, n, clamp};
          // The ray's own point beside the supporting vertex first: where it lies within `flat_tolerance`
          // (in slope seen from the texel) of the vertex, the terrain across the two is smooth at this
          // scale and the ray's caster is the vertex's neighbour (first order), so that point is taken.
          if (!shifted) {
            const double pq = stack_.position(q);
            w.consider(pq);
            const double rq = (n - pq) * line.step;
            if (w.any && std::fabs(w.dz + zt - stack_.height(q)) <= flat_tolerance * rq) {
              o[2 * slot] = float(w.dz), o[2 * slot + 1] = float(w.run);
              continue;
            }
          }
          if (shifted) w.scan(p_on, p_on + half_window);
          const int c0 = std::max(0, q - neighbours), c1 = std::min(stack_.size() - 1, q + neighbours);
          double lo = -1e300, hi = -1e300;  // merge overlapping windows (hull positions increase with c)
          for (int c = c0; c <= c1; ++c) {
            const double a = std::max(stack_.position(c) - half_window, p_on),
                         b = stack_.position(c) + half_window;
            if (a > hi) {
              if (hi > lo) w.scan(lo, hi);
              lo = a;
            }
            hi = std::max(hi, b);
          }
          if (hi > lo) w.scan(lo, hi);
          any = w.any, best_dz = w.dz, best_run = w.run;
        }
        if (any) o[2 * slot] = float(best_dz), o[2 * slot + 1] = float(best_run);
      }
    }
  }

 private:
  // The crossings of one texel's ray in a range of positions, and the steepest of them seen from it.
  struct Window {
    const SweepLine& line;
    const SweepDirection& d;
    const HeightField& f;
    double delta;
    float zt;
    int n;
    bool clamp;
    bool any = false;
    double dz = 0, run = 0;

    std::vector<double>* points = nullptr;  // if set: collect the points on the field instead
    std::vector<float>* heights = nullptr;

    void consider(double p) {
      if (!(p < n)) return;
      const double uu = d.u_start + d.su * p, vv = line.line + uu * d.slope + delta;
      double x = d.x_major ? uu : vv, y = d.x_major ? vv : uu;
      if (clamp) {
        if (x < -1e-9 || y < -1e-9 || x > f.width - 1 + 1e-9 || y > f.height - 1 + 1e-9) return;
        x = std::clamp(x, 0.0, double(f.width - 1)), y = std::clamp(y, 0.0, double(f.height - 1));
      }
      if (points) {
        points->push_back(p), heights->push_back(f.triangle_height(x, y));
        return;
      }
      float h;
      if (x >= 1 && y >= 1 && x <= f.width - 3 && y <= f.height - 3) {  // inside: no clamp or wrap
        const int i = floor_int(x), j = floor_int(y);
        const float tx = float(x - i), ty = float(y - j);
        const float* Z = f.z.data() + f.index(i, j);
        if (tx + ty <= 1)
          h = Z[0] + (Z[1] - Z[0]) * tx + (Z[f.width] - Z[0]) * ty;
        else
          h = Z[f.width + 1] + (Z[f.width] - Z[f.width + 1]) * (1 - tx) + (Z[1] - Z[f.width + 1]) * (1 - ty);
      } else {
        h = f.triangle_height(x, y);
      }
      const double z = double(h) - zt, r = (n - p) * line.step;
      if (!any || z * run > dz * r) dz = z, run = r, any = true;
    }
    // Positions p in [p0, p1] where a + b p is an integer.
    void family(double a, double b, double p0, double p1) {
      if (b == 0) return;
      const double w0 = a + b * p0, w1 = a + b * p1;
      const double lo = std::min(w0, w1), hi = std::max(w0, w1);
      for (double k = std::ceil(lo); k <= hi; k += 1) consider((k - a) / b);
    }
    void scan(double p0, double p1) {
      p0 = std::max(p0, 0.0), p1 = std::min(p1, double(n) - 1e-9);
      if (p1 < p0) return;
      const double v0 = line.line + d.u_start * d.slope + delta, dv = d.su * d.slope;
      if (!points && scan_inside(p0, p1, v0, dv)) return;
      for (double p = std::ceil(p0); p <= p1; p += 1) consider(p);  // columns
      family(v0, dv, p0, p1);                                       // rows
      family(v0 + d.u_start, dv + d.su, p0, p1);                    // diagonals
    }
    // scan() where the window and its cells lie inside the field (no clamping, no wrapping): the same
    // points (columns, rows, diagonals) with their heights read straight from the field's array, in
    // (u, v) coordinates. Returns false (nothing done) elsewhere.
    bool scan_inside(double p0, double p1, double v0, double dv) {
      const double ua = d.u_start + d.su * p0, ub = d.u_start + d.su * p1;
      const double va = v0 + dv * p0, vb = v0 + dv * p1;
      const int nu = d.x_major ? f.width : f.height, nv = d.x_major ? f.height : f.width;
      if (std::min(ua, ub) < 1 || std::max(ua, ub) > nu - 3 || std::min(va, vb) < 1 ||
          std::max(va, vb) > nv - 3)
        return false;
      const float* Z = f.z.data();
      const std::ptrdiff_t su_s = d.x_major ? 1 : f.width, sv_s = d.x_major ? f.width : 1;
      auto at = [&](int uu, int vv) { return Z[uu * su_s + vv * sv_s]; };
      auto take = [&](double p, float z) {
        const double dzz = double(z) - zt, r = (n - p) * line.step;
        if (!any || dzz * run > dz * r) dz = dzz, run = r, any = true;
      };
      // Columns: p integer, u integer, v on the column edge.
      for (int k = -floor_int(-p0), k1 = floor_int(p1); k <= k1; ++k) {
        const int uu = d.u_start + d.su * k;
        const double v = v0 + dv * k;
        const int fv = floor_int(v);
        const float a = at(uu, fv), b = at(uu, fv + 1);
        take(k, a + (b - a) * float(v - fv));
      }
      // Rows: v integer, on the row edge between columns floor u and floor u + 1.
      if (dv != 0) {
        const double lo = std::min(va, vb), hi = std::max(va, vb), inv = 1 / dv;
        for (int k = -floor_int(-lo), k1 = floor_int(hi); k <= k1; ++k) {
          const double p = (k - v0) * inv, u = d.u_start + d.su * p;
          const int fu = floor_int(u);
          const float a = at(fu, k), b = at(fu + 1, k);
          take(p, a + (b - a) * float(u - fu));
        }
      }
      // Diagonals: u + v integer, on the diagonal (fu + 1, fv)-(fu, fv + 1) of cell (fu, fv).
      const double dw = d.su + dv;
      if (dw != 0) {
        const double w0 = v0 + d.u_start, wa = ua + va, wb = ub + vb, inv = 1 / dw;
        const double lo = std::min(wa, wb), hi = std::max(wa, wb);
        for (int k = -floor_int(-lo), k1 = floor_int(hi); k <= k1; ++k) {
          const double p = (k - w0) * inv, u = d.u_start + d.su * p, v = k - u;
          const int fv = floor_int(v), cu = k - fv - 1;
          const float a = at(cu + 1, fv), b = at(cu, fv + 1);
          take(p, a + (b - a) * float(v - fv));
        }
      }
      return true;
    }
  };

  HullStackF stack_;
  std::vector<double> pos_;
  std::vector<float> pz_;
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
