// The Earth's curvature as a height correction: a far point at horizontal distance d from a receiver lies
// d^2 / (2 R) below the receiver's tangent plane (R the radius of the normal section through both), and
// refraction bends the line of sight down with curvature k / R, which raises it by k d^2 / (2 R). What a
// horizon sees is therefore each point lowered by d^2 (1 - k) / (2 R) (docs/gis.md "Earth curvature"; the
// exact drop of a sphere, R (1 / cos(d / R) - 1), differs by under 0.1 m at 100 km).
#pragma once

#include <cmath>

namespace hfbake {

// IUGG mean Earth radius R1 = (2a + b) / 3 of GRS 80 / WGS 84, metres: the radius of a sphere when the
// CRS names no ellipsoid.
inline constexpr double kMeanEarthRadius = 6371008.8;

// The coefficient of terrestrial refraction, the line of sight's curvature divided by the Earth's: Gauss's
// 0.13, the value surveying uses for trigonometric heights (GRASS r.viewshed defaults to 1/7 = 0.143).
inline constexpr double kDefaultRefraction = 0.13;

// An ellipsoid by its semi-axes, in the world unit.
struct Ellipsoid {
  double a = kMeanEarthRadius, b = kMeanEarthRadius;
  double e2() const { return 1 - (b * b) / (a * a); }
  // Radius of curvature of the meridian (M) and of the prime vertical (N) at geodetic latitude lat (rad).
  double meridian_radius(double lat) const {
    const double s = std::sin(lat), w = 1 - e2() * s * s;
    return a * (1 - e2()) / (w * std::sqrt(w));
  }
  double prime_vertical_radius(double lat) const {
    const double s = std::sin(lat);
    return a / std::sqrt(1 - e2() * s * s);
  }
};

// The curvature correction at one receiver: the ellipsoid's principal radii there and the refraction.
struct EarthCurvature {
  double meridian_radius = kMeanEarthRadius;  // M at the receiver, world units
  double normal_radius = kMeanEarthRadius;    // N at the receiver, world units
  double refraction = kDefaultRefraction;     // k

  static EarthCurvature at(const Ellipsoid& e, double lat_rad, double refraction) {
    return {e.meridian_radius(lat_rad), e.prime_vertical_radius(lat_rad), refraction};
  }
  // Euler's radius of the normal section in compass azimuth A (radians): 1/R = cos^2 A / M + sin^2 A / N.
  double radius(double azimuth) const {
    const double c = std::cos(azimuth), s = std::sin(azimuth);
    return 1 / (c * c / meridian_radius + s * s / normal_radius);
  }
  // The lowering of a point at horizontal distance d is coefficient(A) * d^2.
  double coefficient(double azimuth) const { return (1 - refraction) / (2 * radius(azimuth)); }
};

}  // namespace hfbake
