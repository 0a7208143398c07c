// The slab integral of far-field ambient obscurance (P4 Eq. 3, the table L), for an orthographic height
// field where every slab is a vertical half-line going down (P4, Timonen 2013, on an orthographic height
// field): in the slice of azimuth D, rays at elevations in [a, b] that hit a slab at horizontal distance x
// (world units) are occluded with weight
//     band(a, b, x) = integral_a^b rho(x / cos e) max(0, nt cos e + nz sin e) cos e de
// (nt, nz) = (n.D, n.z), the receiver normal in the slice. The obscurance of K equally weighted slices is
// 1 - (2/K) sum_k sum_slabs band. Splitting at the tangent elevation t = atan2(-nt, nz):
//     band = nt [A(b', x) - A(a', x)] + nz [B(b', x) - B(a', x)],   a' = max(a, t), b' = max(b, t)
//     A(e, x) = integral_{-pi/2}^e rho(x / cos e') cos^2 e' de',  B(e, x) = same with sin e' cos e'.
// A and B are closed forms for falloff none and step; the other falloffs are tabulated once per bake on a
// (elevation, distance) grid and interpolated bilinearly (max error < 1e-5, tests/ao/test_farfield.cpp).
#pragma once

#include <vector>

#include "methods/ao/falloff.hpp"

namespace hfbake {

class SlabTable {
 public:
  explicit SlabTable(const Falloff& rho, int elevation_nodes = 1025, int distance_nodes = 257);

  // A(e, x) and B(e, x) (see the file comment); e in radians, clamped to [-pi/2, pi/2]; x >= 0 world units.
  void integrals(double e, double x, double* a, double* b) const;
  // The band [a, b] (radians, a <= b) hidden by a slab at distance x, for the slice normal (nt, nz) whose
  // tangent elevation is t = atan2(-nt, nz).
  double band(double a, double b, double x, double nt, double nz, double t) const;

  const Falloff& falloff() const { return rho_; }

 private:
  double to_u(double x) const;  // distance -> table coordinate in [0, 1]
  Falloff rho_;
  int ne_ = 0, nu_ = 0;
  bool compact_ = false;       // rho = 0 beyond radius: u = x / R; otherwise u = x / (x + R)
  std::vector<double> a_, b_;  // [iu * ne_ + ie]
};

// Direct numerical integration of the band (adaptive Simpson; slow): for tests.
double slab_band_reference(const Falloff& rho, double a, double b, double x, double nt, double nz);

}  // namespace hfbake
