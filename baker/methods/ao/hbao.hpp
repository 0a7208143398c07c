// hbao: the brute-force horizon march, the obscurance family's baseline and LSAO's truth.
//
// Per receiver and per azimuthal direction, march outward in equal steps (bilinear heights) up to a reach.
// Estimator "slab" (default): every sample that rises above the running horizon is a visible vertical slab
// (P4's slab model, Timonen 2013, each slab a vertical half-line on a height field); the elevations between
// the previous horizon maximum and the new one are occluded by it, weighted by rho(x / cos e) (exact distance
// of each ray to the slab) and by the cosine (contract obscurance) or uniform (HBAO) weighting. With falloff
// none and cosine weighting this is P1's Eq. 5 AO of the sampled horizons; it converges to the exact integral
// as K grows and the step shrinks. Estimator "largest_occluder": P3's Eq. 1 with one occluder per direction,
// the visible sample that casts the largest sinT + max(0, sin h - sinT) rho(|h|) (the brute-force reference
// of P3 Fig. 7). Estimator "segment": like slab, but a band's rays meet the straight piece of profile between
// the previous sample and the new horizon sample (slice_integral.hpp), not a vertical slab at the new one.
// Surface "triangles": instead of equal steps on the bilinear surface, the march visits every vertex of the
// profile of the reference's triangulated surface (two triangles per quad split along (i+1, j)-(i, j+1)):
// every column, row and diagonal crossing, plus the end of the reach. With the segment estimator the slice
// integral is then exact for that surface, and hbao converges to the reference's obscurance as K grows
// (tests/ao/bench_obscurance_bias.cpp, 128^2 receivers of the frontier field, R = 16 step, K = 32,
// 1024-sample reference: bias -0.0002, rmse 0.0034 = the reference's noise, against +0.0060 / 0.0093 for
// one-texel steps on the bilinear surface, whose peaks between samples are missed; 1/8-texel bilinear steps:
// -0.0011 / 0.0063, the bilinear surface itself differs). About 2.5 samples per texel of distance instead of
// 1; measured 1.5x hbao's CPU time at 1024^2, K = 16.
#pragma once

#include <vector>

#include "core/direction_blocks.hpp"
#include "core/run_control.hpp"
#include "core/vec.hpp"
#include "field/height_field.hpp"
#include "methods/ao/falloff.hpp"
#include "methods/ao/obscurance_params.hpp"

namespace hfbake {

// One march direction: unit xy vector (texel axes = world axes) towards the occluders, and a relative
// azimuthal weight (its coverage; the weights are normalised by their sum).
// A direction may carry its own step (in texels; 0 = HbaoSettings::step): with LSAO's box pattern, direction
// (a, b) / |(a, b)| and step |(a, b)| put every sample on a texel centre (no interpolation, as P3 5.2).
struct MarchDirection {
  double dx = 1, dy = 0;
  double weight = 1;
  double step = 0;
};
// phi_k = 2 pi k / K from +x towards +y, equal weights (the direction set of docs/contract.md).
std::vector<MarchDirection> uniform_directions(int count);

enum class HorizonEstimator { slab, segment, largest_occluder };
enum class MarchSurface { bilinear, triangles };

struct HbaoSettings {
  Falloff falloff;
  Weighting weighting = Weighting::cosine;
  HorizonEstimator estimator = HorizonEstimator::slab;
  MarchSurface surface = MarchSurface::bilinear;  // triangles: `step` is unused (every profile vertex)
  std::vector<MarchDirection> directions = uniform_directions(16);
  double reach = 0;  // world units marched per direction (clamp fields also stop at their border)
  double step = 1;   // world units between samples
  // largest_occluder only: the fixed tangent sinT (P3 chose -0.85), or the receiver's real tangent per
  // direction (P3's strategy 1); and whether only visible samples (elevation >= running maximum) compete.
  double sin_tangent = -0.85;
  bool real_tangent = false;
  bool visible_only = true;
  bool bent = true;  // compute the bent normal (hbao_field sets it from its output)
};

struct HorizonTexel {
  double occluded = 0;        // occluded measure: obscurance = 1 - occluded (largest_occluder: clamped)
  Vec3 bent_normal{0, 0, 1};  // unit, cosine weighted by (1 - rho) (slab model whatever the estimator);
                              // the normal when HbaoSettings::bent is false
};

HorizonTexel hbao_texel(const HeightField& field, Vec3 normal, int i, int j, const HbaoSettings& s);

// The farm's direction blocks (core/direction_blocks.hpp): hbao_texel sums each block of directions from
// zero in double, adds the blocks in order (as SplitDouble: 48 bits) and finishes; `hfbake merge` adds
// blocks baked on other machines the same way, so both give the same bits.
struct HbaoSums {
  SplitDouble occluded;  // sum over the directions of weight * occluded measure
  SplitDouble bent[3];   // sum of weight * the open direction (when HbaoSettings::bent)
};
HbaoSums hbao_texel_sums(const HeightField& field, Vec3 n, int i, int j, const HbaoSettings& s, int d0,
                         int d1);
void hbao_add_sums(HbaoSums& total, const HbaoSums& block);
double hbao_weight_sum(const HbaoSettings& s);  // of every direction, in order
HorizonTexel hbao_finish(const HbaoSums& sums, double weight_sum, Vec3 n, const HbaoSettings& s);
// Block `block` of the whole field: per texel the block's occluded sum (hi, lo) and (bent_xyz not null) bent
// sums (X hi, X lo, Y hi, ...), normals from the heights (normal_at); and the whole field's finish from the
// summed blocks.
void hbao_field_block(const HeightField& field, const HbaoSettings& s, int block, const RunControl& rc,
                      float* occluded, float* bent_xyz);
void hbao_field_finish(const HeightField& field, const HbaoSettings& s, const float* occluded,
                       const float* bent_sums, float* obscurance, float* bent_xyz);

// Whole field, rows in parallel (deterministic). obscurance / bent may be null.
void hbao_field(const HeightField& field, const std::vector<Vec3f>& normals, const HbaoSettings& s,
                const RunControl& rc, float* obscurance, float* bent_xyz);

// The reach used when the job gives none: the falloff's support (rho < 1e-4), or for falloff none the whole
// field (its diagonal when clamped, one period when it repeats).
double default_reach(const FieldShape& field, const Falloff& f);

// Reads and checks an hbao bake entry (schemas/methods/hbao.schema.json); the layers are the reader's
// (Params::layers).
HbaoSettings read_hbao_settings(Params& in, const FieldShape& field);

}  // namespace hfbake
