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
  // One coefficient for every azimuth, with Gauss's mean radius sqrt(M N): what a bake lowers by (the
  // Scene's curvature). It is within (M - N) / (2 sqrt(M N)) relative of coefficient(A) at any azimuth:
  // 0.34 % at the equator, 0 at the poles.
  double mean_coefficient() const {
    return (1 - refraction) / (2 * std::sqrt(meridian_radius * normal_radius));
  }
};

// A geographic raster's local frame (docs/gis.md "Geographic DEMs"): east and north metres per degree at
// the field's centre latitude lat0 (radians), so one texel of dlon x dlat degrees is a rectangle of
// east_per_degree * dlon x north_per_degree * dlat.
struct GeographicFrame {
  double east_per_degree = 0, north_per_degree = 0;
  static GeographicFrame at(const Ellipsoid& e, double lat0) {
    constexpr double kRadPerDeg = 3.14159265358979323846 / 180;
    return {kRadPerDeg * e.prime_vertical_radius(lat0) * std::cos(lat0),
            kRadPerDeg * e.meridian_radius(lat0)};
  }
};

// The frame's relative east-west scale error at latitude lat (radians): the true length of a degree of
// longitude there over the frame's, minus 1 (N cos lat / (N0 cos lat0) - 1; about -tan(lat0) (lat - lat0)).
inline double frame_scale_error(const Ellipsoid& e, double lat0, double lat) {
  return e.prime_vertical_radius(lat) * std::cos(lat) / (e.prime_vertical_radius(lat0) * std::cos(lat0)) - 1;
}

// The largest east-west scale error a geographic field is baked with (the loader refuses larger spans):
// 1 %, i.e. horizons within 0.01 sin e cos e radians of those of a true local frame (0.1 degrees at an
// elevation e of 10 degrees, 0.29 at 45 degrees) at the raster's northern and southern rows, less inside.
inline constexpr double kMaxFrameScaleError = 0.01;
// The latitude beyond which a geographic field is refused (degrees): the frame's east scale vanishes at
// the pole.
inline constexpr double kMaxFrameLatitude = 89.9;

}  // namespace hfbake
