// The environment band-limited to real spherical harmonics of order 4 (bands l = 0..3, 16 coefficients per
// colour channel), for judging the SH methods on visibility alone (NS09, Figure 10): the reference lit by
// exactly the lighting those methods can represent.
#pragma once

#include <array>

#include "env/environment.hpp"

namespace hfbake::reference {

inline constexpr int kShCoefficients = 16;

// Orthonormal real SH basis at unit direction d, index l (l + 1) + m, world frame (+z up).
std::array<double, kShCoefficients> sh_basis(Vec3 d);

// Projection of the environment's level-0 texels (radiance x solid angle); uniform: exact (band 0 only).
std::array<Rgb, kShCoefficients> project_sh(const Environment& env);

// The band-limited environment: uniform stays uniform; a lat-long becomes a lat-long of the same level-0
// size holding the SH reconstruction at each texel center (signed: ringing below zero is kept, so the
// reference integrates the same function the SH methods do).
Environment band_limited_environment(const Environment& env);

}  // namespace hfbake::reference
