#include "methods/p1/far_floor.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <stdexcept>

namespace hfbake::p1 {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The distance at which x0 + t rate leaves [lo, hi] (x0 inside; +inf when rate = 0, a negative value when
// x0 is outside).
double exit_t(double x0, double rate, double lo, double hi) {
  if (rate > 1e-15) return (hi - x0) / rate;
  if (rate < -1e-15) return (x0 - lo) / -rate;
  return x0 >= lo && x0 <= hi ? kInf : -1.0;
}

float float_down(double v) {
  if (!(v > -kInf)) return -std::numeric_limits<float>::infinity();
  float f = float(v);
  if (double(f) > v) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

// A margin above a bound of height `hi` seen from height z at distance t: the lane search rounds each
// crossing's slope in single precision (heights, their difference, the product by 1 / t), which this exceeds,
// so the floor stays above every rounded slope it bounds.
double rounding_margin(double hi, double z, double t, double bound) {
  return (std::fabs(hi) + std::fabs(z)) * 1e-6 / t + std::fabs(bound) * 1e-6;
}

}  // namespace

FloorGrid floor_grid(const CoarseHeights& coarse, int x0, int y0, const FieldShape& field, double beyond,
                     double curvature) {
  if (coarse.wrap != Wrap::clamp) throw std::logic_error("floor_grid: clamp fields only");
  FloorGrid g;
  g.coarse = &coarse;
  g.x0 = x0, g.y0 = y0;
  g.dx = field.dx(), g.dy = field.dy();
  g.beyond = beyond;
  g.curvature = curvature;
  return g;
}

void direction_floor(const FloorGrid& grid, int width, int height, double phi, DirectionFloor& out) {
  const CoarseHeights& g = *grid.coarse;
  const int C = g.cell;
  out.cx0 = std::min(grid.x0 / C, g.columns - 1);
  out.cy0 = std::min(grid.y0 / C, g.rows - 1);
  out.columns = std::min((grid.x0 + width - 1) / C, g.columns - 1) - out.cx0 + 1;
  out.rows = std::min((grid.y0 + height - 1) / C, g.rows - 1) - out.cy0 + 1;
  const std::size_t cells = std::size_t(out.columns) * std::size_t(out.rows);
  out.at_low.resize(cells), out.at_high.resize(cells), out.least.resize(cells), out.distance.resize(cells);
  // Texel coordinates per world unit along the ray; a direction along an axis moves along it alone (its
  // other component rounds to about 1e-16, which no texel coordinate can represent a step of).
  auto component = [](double v) { return std::fabs(v) < 1e-12 ? 0.0 : v; };
  const double rx = component(std::cos(phi)) / grid.dx, ry = component(std::sin(phi)) / grid.dy;
  const int sx = rx > 1e-15 ? 1 : rx < -1e-15 ? -1 : 0, sy = ry > 1e-15 ? 1 : ry < -1e-15 ? -1 : 0;
  const double half = 0.5 * C, W = g.width - 1, H = g.height - 1, c = grid.curvature, t0 = grid.beyond;
  tbb::parallel_for(0, out.rows, [&](int row) {
    for (int col = 0; col < out.columns; ++col) {
      const int cx = out.cx0 + col, cy = out.cy0 + row;
      const double ox = (cx + 0.5) * C, oy = (cy + 0.5) * C;  // c0, in the copy's texel coordinates
      const std::size_t home = g.index(cx, cy);
      const double z_lo = g.low[home], z_hi = g.high[home];
      // Every receiver's ray point lies within half of c0's: the walk ends where that square leaves the
      // field, and `least` counts only where it lies wholly inside.
      const double t1 = std::min(exit_t(ox, rx, -half, W + half), exit_t(oy, ry, -half, H + half));
      const double t_in = std::min(exit_t(ox, rx, half, W - half), exit_t(oy, ry, half, H - half));
      double up_lo = -kInf, up_hi = -kInf, least = -kInf, dist = kInf;
      if (t1 > t0) {
        // Dual cell u spans x in [(u - 1/2) C, (u + 1/2) C].
        const int columns = g.columns + 1, rows = g.rows + 1;  // dual cells
        auto dual = [&](double x, int n) { return std::clamp(int(std::floor(x / C + 0.5)), 0, n - 1); };
        int u = dual(ox + t0 * rx, columns), v = dual(oy + t0 * ry, rows);
        auto leave = [&](int cell, int s, double rate, double origin) {
          if (s == 0) return kInf;
          return ((cell + (s > 0 ? 0.5 : -0.5)) * C - origin) / rate;
        };
        double next_x = leave(u, sx, rx, ox), next_y = leave(v, sy, ry, oy);
        for (double ta = t0;;) {
          // Never before ta: where the start lies on a border, its rounding may name the cell behind it.
          const double tb = std::max(ta, std::min({next_x, next_y, t1}));
          // Dual cell (u, v): the highest and lowest of coarse cells u - 1 .. u, v - 1 .. v (clamped).
          float hi = -std::numeric_limits<float>::infinity(), lo = std::numeric_limits<float>::infinity();
          for (int b = std::max(v - 1, 0); b <= std::min(v, g.rows - 1); ++b)
            for (int a = std::max(u - 1, 0); a <= std::min(u, g.columns - 1); ++a) {
              hi = std::max(hi, g.high[g.index(a, b)]);
              lo = std::min(lo, g.low[g.index(a, b)]);
            }
          auto most = [&](double z) {
            const double b = (hi - z) / (hi >= z ? ta : tb) - c * ta;
            return b + rounding_margin(hi, z, ta, b);
          };
          const double at_lo = most(z_lo);
          if (at_lo > up_lo) up_lo = at_lo, dist = ta;
          up_hi = std::max(up_hi, most(z_hi));
          if (tb <= t_in) least = std::max(least, (lo - z_hi) / (lo <= z_hi ? ta : tb) - c * tb);
          if (!(tb < t1)) break;
          if (next_x <= tb) {
            u = std::clamp(u + sx, 0, columns - 1);
            next_x = leave(u, sx, rx, ox);
            if (next_x <= tb) next_x = kInf;  // clamped: the walk ends at t1
          }
          if (next_y <= tb) {
            v = std::clamp(v + sy, 0, rows - 1);
            next_y = leave(v, sy, ry, oy);
            if (next_y <= tb) next_y = kInf;
          }
          ta = tb;
        }
      }
      const std::size_t at = std::size_t(row) * std::size_t(out.columns) + std::size_t(col);
      out.at_low[at] = round_up_to_float(up_lo);
      out.at_high[at] = round_up_to_float(up_hi);
      out.least[at] = float_down(least);
      out.distance[at] = float(dist);
    }
  });
}

float round_up_to_float(double v) {
  if (!(v > -kInf)) return -std::numeric_limits<float>::infinity();
  float f = float(v);
  if (double(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

double floor_bytes(int width, int height, int cell) {
  return 16 * double(width / cell + 2) * double(height / cell + 2);
}

}  // namespace hfbake::p1
