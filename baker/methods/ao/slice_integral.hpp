// Integrals over elevation in one vertical azimuthal slice, the building block of the horizon-based methods.
//
// In the slice of azimuth direction D (towards the occluders), a direction at elevation e is
// w(e) = (cos e * D, sin e); the receiver normal projects to (nt, nz) = (n.D, n.z). With the solid angle
// dw = cos e de dphi, the cosine-weighted occluded measure (docs/contract.md) of a band [a, b] of elevations
// whose rays all hit a vertical slab at horizontal distance x (P4's slab model, Timonen 2013) is
//     C = integral_a^b rho(x / cos e) max(0, nt cos e + nz sin e) cos e de
// and the obscurance of K equally weighted slices is 1 - (2/K) sum_k sum_bands C. The uniform (solid-angle,
// HBAO) measure is U = integral over [max(a, t), b] of rho(x / cos e) cos e de with t the tangent elevation,
// and the occluded fraction is (1/K) sum_k sum_bands U (HBAO's mean_k (sin h_k - sin t_k) when rho = 1).
#pragma once

#include "methods/ao/falloff.hpp"
#include "methods/ao/obscurance_params.hpp"

namespace hfbake {

struct SliceFrame {
  double nt = 0, nz = 1;  // normal components along D and up
  double tangent = 0;     // elevation of the tangent plane towards D: atan2(-nt, nz), in (-pi/2, pi/2)
};
SliceFrame slice_frame(double nt, double nz);

struct SliceVec {
  double h = 0, v = 0;  // along D, up
};

// Occluded measure of the band [a, b] (radians) hidden by a slab at horizontal distance x (world units).
double band_occlusion(const Falloff& f, Weighting w, const SliceFrame& s, double a, double b, double x);
// rho-weighted cosine-weighted direction integral of the band: integral rho max(0, n.w) w cos e de.
SliceVec band_direction(const Falloff& f, const SliceFrame& s, double a, double b, double x);
// The same with rho = 1 (closed form): the cosine-weighted direction integral of a band of open sky.
SliceVec open_direction(const SliceFrame& s, double a, double b);

// The band [a, b] when its rays meet the straight segment from A to B (slice points relative to the
// receiver: h = horizontal distance, v = height; 0 <= A.h < B.h) instead of a vertical slab at B: each ray of
// elevation e hits the segment's line at distance cross(A, B - A) / cross(w(e), B - A). Exact for a polyline
// profile (the triangulated surface along a slice, or straight lines between samples) when b is the new
// horizon at B and a the highest elevation of the vertices before B: every ray of the band then passes
// above the profile up to A and meets it first on this segment. Step falloff: closed form (the segment's
// part inside the radius is an elevation interval); other falloffs: Gauss-Legendre in elevation.
double segment_band_occlusion(const Falloff& f, Weighting w, const SliceFrame& s, double a, double b,
                              SliceVec A, SliceVec B);
SliceVec segment_band_direction(const Falloff& f, const SliceFrame& s, double a, double b, SliceVec A,
                                SliceVec B);

// The closed forms behind band_occlusion and band_direction for falloffs none, step, linear and smooth:
// inside the radius rho(x / cos e) = sum_k coef[k] sec^k e (q = x / R: step 1; linear 1 - q sec e; smooth (1
// - q sec e)^2), so a band's integral is sum_k coef[k] (P_k(hi) - P_k(lo)) with P_k an antiderivative of
// weight(e) sec^k e (and, for the direction, of the cosine weight times (cos e, sin e) sec^k e). A chain of
// adjacent bands evaluates each end once (lsao_chain_hull.hpp).
struct SlabPrimitives {
  double occ[3] = {0, 0, 0};                  // the weighting's measure
  double h[3] = {0, 0, 0}, v[3] = {0, 0, 0};  // the cosine-weighted direction (band_direction)
};
// The falloff's degree in sec e (0 none and step, 1 linear, 2 smooth; -1: no closed form) and its
// coefficients for a slab at horizontal distance x < R (none: coef {1}).
int slab_degree(const Falloff& f);
void slab_coefficients(const Falloff& f, double x, double coef[3]);
// P_k at elevation e in [s.tangent, pi/2) given sin e and cos e (> 0), for k <= degree; direction: also h, v.
SlabPrimitives slab_primitives(const SliceFrame& s, Weighting w, double e, double sin_e, double cos_e,
                               int degree, bool direction);

}  // namespace hfbake
