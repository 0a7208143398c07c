#include "terrain/point_horizon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/vec.hpp"
#include "field/edge_crossings.hpp"

namespace hfbake {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The surface height at (x, y) clamped into the field (a crossing computed a rounding error outside it):
// the facet's barycentric sum over the corners with a weight, so that a point on an edge or a vertex next to
// a NoData texel has its height (NaN only where a weighted corner is not finite).
double height_at(const HeightField& f, double x, double y) {
  x = std::clamp(x, 0.0, double(f.width - 1));
  y = std::clamp(y, 0.0, double(f.height - 1));
  const double fx = std::floor(x), fy = std::floor(y);
  const int i = int(fx), j = int(fy);
  const FacetWeights w = facet_weights(x - fx, y - fy);
  double z = 0;
  for (int c = 0; c < 3; ++c)
    if (w.w[c] != 0) z += w.w[c] * double(f.at(i + w.di[c], j + w.dj[c]));
  return z;
}

// The surface height at a crossing of an edge (field/edge_crossings.hpp): column x = m, row y = m or
// diagonal x + y = m, at (x, y) on it. From the edge's own two vertices, so a point on the last edge before a
// NoData texel has its height though its computed position rounds a hair into the hole's facet.
double height_on_edge(const HeightField& f, EdgeFamily family, int m, double x, double y) {
  auto lerp = [](double a, double b, double t) { return t == 0 ? a : t == 1 ? b : (1 - t) * a + t * b; };
  switch (family) {
    case EdgeFamily::column: {
      const double v = std::clamp(y, 0.0, double(f.height - 1));
      if (f.height < 2) return f.at(m, 0);
      const int j = std::min(int(std::floor(v)), f.height - 2);
      return lerp(f.at(m, j), f.at(m, j + 1), v - j);
    }
    case EdgeFamily::row: {
      const double u = std::clamp(x, 0.0, double(f.width - 1));
      if (f.width < 2) return f.at(0, m);
      const int i = std::min(int(std::floor(u)), f.width - 2);
      return lerp(f.at(i, m), f.at(i + 1, m), u - i);
    }
    case EdgeFamily::diagonal: {
      // The edge from (i, m - i) to (i + 1, m - i - 1), both on the field.
      const int lo = std::max(0, m - (f.height - 1)), hi = std::min(f.width - 1, m);
      if (hi <= lo) return double(f.at(lo, m - lo));
      const double u = std::clamp(x, double(lo), double(hi));
      const int i = std::min(int(std::floor(u)), hi - 1);
      return lerp(f.at(i, m - i), f.at(i + 1, m - i - 1), u - i);
    }
  }
  return height_at(f, x, y);
}

// A crossing nearer the eye than this, in texels along the ray's major axis, is the eye's own edge: the
// eye is taken to lie on it. Its rise over so short a distance is rounding (a point given as a texel centre
// in map coordinates lands about 1e-10 texel off its column), and the piece from the eye to the next
// crossing gives the surface's slope there exactly.
constexpr double kOwnEdge = 1e-6;

// Distance along the ray at which origin + d * rate leaves [0, n - 1].
double exit_distance(double origin, double rate, int n) {
  if (rate > 0) return (n - 1 - origin) / rate;
  if (rate < 0) return origin / -rate;
  return kInf;
}

HorizonRay march(const HeightField& f, const PointHorizonQuery& q, double z_surface, double azimuth) {
  HorizonRay ray;
  ray.azimuth_deg = azimuth * 180 / kPi;
  // sin and cos of multiples of 90° are 1e-16 off zero: snapped, so that a ray along a border row or
  // column stays on the field.
  auto snap = [](double v) { return std::abs(v) < 1e-12 ? 0.0 : v; };
  const double grid_azimuth = azimuth + q.frame.convergence;
  const double vx = snap(std::sin(grid_azimuth)) / q.frame.east_per_x;
  const double vy = snap(std::cos(grid_azimuth)) / q.frame.north_per_y;
  const double c = q.curvature ? q.curvature->coefficient(azimuth) : 0;
  const double z0 = z_surface + q.observer_height;
  const double d_end = std::min(exit_distance(q.x, vx, f.width), exit_distance(q.y, vy, f.height));
  if (!(d_end > 0)) return ray;
  double best = -kInf;  // tangent of the elevation
  auto consider = [&](double d, double z) {
    const double slope = (z - c * d * d - z0) / d;
    if (slope > best) {
      best = slope;
      ray.found = true;
      ray.distance = d, ray.x = q.x + d * vx, ray.y = q.y + d * vy, ray.z = z;
    }
  };
  double d_prev = 0, z_prev = z_surface;  // the last point visited; z_prev NaN: a hole behind
  const double major_rate = std::max(std::abs(vx), std::abs(vy));
  // family, m: the edge the point lies on (a step's end lies on its column or row).
  auto visit = [&](double d, EdgeFamily family, int m) {
    if (d * major_rate < kOwnEdge) return;
    const double z = height_on_edge(f, family, m, q.x + d * vx, q.y + d * vy);
    if (!std::isfinite(z)) {
      d_prev = d, z_prev = z;
      return;
    }
    if (c > 0 && std::isfinite(z_prev) && d > d_prev) {
      const double b = (z - z_prev) / (d - d_prev), a = z_prev - b * d_prev;
      if (d_prev == 0 && a >= z0 && b > best) {
        // An eye on the surface: the slope b - c d of the first piece is highest as d -> 0, the facet's
        // own slope, cast by the surface at the point itself.
        best = b, ray.found = true;
        ray.distance = 0, ray.x = q.x, ray.y = q.y, ray.z = z_prev;
      } else if (a < z0) {
        const double d_star = std::sqrt((z0 - a) / c);
        if (d_star > d_prev && d_star < d) consider(d_star, a + b * d_star);
      }
    }
    consider(d, z);
    d_prev = d, z_prev = z;
  };
  // The ray in steps of one texel along its major axis, from one column (row) to the next; each step's
  // crossings from field/edge_crossings.hpp, then its end (on a column or row: not one of them).
  const bool along_x = std::abs(vx) >= std::abs(vy);
  const double major0 = along_x ? q.x : q.y, rate = along_x ? vx : vy;
  double d0 = 0, x0 = q.x, y0 = q.y;
  for (long m = 1;; ++m) {
    const double edge = rate > 0 ? std::floor(major0) + double(m) : std::ceil(major0) - double(m);
    const double d1 = std::min((edge - major0) / rate, d_end);
    double x1 = q.x + d1 * vx, y1 = q.y + d1 * vy;
    if (d1 < d_end) (along_x ? x1 : y1) = edge;  // exactly on the column (row)
    EdgeCrossing crossings[kMaxEdgeCrossings];
    const int n = edge_crossings(x0, y0, x1, y1, crossings);
    for (int e = 0; e < n; ++e) visit(d0 + crossings[e].t * (d1 - d0), crossings[e].family, crossings[e].m);
    if (d1 >= d_end) break;
    visit(d1, along_x ? EdgeFamily::column : EdgeFamily::row, int(edge));
    d0 = d1, x0 = x1, y0 = y1;
  }
  // The border: on the column or row the ray leaves by (the other coordinate rounds onto its line).
  const bool leaves_x = exit_distance(q.x, vx, f.width) <= exit_distance(q.y, vy, f.height);
  visit(d_end, leaves_x ? EdgeFamily::column : EdgeFamily::row,
        leaves_x ? (vx > 0 ? f.width - 1 : 0) : (vy > 0 ? f.height - 1 : 0));
  if (ray.found) ray.elevation_deg = std::atan(best) * 180 / kPi;
  return ray;
}

}  // namespace

std::optional<double> surface_height(const HeightField& field, double x, double y) {
  if (!(x >= 0 && y >= 0 && x <= field.width - 1 && y <= field.height - 1)) return std::nullopt;
  const double z = height_at(field, x, y);
  if (!std::isfinite(z)) return std::nullopt;
  return z;
}

std::vector<HorizonRay> point_horizon(const HeightField& field, const PointHorizonQuery& query) {
  const std::optional<double> z = surface_height(field, query.x, query.y);
  if (!z) throw std::invalid_argument("point_horizon: the point has no surface height");
  if (query.directions < 1) throw std::invalid_argument("point_horizon: directions must be >= 1");
  std::vector<HorizonRay> rays;
  rays.reserve(std::size_t(query.directions));
  for (int k = 0; k < query.directions; ++k)
    rays.push_back(march(field, query, *z, 2 * kPi * k / query.directions));
  return rays;
}

}  // namespace hfbake
