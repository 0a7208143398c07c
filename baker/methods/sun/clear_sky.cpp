#include "methods/sun/clear_sky.hpp"

#include <cmath>

#include "core/vec.hpp"

namespace hfbake::sun {

double refracted_elevation(double h) {
  return h + 0.061359 * (0.1594 + 1.123 * h + 0.065656 * h * h) / (1 + 28.9344 * h + 277.3971 * h * h);
}

double relative_air_mass(double elevation) {
  const double h = refracted_elevation(elevation);
  return 1 / (std::sin(h) + 0.50572 * std::pow(h * 180 / kPi + 6.07995, -1.6364));
}

double rayleigh_thickness(double m) {
  if (m <= 20) return 1 / (6.6296 + m * (1.7513 + m * (-0.1202 + m * (0.0065 - m * 0.00013))));
  return 1 / (10.4 + 0.718 * m);
}

double beam_normal(double g0, double m, double linke) {
  return g0 * std::exp(-0.8662 * linke * m * rayleigh_thickness(m));
}

double diffuse_horizontal(double g0, double elevation, double linke) {
  const double t = linke;
  const double tn = -0.015843 + 0.030543 * t + 0.0003797 * t * t;  // the diffuse transmission at zenith
  double a1 = 0.26463 - 0.061581 * t + 0.0031408 * t * t;
  if (a1 * tn < 0.0022) a1 = 0.0022 / tn;
  const double a2 = 2.04020 + 0.018945 * t - 0.011161 * t * t;
  const double a3 = -1.3025 + 0.039231 * t + 0.0085079 * t * t;
  const double s = std::sin(elevation);
  return g0 * tn * (a1 + a2 * s + a3 * s * s);
}

double pressure_ratio(double z) {
  return std::exp(-z / 8434.5);
}

}  // namespace hfbake::sun
