// The row-run lighting for the baseline instruction set (SSE2), the choice of kernel, and the environment
// light the kernels share (row_shading.hpp).
#include "methods/p1/row_shading.hpp"

#include <cmath>

#include "methods/p1/fast_math.hpp"

namespace hfbake::p1 {

namespace {
#include "methods/p1/row_shading_kernel.inc"
}  // namespace

void shade_row_sse2(const ShadeRowTarget& t, const ShadeRowRun& run) {
  shade_row_body(t, run);
}

ShadeRowFn shade_row_kernel(LaneIsa isa) {
  switch (isa == LaneIsa::best ? lane_isa() : isa) {
    case LaneIsa::avx512:
      return shade_row_avx512;
    case LaneIsa::avx2:
      return shade_row_avx2;
    default:
      return shade_row_sse2;
  }
}

Rgb table_light(const LightingTables& tables, int k, float np, float nz, float e) {
  const float len = std::sqrt(np * np + nz * nz);
  return tables.lookup(k, fast_atan(np / nz), kHalfPiF - e) * len;
}

Rgb profile_light(const SwathProfiles& profiles, int k, float theta, float st, float ct, float nz, float np) {
  return profiles.eval(k, theta, st, ct, nz, np);
}

}  // namespace hfbake::p1
