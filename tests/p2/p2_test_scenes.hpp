// What several p2 tests and measurements share: a field rough at the texel scale, and p2 with its defaults.
#pragma once

#include <random>

#include "field/height_field.hpp"
#include "methods/p2/bake_p2.hpp"

namespace hfbake {

// White noise of `sigma` world units a texel on a side x side clamp field of unit texels (sigma 1.8: 60-70
// degrees between neighbours), from `seed`.
inline HeightField white_noise_field(int side, unsigned seed = 2, float sigma = 1.8f) {
  HeightField f;
  f.width = f.height = side;
  f.z.resize(f.texel_count());
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, sigma);
  for (float& z : f.z) z = noise(rng);
  return f;
}

// p2 with its defaults at K directions and one bounce, its direct, indirect and total layers: what the
// stepped-hill measurement and test (docs/methods/p2.md "Steps") score against the reference.

inline LayerSet bake_p2_defaults(const Scene& scene, int K) {
  P2Params p;
  p.directions = K;
  p.bounces = 1;
  p.keep_bounces = false;
  p.layers = {"direct", "indirect", "total"};
  return p2_layers(p, 1, compute_p2(scene, p, RunControl{}));
}

}  // namespace hfbake
