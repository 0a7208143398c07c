#include "methods/relief/radius_horizon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hfbake {

namespace {

// The world distance t of the m-th crossing of lines spaced 1 apart along a texel coordinate that changes
// by `rate` per world unit, starting on a line: m / |rate|; +inf when the ray runs along them.
struct Crossings {
  double step = std::numeric_limits<double>::infinity();
  long m = 1;
  explicit Crossings(double rate) {
    if (std::abs(rate) > 1e-12) step = 1 / std::abs(rate);
  }
  double next() const { return double(m) * step; }
};

// The world distance at which the ray x0 + t rate leaves [0, n - 1] (x0 inside): +inf when rate = 0.
double exit_t(double x0, double rate, int n) {
  if (rate > 1e-15) return (n - 1 - x0) / rate;
  if (rate < -1e-15) return x0 / -rate;
  return std::numeric_limits<double>::infinity();
}

// The march, with `height(ci, cj)` the corner heights (direct reads inside the field, wrapped or clamped
// reads near its border); (rx, ry) the texel coordinates' change per world unit along the ray.
template <class Height>
HorizonPair march(const HeightField& field, int i, int j, double rx, double ry, double t_end, double c,
                  Height height) {
  const double z0 = field.z[field.index(i, j)];
  HorizonPair h;
  if (!(t_end > 0)) return h;
  h.up = -std::numeric_limits<double>::infinity();
  h.down = std::numeric_limits<double>::infinity();
  double t_prev = 0, z_prev = z0;
  // Offsets from the texel, not positions in the field: the same bits wherever the texel lies (a tile of a
  // raster bakes the whole raster's texels, docs/large-fields.md).
  auto visit = [&](double t) {
    const double u = t * rx, v = t * ry;
    const double fu = std::floor(u), fv = std::floor(v);
    const int ci = i + int(fu), cj = j + int(fv);
    const double z = facet_height(u - fu, v - fv, [&](int di, int dj) { return height(ci + di, cj + dj); });
    const double slope = (z - z0) / t - c * t;
    h.up = std::max(h.up, slope);
    h.down = std::min(h.down, slope);
    if (c > 0) {  // the piece (t_prev, t): z = a + b t, highest at t* = sqrt((z0 - a) / c) inside it
      const double b = (z - z_prev) / (t - t_prev), a = z_prev - b * t_prev;
      // The first piece starts at the receiver (a = z0): s = b - c t is highest as t -> 0, the facet's
      // own slope.
      if (t_prev == 0) h.up = std::max(h.up, b);
      if (a < z0) {
        const double ts = std::sqrt((z0 - a) / c);
        if (ts > t_prev && ts < t) h.up = std::max(h.up, b + (a - z0) / ts - c * ts);
      }
    }
    t_prev = t, z_prev = z;
  };
  Crossings cx(rx), cy(ry), cd(rx + ry);
  for (;;) {
    const double t = std::min({cx.next(), cy.next(), cd.next()});
    if (!(t < t_end)) break;
    visit(t);
    // Every sequence at this t advances (a vertex is a column, row and diagonal crossing at once).
    if (cx.next() <= t) ++cx.m;
    if (cy.next() <= t) ++cy.m;
    if (cd.next() <= t) ++cd.m;
  }
  visit(t_end);
  h.any = true;
  return h;
}

// The far field's walk over the cells of `g` from distance t0 to t1 along the ray (gi, gj) + t (rx, ry) in
// the coarse copy's texel coordinates, folded into `h` (the exact march's result out to t0).
void walk_far(const CoarseHeights& g, long gi, long gj, double rx, double ry, double t0, double t1, double z0,
              double c, HorizonPair& h) {
  const double C = g.cell;
  const int sx = rx > 1e-15 ? 1 : rx < -1e-15 ? -1 : 0, sy = ry > 1e-15 ? 1 : ry < -1e-15 ? -1 : 0;
  long cx = long(std::floor((double(gi) + t0 * rx) / C)), cy = long(std::floor((double(gj) + t0 * ry) / C));
  if (g.wrap == Wrap::clamp) {  // the ray stays within [0, n - 1]: its cells are [0, cells)
    cx = std::clamp(cx, 0L, long(g.columns) - 1);
    cy = std::clamp(cy, 0L, long(g.rows) - 1);
  }
  // The distance at which the ray leaves cell c along an axis moving by s (from integers: the same bits
  // for every window of the field).
  auto leave = [&](long cell, int s, double rate, long origin) {
    if (s == 0) return std::numeric_limits<double>::infinity();
    return (double((cell + (s > 0 ? 1 : 0)) * g.cell) - double(origin)) / rate;
  };
  auto wrapped = [](long k, int n) { return int((k % n + n) % n); };
  double next_x = leave(cx, sx, rx, gi), next_y = leave(cy, sy, ry, gj);
  double up = -std::numeric_limits<double>::infinity(), up_floor = up;
  double down = std::numeric_limits<double>::infinity(), down_ceiling = down;
  for (double ta = t0;;) {
    const double tb = std::max(ta, std::min({next_x, next_y, t1}));  // never before ta (a start on a border)
    const std::size_t k = g.wrap == Wrap::repeat ? g.index(wrapped(cx, g.columns), wrapped(cy, g.rows))
                                                 : g.index(int(std::clamp(cx, 0L, long(g.columns) - 1)),
                                                           int(std::clamp(cy, 0L, long(g.rows) - 1)));
    const double hi = g.high[k], lo = g.low[k];
    // The highest s any point of the cell on [ta, tb] can reach, and the lowest.
    const double most = (hi - z0) / (hi >= z0 ? ta : tb) - c * ta;
    const double least = (lo - z0) / (lo <= z0 ? ta : tb) - c * tb;
    up = std::max(up, most);
    up_floor = std::max(up_floor, least);
    down = std::min(down, least);
    down_ceiling = std::min(down_ceiling, most);
    if (!(tb < t1)) break;
    if (next_x <= tb) next_x = leave(cx += sx, sx, rx, gi);
    if (next_y <= tb) next_y = leave(cy += sy, sy, ry, gj);
    ta = tb;
  }
  const double near_up = h.up, near_down = h.down;
  h.up = std::max(near_up, up);
  h.up_slack = h.up - std::max(near_up, up_floor);
  h.down = std::min(near_down, down);
  h.down_slack = std::min(near_down, down_ceiling) - h.down;
}

HorizonPair exact_horizon(const HeightField& field, int i, int j, double rx, double ry, double radius,
                          double curvature) {
  double t_end = radius;
  const int reach_x = int(std::ceil(radius / field.dx())) + 1,
            reach_y = int(std::ceil(radius / field.dy())) + 1;
  if (i - reach_x >= 0 && j - reach_y >= 0 && i + reach_x < field.width && j + reach_y < field.height) {
    const float* z = field.z.data();
    const std::size_t w = std::size_t(field.width);
    return march(field, i, j, rx, ry, t_end, curvature,
                 [z, w](int a, int b) { return double(z[std::size_t(b) * w + std::size_t(a)]); });
  }
  if (field.wrap == Wrap::clamp)
    t_end = std::min({t_end, exit_t(i, rx, field.width), exit_t(j, ry, field.height)});
  return march(field, i, j, rx, ry, t_end, curvature,
               [&field](int a, int b) { return double(field.at(a, b)); });
}

}  // namespace

HorizonPair radius_horizon(const HeightField& field, int i, int j, double ux, double uy, double radius,
                           double curvature, const FarField& far) {
  // A direction along an axis moves along it alone: its other component rounds to about 1e-16, which the
  // far field's walk would otherwise take for a step (the exact march already ignores it).
  auto component = [](double v) { return std::fabs(v) < 1e-12 ? 0.0 : v; };
  const double rx = component(ux) / field.dx(), ry = component(uy) / field.dy();
  if (!far.coarse || !(far.beyond < radius)) return exact_horizon(field, i, j, rx, ry, radius, curvature);
  HorizonPair h = exact_horizon(field, i, j, rx, ry, far.beyond, curvature);
  const CoarseHeights& g = *far.coarse;
  const long gi = long(i) + far.x0, gj = long(j) + far.y0;
  double t_end = radius;
  if (g.wrap == Wrap::clamp)
    t_end = std::min({t_end, exit_t(double(gi), rx, g.width), exit_t(double(gj), ry, g.height)});
  if (h.any && t_end > far.beyond)
    walk_far(g, gi, gj, rx, ry, far.beyond, t_end, field.z[field.index(i, j)], curvature, h);
  return h;
}

}  // namespace hfbake
