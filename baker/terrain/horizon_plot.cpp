#include "terrain/horizon_plot.hpp"

#include <cmath>

#include "core/vec.hpp"

namespace hfbake {

double profile_elevation(const std::vector<HorizonRay>& rays, double azimuth_deg) {
  const int K = int(rays.size());
  if (K == 0) return -90;
  const double step = 360.0 / K;
  double a = std::fmod(azimuth_deg, 360.0);
  if (a < 0) a += 360;
  const int k0 = int(std::floor(a / step)) % K, k1 = (k0 + 1) % K;
  const double t = a / step - std::floor(a / step);
  auto e = [&](int k) { return rays[std::size_t(k)].found ? rays[std::size_t(k)].elevation_deg : -90.0; };
  return e(k0) + t * (e(k1) - e(k0));
}

std::vector<std::uint8_t> horizon_polar_plot(const std::vector<HorizonRay>& rays,
                                             const PolarPlotGeometry& g) {
  const int n = g.size;
  const double c = 0.5 * n, rh = g.horizon_radius(), deg = 180 / kPi;
  std::vector<std::uint8_t> px(std::size_t(n) * n * 3);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double dx = x + 0.5 - c, dy = y + 0.5 - c, r = std::hypot(dx, dy);
      const double e = 90 - 90 * r / rh, a = std::atan2(dx, -dy) * deg;
      std::uint8_t rgb[3] = {255, 255, 255};
      if (e >= -22.5) {
        const bool sky = e > profile_elevation(rays, a);
        const std::uint8_t sky_rgb[3] = {170, 205, 240}, ground_rgb[3] = {150, 115, 80};
        for (int i = 0; i < 3; ++i) rgb[i] = sky ? sky_rgb[i] : ground_rgb[i];
        // Grid: circles at 0°, 30°, 60° (one pixel wide) and the four compass spokes.
        bool grid = false;
        for (const double ge : {0.0, 30.0, 60.0}) grid |= std::abs(r - (90 - ge) / 90 * rh) < 0.5;
        grid |= x == n / 2 || y == n / 2;
        if (grid)
          for (std::uint8_t& v : rgb) v = std::uint8_t(v / 2);
      }
      std::uint8_t* p = &px[(std::size_t(y) * n + x) * 3];
      p[0] = rgb[0], p[1] = rgb[1], p[2] = rgb[2];
    }
  return px;
}

}  // namespace hfbake
