// A height field subdivided on its own triangulation (field/triangulation.hpp): each quad cut into s x s
// quads, every fine texel the exact height of the coarse triangulated surface there, so the fine
// triangulation (the same split) lies on the coarse facets and the surface is unchanged. Used by p2's
// `subdivide` (docs/methods/p2.md, rough ground).
//
// A clamp field of W x H texels gives (W - 1) s + 1 x (H - 1) s + 1 (the same extent), a repeat field
// W s x H s (the same period); the fine texels are dx / s x dy / s, and fine texel (s i, s j) is coarse
// texel (i, j) with its height. A value carried per coarse texel (albedo, emission) is interpolated the same
// way: the barycentric weights of the coarse facet, as the reference interpolates it over a hit
// (reference/bake_reference.cpp surface_at), so the fine facets' interpolation of the fine values is the
// coarse one.
#pragma once

#include <cstddef>
#include <vector>

#include "core/vec.hpp"
#include "field/height_field.hpp"

namespace hfbake {

// The fine field's shape.
FieldShape subdivided_shape(const FieldShape& coarse, int s);

// The coarse facet's weights at fine texel (fi, fj): the quad's texel (i, j) and facet_weights' corners.
struct FineTexelWeights {
  int i = 0, j = 0;
  FacetWeights w;
};
FineTexelWeights fine_texel_weights(const FieldShape& coarse, int s, int fi, int fj);

HeightField subdivided_field(const HeightField& coarse, int s);
// values[coarse.index(i, j)] interpolated at every fine texel (row-major over subdivided_shape).
std::vector<Rgb> subdivided_values(const HeightField& coarse, int s, const std::vector<Rgb>& values);

// The fine texel of coarse texel (i, j): fine.index(s i, s j).
inline std::size_t fine_index_of(const FieldShape& fine, int s, int i, int j) {
  return std::size_t(s) * std::size_t(j) * std::size_t(fine.width) + std::size_t(s) * std::size_t(i);
}

}  // namespace hfbake
