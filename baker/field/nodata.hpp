// Missing heights (NaN/Inf, or a nodata value) in real elevation models.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "field/height_field.hpp"

namespace hfbake {

struct NodataScan {
  std::size_t count = 0;           // texels without a valid height
  int first_i = -1, first_j = -1;  // the first one in row-major order
};

// Texels that are not finite, or equal to `nodata_value` when given.
NodataScan scan_nodata(const HeightField& field, std::optional<float> nodata_value);

// Fills every missing texel from its nearest valid ones: holes are filled in waves from their rims
// inwards, each texel taking the mean of its already-valid 8-neighbours. Deterministic (no threads), O(n).
// Returns false if the field has no valid texel at all.
bool fill_nodata(HeightField& field, std::optional<float> nodata_value);

}  // namespace hfbake
