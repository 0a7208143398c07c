// Line-sweep ambient obscurance (P3, Timonen 2013) on the shared line sweep (baker/sweep): per azimuth
// phi_k = 2 pi k / K one sweep whose lines carry a hull of occluders, and the sweep brings the per-sample
// values back to the texel centres by its documented two-tap rule. The sweep is O(K) per texel whatever the
// radius; the walk of a texel's visible chain grows slowly with it (docs/performance-lsao.md).
// Two tangent strategies (LsaoTangent):
// * receiver (default): each texel's own tangent plane per direction; the slice's value is the
//   contract's measure of the bands between that tangent and the horizon, each weighted by the falloff where
//   its rays meet the terrain (hbao's slab integral), over the visible chain of a per-line chain hull
//   (lsao_chain_hull.hpp). Exact on planes for every falloff; elsewhere within the two-tap rule's
//   interpolation between lines (exact along axes and diagonals), and a texel at a crease over-occludes
//   (docs/job-reference.md, lsao tangent).
// * fixed: P3 as written, the obscurance hull (obscurance_hull.hpp) with P3 Eq. 1 for the single largest
//   occluder and the fixed tangent sin t (strategy 3: a screen-space choice that misses gentle terrain's
//   occlusion).
// Sampling: the sweep's lines step one texel column (row) at a time and interpolate heights along that column
// only, so axis and diagonal directions sample texel centres exactly (P3 §5.2's box pattern for K = 8, n = 1)
// and other directions interpolate between two texels of one column.
// Surface (receiver tangent, LsaoSurface): the column samples lie on cell edges of the
// reference's triangulated surface, but its kinks between them (row and diagonal crossings) are not samples,
// and on rough ground they carry most of the peaks. Measured against hbao on the triangulated surface (the
// exact slice integral), nightly fields, K = 16, step R = 8 (tests/ao/bench_lsao_surface.cpp): each texel's
// own ray over the column crossings only is as far off as the sweep (rmse 0.061 rough, 0.017 terraces), and
// over every crossing 4x closer (0.015, 0.0025, slab estimator): the missed kinks, not the line offset nor
// the hull, were the excess. With `triangles` (default) the line's hull also holds those crossings
// (line_crossings: heights from field/triangulation.hpp), a rising point's band meets the segment from the
// point before it (TangentChain::segments) and each texel marches its own ray over every crossing up to
// near_radius texels (triangle_profile.hpp), where the line's offset from the texel matters most; that near
// field's cost per texel-direction is fixed whatever the radius. `bilinear`: the column samples alone.
//
// Output: obscurance = 1 - clamp(mean_k value_k, 0, 1) (P3 leaves the mapping open). With
// cosine weighting and rho = 1 this converges to the contract's cosine-weighted AO (fixed tangent: of an
// upward normal, sin^2 of the horizon elevation); with uniform weighting to HBAO's solid-angle estimator.
#pragma once

#include <cstdint>
#include <vector>

#include "core/run_control.hpp"
#include "field/height_field.hpp"
#include "job/params.hpp"
#include "methods/ao/obscurance_hull.hpp"

namespace hfbake {

enum class LsaoEstimator {
  hull,           // P3: the obscurance hull, O(1) amortised per sample
  brute_visible,  // per sample, the largest occlusion over the earlier visible samples (O(M^2) per line);
                  // receiver tangent: the band sum over every earlier visible sample (brute_chain)
  brute_all,      // per sample, the largest occlusion over all earlier samples ("the only occluder");
                  // receiver tangent: as brute_visible
};

// Which tangent an occluder must rise above before it counts.
enum class LsaoTangent {
  receiver,  // the texel's own tangent per direction, the visible chain's bands (lsao_chain_hull.hpp)
  fixed,     // P3 strategy 3: OcclusionFunction::sin_t for every receiver (P3's -0.85: a screen-space choice
             // that misses gentle terrain's occlusion; with falloff none and -1 the exact horizon AO)
};

// What a line's hull holds (receiver tangent): its samples (one per column, on the cell edges) alone, or
// also every vertex of the triangulated surface between them (where it crosses a row or a quad's diagonal:
// the kinks the samples miss, which on rough ground hide most of the peaks; tests/ao/bench_lsao_surface).
enum class LsaoSurface { bilinear, triangles };

// The job's default near radius (texels) with surface triangles (measured: tests/ao/bench_lsao_surface).
inline constexpr double kLsaoNearRadius = 4;

struct LsaoOptions {
  int directions = 16;          // K
  OcclusionFunction occlusion;  // falloff, weighting; sin_t: the fixed tangent (LsaoTangent::fixed)
  LsaoTangent tangent = LsaoTangent::receiver;
  double rho_tolerance = 0.1;  // receiver: the chain hull's merge tolerance in rho (lsao_chain_hull.hpp)
  // receiver with a near field (near_radius > 0): the hull's merges are judged from the near field's edge
  // (lsao.cpp), where more of them hold; this finer tolerance keeps its rmse against hbao's exact slice march
  // at or below that of merges judged from the adjacent sample at 0.1, at every radius
  // (docs/performance-lsao.md).
  double near_rho_tolerance = 0.05;
  // receiver, surface triangles: the chain's coalescing tolerance in rho (TangentChain::coalesce): adjacent
  // rising bands weighted within it are integrated as one, so a query adds no more bands at R = 512 than at
  // R = 8 (test_lsao_tangent CoalescedBandsKeepAccuracyAndFlattenTheWork: 2.96 at R 8, 1.53 at R 512 a
  // query; separate 3.12, 3.22), within 4 % of the separate bands' rmse against hbao's exact slice march.
  double band_tolerance = 0.01;
  // receiver: texels (0: none) within which each texel marches its own ray over the triangulated surface
  // (triangle_profile.hpp) instead of reading the line's hull (see the file comment).
  double near_radius = kLsaoNearRadius;
  LsaoSurface surface = LsaoSurface::triangles;  // receiver only
  LsaoEstimator estimator = LsaoEstimator::hull;
  int wrap_periods = 1;  // repeat fields: warm-up periods of the sweep
  // true: each texel is a receiver at its own height (LsaoTangent::receiver always is) (the line's hull
  // queried at the texel's height and the sample's along-distance); false: P3 as written, the line samples
  // are the receivers (interpolated heights) and the sweep blends their results.
  bool texel_receivers = true;
};

struct LsaoStats {
  std::uint64_t samples = 0;     // line samples swept (receivers and warm-up, over all directions)
  std::uint64_t iterations = 0;  // hull loop tests (P3: between samples and 2 x samples)
  // Receiver tangent: texel-direction queries, the steps their walks over the hulls took (a skipped block of
  // points one step) and the bands they added (near field included).
  std::uint64_t queries = 0, walked = 0, bands = 0;
};

// Per texel the sums over the K directions, accumulated in float (one rounding per direction, k ascending,
// by the farm's direction blocks: core/direction_blocks.hpp FloatBlocks; the same bits for any thread count
// and for `hfbake merge` of lsao_block_sums): sum[N] of the per-direction value (before clamping) and, when
// bent_xyz is not null (receiver tangent, or the fixed one's hull estimator with texel receivers; else
// zeros), bent_xyz[3 * texel + c] of the cosine-weighted open direction about the texel's normal,
// unnormalised: receiver tangent: each direction's open band less the chain's bands weighted by rho (as
// hbao); fixed: the band from the tangent plane up to its largest occluder weighted by 1 - rho(|h|).
// Normals: held (compute_normals, 12 bytes a texel) up to 8192^2 texels, recomputed per tap from the heights
// beyond (normal_at: the same values, about 40 % more CPU time): lsao_holds_normals. Nothing else is held
// beyond the two outputs and the sweep's bounded line buffers.
void lsao_sums(const HeightField& field, const LsaoOptions& options, const RunControl& rc, LsaoStats* stats,
               float* sum, float* bent_xyz);
bool lsao_holds_normals(const FieldShape& field);
// Direction block `block` alone (core/direction_blocks.hpp), summed from zero: what a shard computes.
void lsao_block_sums(const HeightField& field, const LsaoOptions& options, int block, const RunControl& rc,
                     float* sum, float* bent_xyz);
// Finishes sums in place into the layers (what lsao_layers does after lsao_sums).
void lsao_finish(const HeightField& field, const LsaoOptions& options, float* light, float* bent_xyz);
// The layers, finished in place from lsao_sums: light[t] = 1 - clamp(sum / K, 0, 1); bent_xyz (optional)
// normalised (the texel's normal where nothing is open).
void lsao_layers(const HeightField& field, const LsaoOptions& options, const RunControl& rc, LsaoStats* stats,
                 float* light, float* bent_xyz);
// Mean over the K directions of the per-direction value (lsao_sums / K), per texel: for tests.
std::vector<double> lsao_mean_occlusion(const HeightField& field, const LsaoOptions& options,
                                        const RunControl& rc, LsaoStats* stats = nullptr);
// lsao_layers into vectors (bent_normal optional): for tests.
std::vector<float> lsao_obscurance(const HeightField& field, const LsaoOptions& options, const RunControl& rc,
                                   LsaoStats* stats = nullptr, std::vector<Vec3f>* bent_normal = nullptr);

// Reads and checks an lsao bake entry (schemas/methods/lsao.schema.json); the layers are the reader's
// (Params::layers).
LsaoOptions read_lsao_options(Params& in);

}  // namespace hfbake
