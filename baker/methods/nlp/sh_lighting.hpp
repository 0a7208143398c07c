// Distant lighting in order-4 SH: the environment's projection (NS09 §7's L).
#pragma once

#include <array>

#include "env/environment.hpp"
#include "methods/nlp/sh.hpp"

namespace hfbake::nlp {

// SH coefficients of the environment's radiance, per colour channel (R, G, B). Integrates the lat-long
// texel by texel (the first mip level with at most 128 rows; mips preserve the sphere integral), each texel's
// mean radiance times the exact integral of Y_i over the texel (3 x 3 Gauss-Legendre in theta and phi).
// Any environment kind works: a uniform one carries its constant stand-in lat-long.
std::array<sh::Coeffs, 3> project_environment(const Environment& env);

}  // namespace hfbake::nlp
