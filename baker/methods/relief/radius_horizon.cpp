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

}  // namespace

HorizonPair radius_horizon(const HeightField& field, int i, int j, double ux, double uy, double radius,
                           double curvature) {
  const double rx = ux / field.dx(), ry = uy / field.dy();
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

}  // namespace hfbake
