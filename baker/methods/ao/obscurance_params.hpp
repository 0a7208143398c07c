// The keys every obscurance method shares (schemas/methods/obscurance_common.schema.json): falloff, radius,
// weighting, layers. Parsed once into plain values; errors are InputError with the key as "where".
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/layers.hpp"
#include "core/vec.hpp"
#include "methods/ao/falloff.hpp"

namespace hfbake {

// How directions are weighted in the occluded measure: cosine = (1/pi) * integral of rho (n.w) dw (the
// contract's obscurance); uniform = (1/2pi) * solid angle above the tangent plane (HBAO's sin h - sin t).
enum class Weighting { cosine, uniform };

// "falloff" (default "step" when "radius" is given, else "none") and "radius" (world units; required by every
// falloff except none, refused with none, which has no radius).
Falloff parse_falloff(const nlohmann::json& params);
// "weighting": "cosine" (default) or "uniform"; `allow_uniform` false -> "uniform" is an InputError.
Weighting parse_weighting(const nlohmann::json& params, bool allow_uniform);

// Integer key with a default, checked against [lo, hi] (the schema checks too; this guards direct API use).
int int_param(const nlohmann::json& params, const char* key, int fallback, int lo, int hi);
double number_param(const nlohmann::json& params, const char* key, double fallback, double lo, double hi);

// The layers to write: params["layers"] if present (each must be in `known`, else InputError at "layers"),
// else `defaults`.
std::vector<std::string> select_layers(const nlohmann::json& params, const std::vector<std::string>& known,
                                       const std::vector<std::string>& defaults);
bool wants(const std::vector<std::string>& layers, const char* name);

// A method's output, in `layers` order: "bent_normal" from `bent` (one unit vector per texel), every other
// name ("obscurance", "ao") the scalar `light`. width x height texels.
LayerSet obscurance_layers(int width, int height, const std::vector<std::string>& layers,
                           const std::vector<float>& light, const std::vector<Vec3f>& bent);

}  // namespace hfbake
