// The keys every obscurance method shares (schemas/methods/obscurance_common.schema.json): falloff, radius,
// weighting, layers. Parsed once into plain values; errors are InputError with the key as "where".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "core/vec.hpp"
#include "job/params.hpp"
#include "methods/ao/falloff.hpp"

namespace hfbake {

// How directions are weighted in the occluded measure: cosine = (1/pi) * integral of rho (n.w) dw (the
// obscurance of docs/contract.md); uniform = (1/2pi) * solid angle above the tangent plane (HBAO's sin h -
// sin t).
enum class Weighting { cosine, uniform };

// The falloff an obscurance entry writes (MethodConfig::obscurance): `f` when the entry gives "falloff" or
// "radius", else none.
std::optional<Falloff> written_falloff(const Params& in, const Falloff& f);
// "weighting": "cosine" (default) or "uniform"; `allow_uniform` false -> "uniform" is an InputError.
Weighting read_weighting(Params& in, bool allow_uniform);

bool wants(const std::vector<std::string>& layers, const char* name);

// A method's output, in `layers` order: "bent_normal" from `bent` (one unit vector per texel), every other
// name ("obscurance", "ao") the scalar `light`. width x height texels.
// Takes both by value: `light` ends up as the last scalar layer's data (earlier ones copy it), `bent` is
// freed once converted (no second copy of either is held).
LayerSet obscurance_layers(int width, int height, const std::vector<std::string>& layers,
                           std::vector<float> light, std::vector<Vec3f> bent);
// The same with the bent normals already interleaved ([3 * texel + c]): they become the layer, no copy.
LayerSet obscurance_layers_xyz(int width, int height, const std::vector<std::string>& layers,
                               std::vector<float> light, std::vector<float> bent_xyz);

// The farm's direction-block partial sums of a float-summing method (lsao, farfield): layer "sum" (one
// float a texel) and, when `bent`, layer "bent" (three). block_sum_layers makes them (zeroed) and hands out
// their data; take_block_sums moves them out of a merged set (bent empty without "bent_normal").
struct BlockSums {
  LayerSet set;
  float* sum = nullptr;
  float* bent = nullptr;  // null without bent
};
BlockSums block_sum_layers(int width, int height, bool bent);
void take_block_sums(LayerSet&& sums, bool bent, std::vector<float>* sum, std::vector<float>* bent_xyz);

}  // namespace hfbake
