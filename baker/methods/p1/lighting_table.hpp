// P1's environment lighting tables (Section 6.2, Eq. 6-7). For azimuthal swath k (width 2 pi / K centred
// on phi_k), a normal N is split into its projection onto the vertical plane of phi_k -- length
// |N_p| = sqrt((N.d_k)^2 + N_z^2), angle theta_n = atan2(N.d_k, N_z) from the zenith towards d_k -- and
//   L_p^k(theta_n, theta_h) = (1/pi) * integral over the swath of
//                             integral_0^min(theta_n + pi/2, theta_h) L(theta, phi) sin(theta) cos(theta -
//                             theta_n)
//   E_direct / pi = sum_k |N_p| L_p^k(theta_n, theta_h,k)        (theta_h,k = pi/2 - horizon elevation)
// The azimuthal integral is exact per lat-long row (azimuth_wedge_profile); the polar integral is exact
// for the row-wise constant radiance (closed form of sin(t) cos(t - theta_n)). The table is sampled at
// normal_bins values of theta_n in [-pi/2, pi/2] (odd counts include theta_n = 0 exactly) and
// horizon_bins + 1 values of theta_h in [0, pi], and read with bilinear interpolation.
#pragma once

#include <vector>

#include "core/vec.hpp"
#include "env/environment.hpp"

namespace hfbake::p1 {

struct LightingTables {
  int directions = 0, normal_bins = 0, horizon_bins = 0;
  std::vector<Rgb> data;  // [(k * normal_bins + i) * (horizon_bins + 1) + j]

  // Bilinear lookup for direction k at theta_n in [-pi/2, pi/2], theta_h in [0, pi] (clamped).
  Rgb lookup(int k, float theta_n, float theta_h) const {
    const float a = (theta_n + 1.57079632679f) * float(normal_bins - 1) * 0.318309886f;
    const float b = theta_h * float(horizon_bins) * 0.318309886f;
    int i = int(a), j = int(b);
    i = i < 0 ? 0 : (i > normal_bins - 2 ? normal_bins - 2 : i);
    j = j < 0 ? 0 : (j > horizon_bins - 1 ? horizon_bins - 1 : j);
    float fa = a - float(i), fb = b - float(j);
    fa = fa < 0 ? 0 : (fa > 1 ? 1 : fa);
    fb = fb < 0 ? 0 : (fb > 1 ? 1 : fb);
    const std::size_t row = std::size_t(horizon_bins) + 1;
    const Rgb* p = data.data() + (std::size_t(k) * normal_bins + i) * row + j;
    const Rgb lo = p[0] * (1 - fb) + p[1] * fb;
    const Rgb hi = p[row] * (1 - fb) + p[row + 1] * fb;
    return lo * (1 - fa) + hi * fa;
  }
};

// The exact alternative to the binned tables (the default, normal_bins = 0): since
// |N_p| cos(theta - theta_n) = N_z cos(theta) + N_p sin(theta), Eq. 7 factorises into two 1D integrals per
// swath, and with theta_k = min(theta_h, pi/2 + atan(N_p / N_z)) clamped per texel
//   |N_p| L_p^k(theta_n, theta_h) = N_z A_k(theta_k) + N_p B_k(theta_k),
//   A_k(t) = (2/K) int_0^t Lbar_k sin cos,   B_k(t) = (2/K) int_0^t Lbar_k sin^2
// with Lbar_k the swath's mean radiance per lat-long row. Both are evaluated exactly for the row-wise
// constant radiance (prefix sums at row edges plus the partial row in closed form): no normal or horizon
// bins at all. For a uniform environment this is exactly L times the uniform-sky formula of p1.hpp.
struct SwathProfiles {
  int directions = 0, rows = 0;
  std::vector<Rgb> radiance;  // [k * rows + r]: the swath's mean radiance in row r
  std::vector<Rgb> pa, pb;    // [k * rows + r]: A_k, B_k at the start of row r
  std::vector<float> sa, sb;  // [r]: sin^2 t_r and t_r - sin t_r cos t_r at the start of row r

  // N_z A_k(theta) + N_p B_k(theta), given theta in [0, pi] and its sine and cosine.
  Rgb eval(int k, float theta, float st, float ct, float nz, float np) const {
    int r = int(theta * float(rows) * 0.318309886f);
    r = r < 0 ? 0 : (r >= rows ? rows - 1 : r);
    const std::size_t i = std::size_t(k) * rows + r;
    const float w = (nz * (st * st - sa[r]) + np * ((theta - st * ct) - sb[r])) * inv_k;
    return pa[i] * nz + pb[i] * np + radiance[i] * w;
  }
  float inv_k = 1;
};

SwathProfiles build_swath_profiles(const Environment& env, int directions);

// Builds the tables of `directions` swaths for env (normal_bins >= 2, horizon_bins >= 1). Parallel over k.
LightingTables build_lighting_tables(const Environment& env, int directions, int normal_bins,
                                     int horizon_bins);

// The exact value the table samples, for tests: L_p^k(theta_n, theta_h) from the lat-long rows.
Rgb lighting_table_exact(const Environment& env, int directions, int k, double theta_n, double theta_h);

}  // namespace hfbake::p1
