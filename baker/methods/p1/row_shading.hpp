// The lighting of one row run of texels in one direction from their horizons: the inner loop of p1's
// direction sums (p1.cpp), one source (row_shading_kernel.inc) compiled for SSE2, AVX2 and AVX-512F. Each
// value is the same chain of IEEE multiplies, adds, divides and square roots on every instruction set (no
// fused multiply-add), so the three give the same bits; shade_row_kernel picks by lane_isa().
#pragma once

#include <cstddef>

#include "core/vec.hpp"
#include "field/triangulation.hpp"
#include "methods/p1/lane_horizons.hpp"
#include "methods/p1/lighting_table.hpp"

namespace hfbake::p1 {

// Where a direction block's lighting goes and what it reads for every run: plain pointers into the
// block's sums (null: that sum is not asked for).
struct ShadeRowTarget {
  std::size_t N = 0;                         // texels: the facets' sums and the horizon planes are N apart
  int k_begin = 0;                           // the block's first direction, the horizon planes' first
  const float *cs = nullptr, *sn = nullptr;  // the azimuths' cosines and sines, [k]
  bool uniform_env = true;
  bool normals = true;      // the runs' normals are read (false: they may be null; need_theta and tables
                            // are then off)
  bool need_theta = false;  // the lobe (the horizon's zenith angle against the normal's) is needed
  bool facets = false;      // the corner facets' sums too (fao under a uniform sky, else fdr, fdg, fdb)
  float *ao = nullptr, *vsky = nullptr;                                  // [texel]
  float *rgb = nullptr, *bent = nullptr;                                 // [3 * texel + c]
  float *fao = nullptr, *fdr = nullptr, *fdg = nullptr, *fdb = nullptr;  // [q * N + texel]
  float *hz = nullptr, *hd = nullptr;       // the horizon layers by direction, [(k - k_begin) * N + texel]
  const LightingTables* tables = nullptr;   // a binned environment's direct light
  const SwathProfiles* profiles = nullptr;  // an exact environment's direct light
};

// One run: direction k, texels base .. base + w - 1 (w <= kShadeRun), their normals and horizons.
inline constexpr int kShadeRun = 32;
struct ShadeRowRun {
  int k = 0;
  std::size_t base = 0;
  int w = 0;
  const float *nx = nullptr, *ny = nullptr, *nz = nullptr;
  // The corner facets' normals (facets only; field/triangulation.hpp kCornerFacet's order).
  const float *fx[kCornerFacets] = {}, *fy[kCornerFacets] = {}, *fz[kCornerFacets] = {};
  const float* horizon = nullptr;   // each texel's horizon: its slope (rise / run), or its elevation (rad)
  bool slopes = true;               // which of the two `horizon` holds
  const float* distance = nullptr;  // the horizon_distance layer's values (when hd is set)
};

using ShadeRowFn = void (*)(const ShadeRowTarget&, const ShadeRowRun&);
// The kernel for `isa` (best: lane_isa()); it must be available (lane_isa_available).
ShadeRowFn shade_row_kernel(LaneIsa isa = LaneIsa::best);
void shade_row_sse2(const ShadeRowTarget& t, const ShadeRowRun& run);
void shade_row_avx2(const ShadeRowTarget& t, const ShadeRowRun& run);
void shade_row_avx512(const ShadeRowTarget& t, const ShadeRowRun& run);

// The environment's direct light through the swath of direction k at a normal whose projection on the
// swath's vertical plane is (np, nz), below a horizon of elevation e: from binned tables (table_light) or
// exact profiles (profile_light, given the lobe's theta and its sine and cosine). Compiled once, for the
// baseline instruction set: the kernels call them per texel.
Rgb table_light(const LightingTables& tables, int k, float np, float nz, float e);
Rgb profile_light(const SwathProfiles& profiles, int k, float theta, float st, float ct, float nz, float np);

}  // namespace hfbake::p1
