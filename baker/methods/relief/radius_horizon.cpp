#include "methods/relief/radius_horizon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hfbake {

namespace {

// The ray parameter t (texels) of the m-th crossing of lines spaced 1 apart along a coordinate that
// changes by `rate` per unit t, starting on a line: m / |rate|; +inf when the ray runs along them.
struct Crossings {
  double step = std::numeric_limits<double>::infinity();
  long m = 1;
  explicit Crossings(double rate) {
    if (std::abs(rate) > 1e-12) step = 1 / std::abs(rate);
  }
  double next() const { return double(m) * step; }
};

// The exit parameter of the ray x0 + t d from [0, n - 1] (x0 inside): +inf when d = 0.
double exit_t(double x0, double d, int n) {
  if (d > 1e-15) return (n - 1 - x0) / d;
  if (d < -1e-15) return x0 / -d;
  return std::numeric_limits<double>::infinity();
}

// The march, with `height(ci, cj)` the corner heights (direct reads inside the field, wrapped or clamped
// reads near its border).
template <class Height>
HorizonPair march(const HeightField& field, int i, int j, double dx, double dy, double t_end, Height height) {
  const double z0 = field.z[field.index(i, j)];
  HorizonPair h;
  if (!(t_end > 0)) return h;
  h.up = -std::numeric_limits<double>::infinity();
  h.down = std::numeric_limits<double>::infinity();
  const double inv_texel = 1 / field.texel_size;
  // Offsets from the texel, not positions in the field: the same bits wherever the texel lies (a tile of a
  // raster bakes the whole raster's texels, docs/large-fields.md).
  auto visit = [&](double t) {
    const double u = t * dx, v = t * dy;
    const double fu = std::floor(u), fv = std::floor(v);
    const int ci = i + int(fu), cj = j + int(fv);
    const double z = facet_height(u - fu, v - fv, [&](int di, int dj) { return height(ci + di, cj + dj); });
    const double slope = (z - z0) / t * inv_texel;
    h.up = std::max(h.up, slope);
    h.down = std::min(h.down, slope);
  };
  Crossings cx(dx), cy(dy), cd(dx + dy);
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

HorizonPair radius_horizon(const HeightField& field, int i, int j, double dx, double dy, double radius) {
  double t_end = radius / field.texel_size;
  const int reach = int(std::ceil(t_end)) + 1;
  if (i - reach >= 0 && j - reach >= 0 && i + reach < field.width && j + reach < field.height) {
    const float* z = field.z.data();
    const std::size_t w = std::size_t(field.width);
    return march(field, i, j, dx, dy, t_end,
                 [z, w](int a, int b) { return double(z[std::size_t(b) * w + std::size_t(a)]); });
  }
  if (field.wrap == Wrap::clamp)
    t_end = std::min({t_end, exit_t(i, dx, field.width), exit_t(j, dy, field.height)});
  return march(field, i, j, dx, dy, t_end, [&field](int a, int b) { return double(field.at(a, b)); });
}

}  // namespace hfbake
