// Far-field ambient obscurance (P4, Timonen, HPG 2013) on an orthographic height field.
//
// Per azimuth phi_k = 2 pi k / K (occluders towards D_k = (cos phi_k, sin phi_k)):
// 1. Scan: parallel lines along D_k, one texel apart, sampled every texel (bilinear heights) on a global
//    along-coordinate s, so that intervals of B0 samples are aligned across lines. Per interval: m0 = max z
//    and m1 = max (z - s) (world units). The virtual point of an interval is the corner of these two
//    supporting lines, (s*, z*) = (m0 - m1, m0): a single sample returns itself, and an interval holding
//    a vertical wall returns exactly the wall's top (for the rising 45-degree line z - s; P4's descending
//    line z + s would put it at the far end of the plateau behind the wall).
// 2. The 1D max pyramid: level n holds intervals of B0 2^n samples, parents the max of their children.
// 3. Prefix sums of (m0, m1, count) across lines for every interval of every level, so that the mean over
//    the lines inside the receiver's sector at that distance costs O(1) (P4 §7; optionally two half
//    sectors per direction, P4's "K x 2"). Clamp fields: lines outside the field do not count.
// 4. Per texel: near field by an exact march (one texel steps, every sample its own slab) up to the first
//    aligned interval at least `near_field` texels away (P4 §9: 1.5 B0), then outwards the largest aligned
//    pyramid interval no longer than growth x its distance (O(log N) intervals), each virtual point a
//    slab if it rises above the horizon so far; the slabs' bands come from SlabTable (P4's table L).
// Result: obscurance = 1 - (2/K) sum_k sum_slabs band, the cosine-weighted obscurance of docs/contract.md.
#pragma once

#include <cstdint>
#include <vector>

#include "core/run_control.hpp"
#include "core/vec.hpp"
#include "field/height_field.hpp"
#include "job/params.hpp"
#include "methods/ao/falloff.hpp"

namespace hfbake {

struct FarfieldOptions {
  int directions = 16;         // K
  Falloff rho;                 // falloff and radius (world units)
  int interval = 8;            // B0, samples per level-0 interval
  double near_field = -1;      // texels of exact march; < 0: 1.5 * interval
  bool sector_average = true;  // average virtual points over the lines of the sector (P4 §7)
  bool split = true;           // two half sectors per direction (P4 "K x 2"), with sector_average
  double growth = 1.0;         // far-field interval length <= growth * its distance (pyramid traversal)
  // Near field on the reference's triangulated surface (every column, row and diagonal crossing, each band
  // hit on its segment; triangle_profile.hpp) instead of one-texel bilinear steps, which miss the peaks
  // between samples (hbao's measurement: +0.006 too open on a rough fractal at R = 16).
  bool triangles = false;
};

struct FarfieldStats {
  std::uint64_t near_samples = 0;    // near-field samples marched
  std::uint64_t virtual_points = 0;  // far-field intervals read (per half sector)
  std::uint64_t texel_directions = 0;
};

// The obscurance (light-like, in [0, 1]) per texel, row-major like field.z. normals: compute_normals(field).
// bent_normal (optional): the bent normal per texel, the normalised cosine-weighted mean open direction of
// the same slabs (each band's directions weighted by 1 - rho, as hbao's), the normal where nothing is open.
std::vector<float> farfield_obscurance(const HeightField& field, const std::vector<Vec3f>& normals,
                                       const FarfieldOptions& options, const RunControl& rc,
                                       FarfieldStats* stats = nullptr,
                                       std::vector<Vec3f>* bent_normal = nullptr);

// The layers straight into the caller's arrays (the sums accumulate there in float, k ascending, and are
// finished in place): light[texel] the obscurance, bent_xyz (optional) [3 * texel + c] the bent normal.
// Holds nothing else per texel: the largest direction's scan (farfield_working_bytes) while it runs.
void farfield_layers(const HeightField& field, const std::vector<Vec3f>& normals,
                     const FarfieldOptions& options, const RunControl& rc, FarfieldStats* stats, float* light,
                     float* bent_xyz);

// Direction block `block` alone (core/direction_blocks.hpp), summed from zero into occluded (and bent_xyz):
// what a shard computes; farfield_layers sums the same blocks (FloatBlocks). farfield_finish turns the sums
// into the layers in place (what farfield_layers does after summing).
void farfield_block_sums(const HeightField& field, const FarfieldOptions& options, int block,
                         const RunControl& rc, float* occluded, float* bent_xyz);
void farfield_finish(const HeightField& field, const std::vector<Vec3f>& normals,
                     const FarfieldOptions& options, float* light, float* bent_xyz);

// Bytes farfield holds beyond its layers for a field of this shape: the largest direction's prefix sums
// over its lines of the interval pyramid (levels the traversal can read only) and a chunk of raw maxima.
double farfield_working_bytes(const FieldShape& field, const FarfieldOptions& options);

// The occluded measure (1 - obscurance, before clamping) at the given texels only (row-major indices):
// for tests and measurements that need a few receivers of a large field.
std::vector<double> farfield_occlusion_at(const HeightField& field, const std::vector<Vec3f>& normals,
                                          const FarfieldOptions& options,
                                          const std::vector<std::size_t>& texels,
                                          FarfieldStats* stats = nullptr);

// Reads and checks a farfield bake entry (schemas/methods/farfield.schema.json).
FarfieldOptions read_farfield_options(Params& in);

}  // namespace hfbake
