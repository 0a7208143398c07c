// Reference sh_irradiance: the order-4 real SH (sh_environment.hpp's basis, nlp's convention) of E(n) / pi as
// a function of the normal n, at each texel, independently of nlp.
//
// E(n) = integral of L_in(w) max(n . w, 0) dw, so by Funk-Hecke its SH coefficients are A_l L_lm, with L_lm
// the projection of the incident radiance L_in over the whole sphere and A_l = pi, 2 pi / 3, pi / 4, 0 for
// l = 0..3 (the clamped cosine has no l = 3 part: band 3 is exactly zero). The layer holds c_lm =
// (A_l / pi) L_lm: 16 coefficients x RGB a texel, channels "<coefficient>.R/G/B" (nlp's), band 3 zero.
//
// L_in at a receiver (the texel centre) is, by direction w:
//   - the environment where a ray escapes (V(w) = [e > h(phi)] over the whole sphere, as sh_visibility:
//     terrain falling away below the horizontal lets the sky in);
//   - the terrain's exit radiance (emission + albedo x its irradiance / pi, up to `bounces` surface
//     vertices, as the reference's indirect layer) where the ray hits the terrain in the upper hemisphere of
//     the texel normal; the ground under the receiver's tangent plane is the solid the receiver sits on and
//     sends nothing (nlp's convention: its indirect radiance U starts at the tangent plane);
//   - every directional light where its disk is visible (radiance E / (pi sin^2 alpha) over the disk).
// The environment term is computed without noise here, from the horizons of `azimuths` directions
// (bisect_horizon, the reference horizons' one home): per azimuth, the wedge's mean radiance per lat-long row
// (azimuth_wedge_profile) integrated in elevation above the horizon against Y_lm cos e, cumulative row
// integrals from the zenith plus Gauss-Legendre on the partial row (exact for the basis to rounding within a
// row). The terrain and light terms are Monte Carlo estimates of the reference's sampler
// (reference/bake_reference.cpp: uniform directions over the normal's hemisphere, paths continued as the
// indirect layer's; uniform points on each light's disk), which also give the layer's standard error.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "env/environment.hpp"

namespace hfbake::reference {

inline constexpr int kShIrradianceCoefficients = 16;
// Coefficients with a non-zero clamped-cosine factor (bands 0..2), times RGB: what is accumulated.
inline constexpr int kShIrradianceSums = 27;
// A_l / pi per coefficient of bands 0..2.
inline constexpr std::array<double, 9> kShIrradianceScale = {1.0,  2.0 / 3, 2.0 / 3, 2.0 / 3, 0.25,
                                                             0.25, 0.25,    0.25,    0.25};

// nlp's channel names: "000.R", "000.G", "000.B", "001.R", ... "015.B".
std::vector<std::string> sh_irradiance_channels();

// The environment's radiance per azimuth wedge and lat-long row, and its cumulative projections: the
// integral from the zenith down to each row's upper edge of L Y_i(e, phi_k) cos e de (i < 9, RGB).
struct ShEnvironmentTable {
  int azimuths = 0, rows = 0;
  std::vector<double> cos_phi, sin_phi;
  std::vector<double> edge;        // rows + 1 elevations, edge[r] = pi / 2 - pi r / rows
  std::vector<double> radiance;    // [(k * rows + r) * 3 + c]
  std::vector<double> cumulative;  // [(k * (rows + 1) + r) * 27 + i * 3 + c]
};
ShEnvironmentTable make_sh_environment_table(const Environment& env, int azimuths);

// Adds to out (27: [i * 3 + c]) the projection of the environment above the horizons: elevation[k] (radians)
// at phi_k = 2 pi k / azimuths, integrated with the periodic trapezoid rule in azimuth. Not yet scaled by
// A_l / pi. Allocates nothing.
void add_sh_environment_above(const ShEnvironmentTable& table, const double* elevation, double* out);

}  // namespace hfbake::reference
