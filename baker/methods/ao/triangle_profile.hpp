// The reference's surface along one slice: the height field's triangulation (two triangles per quad, split
// along (i+1, j)-(i, j+1), the reference's surface, docs/contract.md) cut by a vertical plane is a polyline
// with a vertex at every column, row and diagonal crossing. Marching those vertices (with the segment band
// integrals of slice_integral.hpp) gives the exact slice integral of that surface.
#pragma once

#include <algorithm>
#include <cmath>

#include "field/height_field.hpp"

namespace hfbake {

// Clamp fields: the largest t <= t_end at which the ray from texel (i, j) along (dx, dy) is still on the
// field (repeat fields: t_end).
inline double profile_end(const HeightField& f, int i, int j, double dx, double dy, double t_end) {
  if (f.wrap == Wrap::repeat) return t_end;
  if (dx > 1e-12) t_end = std::min(t_end, (f.width - 1 - i) / dx);
  if (dx < -1e-12) t_end = std::min(t_end, -i / dx);
  if (dy > 1e-12) t_end = std::min(t_end, (f.height - 1 - j) / dy);
  if (dy < -1e-12) t_end = std::min(t_end, -j / dy);
  return t_end;
}

// The profile of the triangulated surface (two triangles per quad, split along (i+1, j)-(i, j+1)) along the
// ray from texel (i, j) towards (dx, dy) (unit, texel units): visits every column, row and diagonal crossing
// with t in (t_begin, t_end] in increasing t (ties in any order), then the point at t_end, as
// visit(t, height) -> bool (false: stop there). Heights are linear along the triangle edge each crossing lies
// on. Crossings are found from offsets to the texel, not from positions in the field, so a texel's profile
// has the same bits wherever the texel lies (a tiled bake's texels are the whole bake's,
// docs/large-fields.md).
template <class Visit>
void triangle_profile_span(const HeightField& f, int i, int j, double dx, double dy, double t_begin,
                           double t_end, Visit&& visit) {
  struct Progression {
    double inv = 0;  // t between crossings (infinite: never)
    int k = 1;       // next crossing number
    double next() const { return k * inv; }
    // The first crossing beyond t_begin (k = 1 from the start).
    void start(double t_begin) {
      if (!(t_begin > 0) || !std::isfinite(inv)) return;
      k = int(std::floor(t_begin / inv)) + 1;
      while (k > 1 && (k - 1) * inv > t_begin) --k;
      while (k * inv <= t_begin) ++k;
    }
  };
  const double ds = dx + dy;
  Progression col{std::abs(dx) > 1e-12 ? 1 / std::abs(dx) : INFINITY};
  Progression row{std::abs(dy) > 1e-12 ? 1 / std::abs(dy) : INFINITY};
  Progression dia{std::abs(ds) > 1e-12 ? 1 / std::abs(ds) : INFINITY};
  col.start(t_begin), row.start(t_begin), dia.start(t_begin);
  const int sx = dx > 0 ? 1 : -1, sy = dy > 0 ? 1 : -1, sd = ds > 0 ? 1 : -1;
  auto lerp = [](double a, double b, double w) { return a + (b - a) * w; };
  for (;;) {
    const double tc = col.next(), tr = row.next(), td = dia.next();
    const double t = std::min({tc, tr, td});
    if (!(t < t_end - 1e-9)) break;
    if (t == tc) {  // x = i + sx k: on the edge between (c, floor y) and (c, floor y + 1)
      const int c = i + sx * col.k++;
      const double v = t * dy, fv = std::floor(v);
      const int jj = j + int(fv);
      if (!visit(t, lerp(f.at(c, jj), f.at(c, jj + 1), v - fv))) return;
    } else if (t == tr) {  // y = j + sy k
      const int r = j + sy * row.k++;
      const double u = t * dx, fu = std::floor(u);
      const int ii = i + int(fu);
      if (!visit(t, lerp(f.at(ii, r), f.at(ii + 1, r), u - fu))) return;
    } else {  // x + y = i + j + sd k: on the edge from (s - jj, jj) to (s - jj - 1, jj + 1)
      const int sum = i + j + sd * dia.k++;
      const double v = t * dy, fv = std::floor(v);
      const int jj = j + int(fv);
      if (!visit(t, lerp(f.at(sum - jj, jj), f.at(sum - jj - 1, jj + 1), v - fv))) return;
    }
  }
  // The end of the reach, inside its triangle.
  const double x = t_end * dx, y = t_end * dy;
  const double fx = std::floor(x), fy = std::floor(y);
  const int ii = i + int(fx), jj = j + int(fy);
  const double u = x - fx, v = y - fy;
  visit(t_end, facet_height(u, v, [&](int di, int dj) { return double(f.at(ii + di, jj + dj)); }));
}

// The whole profile, t in (0, t_end]: visit(t, height) at every vertex (triangle_profile_span from 0).
template <class Visit>
void triangle_profile(const HeightField& f, int i, int j, double dx, double dy, double t_end, Visit&& visit) {
  triangle_profile_span(f, i, j, dx, dy, 0.0, t_end, [&](double t, double z) {
    visit(t, z);
    return true;
  });
}

}  // namespace hfbake
