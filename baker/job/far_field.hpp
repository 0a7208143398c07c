// The far field of a horizon method (relief, p1): out to `beyond` world units every texel's own heights,
// beyond it the cells of a coarsened copy of the field (field/coarse_heights.hpp), taken so that horizons can
// only rise: HORAYZON's distant-terrain simplification (Steger et al. 2022). What makes a method's reach
// bounded, so a raster larger than memory bakes in tiles with a halo of `beyond` (docs/large-fields.md).
#pragma once

#include <limits>
#include <optional>

#include "field/height_field.hpp"
#include "job/params.hpp"

namespace hfbake {

struct FarFieldSpec {
  double beyond = 100;  // world units (default: 100 texels)
  int cell = 8;         // texels along a coarse cell's side
};

// Reads the entry's "far_field" object ({"beyond": D, "cell": C}; absent: none). D at least one texel and
// less than `below` (named by `below_name` in the refusal); on a repeat field C divides its width and height.
std::optional<FarFieldSpec> read_far_field(Params& in, const FieldShape& field,
                                           double below = std::numeric_limits<double>::infinity(),
                                           const char* below_name = "");
// The same for a method whose horizons span the whole field (p1, sun): clamp fields only, since a repeating
// field has no casters beyond its own period.
std::optional<FarFieldSpec> read_field_wide_far_field(Params& in, const FieldShape& field);

// What a method with an optional far field tells the tile plan (MethodInfo::reach and far_cell): its reach
// is `beyond` with one and `otherwise` without; the copy's cell, 0 without one.
inline double far_field_reach(const std::optional<FarFieldSpec>& far, double otherwise) {
  return far ? far->beyond : otherwise;
}
inline int far_field_cell(const std::optional<FarFieldSpec>& far) {
  return far ? far->cell : 0;
}

}  // namespace hfbake
