// Reference sh_visibility: the order-4 real SH projection (sh_environment.hpp's basis, nlp's convention) of
// V over the whole sphere, from the reference horizons (horizon_reference.hpp), independently of nlp.
//
// From a point of a height field, visibility along an azimuth is monotone in elevation, so over the sphere
// V(e, phi) = [e > h(phi)], h the horizon elevation found by Embree bisection (the skirt counts as terrain,
// as for the reference horizons). Then
//   c_i = int_0^{2 pi} dphi int_{h(phi)}^{pi/2} Y_i(cos e cos phi, cos e sin phi, sin e) cos e de.
// The elevation integral is Gauss-Legendre on [h, pi/2] (the integrand is a trigonometric polynomial of
// degree at most 4 in e: 10 nodes are exact to rounding); the azimuth integral is the periodic trapezoid rule
// over `azimuths` horizons phi_k = 2 pi k / azimuths (spectrally accurate where h is smooth, first order
// across a jump of h: docs/methods/reference.md).
#pragma once

#include <array>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/height_field.hpp"

namespace hfbake {

// The projection for one receiver whose horizon elevations (radians) at phi_k = 2 pi k / K are `elevation`.
std::array<double, 16> sh_visibility_of_horizons(const std::vector<double>& elevation);

// Every texel's projection, 16 floats a texel ([texel * 16 + i]).
std::vector<float> trace_reference_sh_visibility(const HeightField& field, int azimuths, const RunControl& rc,
                                                 int iterations = 24);

// Adds "sh_visibility" to a reference's layers when one of `methods` bakes it (16 channels, named as the
// method's); nothing when no method bakes it or the reference has it already.
void add_reference_sh_visibility(const HeightField& field, const std::vector<const LayerSet*>& methods,
                                 LayerSet& reference, const RunControl& rc, int azimuths = 128);

}  // namespace hfbake
