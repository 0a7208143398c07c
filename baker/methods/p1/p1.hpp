// P1 (Timonen & Westerholm 2010, "Scalable Height Field Self-Shadowing") as reusable library functions:
// exact horizons by the convex-hull stack on the shared line sweep, and the lighting computed from them
// at every texel's normal. bake_p1 (bake_p1.hpp) is the CLI entry; P2 calls compute_p1 for direct light
// and horizons from the same sweep.
//
// Per texel and direction k (phi_k = 2 pi k / K), with horizon elevation e_k (exact on the triangulated
// surface: on clamp fields the steepest crossing of the texel's ray by the lane search, lane_horizons.hpp; on
// repeat fields the larger of the near-field march and the far field of its strip, far_horizons.hpp), normal
// N, N_p = N.d_k, theta_k = min(pi/2 - e_k, pi/2 + atan(N_p / N_z)) (P1 Eq. 4 with the pi/2 the extracted
// text drops: the horizon or where the normal's hemisphere ends):
//   ao    = (1/K) sum_k [ N_z sin^2 theta_k + N_p (theta_k - sin theta_k cos theta_k) ]
//           P1 Eq. 5, except that the azimuthal integral of N_p over each swath uses the midpoint rule
//           (2 pi / K) instead of Eq. 5's exact 2 sin(pi / K): the same limit, but spectrally accurate for
//           smooth horizons, so a plane of any slope gives 1 to float rounding (Eq. 5 leaves O(1/K^2)).
//   vsky  = 1 - (1/K) sum_k sin(max(e_k, 0))
//   direct (E/pi, RGB) = sum_k |N_p| L_p^k(theta_n, pi/2 - e_k)  (lighting_table.hpp). Default
//           (normal_bins = 0): evaluated exactly as N_z A_k(theta_k) + N_p B_k(theta_k) (SwathProfiles), so
//           a uniform environment gives exactly L * ao; normal_bins = 7, 15, ...: P1's binned tables. Plus
//           each directional light: irradiance * max(N.l, 0) / pi times the fraction of its disk above the
//           horizon in the light's own azimuth (an extra sweep direction per light, so sun shadows are as
//           sharp as the field).
//   bent_normal = normalize(sum_k integral over the visible part of the swath of w (N.w) dw)
//   horizon = sin e_k per direction; horizon_distance = world distance to the caster (+inf: none).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "job/far_field.hpp"
#include "job/params.hpp"
#include "methods/p1/far_floor.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake {

struct P1Params {
  int directions = 64;     // K
  int normal_bins = 0;     // 0: exact factorised tables; odd >= 3: P1's theta_n bins (odd: up is exact)
  int horizon_bins = 256;  // theta_h resolution of the lighting tables over [0, pi]
  int wrap_periods = 1;    // repeat mode warm-up (see SweepSpec)
  // Texels: horizons marched exactly from each texel center this far (horizon_sweep.hpp).
  double near_radius = 2;
  // The far field's certified accuracy (far_horizons.hpp): every horizon's sine within this of the exact
  // one, never above it; 0: exact (docs/methods.md, p1, for the speed it buys).
  double horizon_tolerance = 0;
  // Casters beyond far_field.beyond bounded from above by the coarse copy's floor (far_floor.hpp): every
  // horizon at least the exact one and at most P1Result::far_field_bound above it; what makes p1 bake in
  // tiles (docs/large-fields.md). Clamp fields. None: the exact search over the whole field.
  std::optional<FarFieldSpec> far_field;
  bool ao = true, vsky = true, direct = true;
  bool horizon = false, horizon_distance = false, bent_normal = false;
  bool lights = true;  // add the scene's directional lights to direct
  // Also the direct light of each texel's corner facets at the texel (P1Result::direct_facets): the same
  // horizons, the facets' own normals. P2's senders radiate with them (the reference shades every hit with
  // its facet).
  bool facet_direct = false;
  // P1Result::horizon by direction, [k * texels + texel], instead of by texel: what a per-direction
  // consumer (P2's lobe split) reads without striding across K floats per texel.
  bool horizon_by_direction = false;
  // The receivers' normals from Scene::normals instead of normal_at (not a job parameter): P2 on a
  // subdivided field (P2Params::subdivide), whose original texels keep the original field's normals.
  bool scene_normals = false;
};

// The layers as the EXR stores them (interleaved per texel), so bake_p1 hands them on without a copy.
struct P1Result {
  int width = 0, height = 0, directions = 0;
  std::vector<float> ao, vsky;  // per texel (empty when not requested)
  std::vector<float> direct;    // E_direct / pi, RGB: [3 * texel + c]
  std::vector<float> horizon;   // sin(elevation), [texel * K + k] (horizon_by_direction: [k * N + texel])
  std::vector<float> horizon_distance;  // world units, [texel * K + k]
  std::vector<float> bent_normal;       // unit, world frame: [3 * texel + c]
  // E_direct / pi at the texel, at the normals of the six triangles of the reference's surface that meet
  // there (field/triangulation.hpp corner_facet_normals): [kCornerFacets * texel + c], c in kCornerFacet's
  // order (0 and 1 the texel's own facets). Empty unless P1Params::facet_direct.
  std::vector<Rgb> direct_facets;
  // With P1Params::far_field: the largest amount (in slope, rise over run) by which any horizon's tangent
  // exceeds the exact one's (far_floor.hpp): a certified bound, each texel's sine and elevation within it.
  std::optional<double> far_field_bound;

  Rgb direct_at(std::size_t texel) const {
    return {direct[3 * texel], direct[3 * texel + 1], direct[3 * texel + 2]};
  }
  Vec3f bent_normal_at(std::size_t texel) const {
    return {bent_normal[3 * texel], bent_normal[3 * texel + 1], bent_normal[3 * texel + 2]};
  }
};

// corner_facet_normals (field/triangulation.hpp) gives the normals of P1Result::direct_facets.

// Reads the bake entry (schemas/methods/p1.schema.json) with every check (even normal_bins, unknown
// layers), recording the resolved values in `in` (layers in the order written).
P1Params read_p1_params(Params& in, const FieldShape& field);
// Every layer p1 can write.
const std::vector<std::string>& p1_layer_names();

// Reads the scene's heights, environment and lights only (normals are recomputed per tile with
// normal_at, or read from Scene::normals with P1Params::scene_normals; else Scene::normals and the surface
// may be empty). Memory: the requested layers (4 bytes per texel
// and channel; direct from a uniform sky also its 4-byte ao sum) plus the sweep's bounded line buffers:
// p1_working_bytes.
P1Result compute_p1(const Scene& scene, const P1Params& params, const RunControl& rc);

// The farm's direction blocks (core/direction_blocks.hpp): compute_p1 sums each block of directions from
// zero (p1_direction_sums), adds the blocks in order (p1_add_sums) and finishes (p1_finish: the means, the
// bent normal, direct from the sums, then the directional lights' own sweeps). `hfbake merge` does the same
// with blocks baked on other machines, so both give the same bits.
struct P1Sums {
  int k_begin = 0, k_end = 0;  // the directions summed
  // Per texel, each direction's term summed (empty when not needed): ao's and vsky's, direct's RGB
  // [3 * texel + c] for a non-uniform environment, the bent normal's [3 * texel + c], and P2's corner-facet
  // sums [c * N + texel] (fao: uniform environment; fdr, fdg, fdb: otherwise).
  std::vector<float> ao, vsky, rgb, bent, fao, fdr, fdg, fdb;
  // The horizons of directions [k_begin, k_end): [texel * n + k - k_begin] (horizon_by_direction:
  // [(k - k_begin) * N + texel]), n = k_end - k_begin; p1_finish wants all K in P1Result's layout.
  std::vector<float> horizon, horizon_distance;
  double far_slack = 0;  // with a far field: the largest slack of the floors the directions took
};
// Floats a texel of each sum p1_direction_sums keeps for these parameters and this scene's environment
// (0: not kept); the corner-facet sums' [c * N + texel] count kCornerFacets.
struct P1SumsShape {
  std::size_t ao = 0, vsky = 0, rgb = 0, bent = 0, fao = 0, fd = 0;  // fd: each of fdr, fdg, fdb
};
P1SumsShape p1_sums_shape(const Scene& scene, const P1Params& params);
// Directions [k_begin, k_end) of params.directions. horizon_out / distance_out (optional, N * K floats in
// P1Result's layout): write the horizons there instead of into the returned sums.
P1Sums p1_direction_sums(const Scene& scene, const P1Params& params, int k_begin, int k_end,
                         const RunControl& rc, float* horizon_out = nullptr, float* distance_out = nullptr);
// The farm's form of the sums: each non-empty one moved into `out` as the float layer of its name ("ao",
// "vsky", "rgb", "bent", "fao", "fdr", "fdg", "fdb"; channels from its size per texel of out's field), and
// back (the layers' data moved out): every sum of `shape` must be there with its size, else an InputError
// (core/direction_blocks.hpp take_block_layer). The horizons are not touched.
void p1_sums_to_layers(P1Sums& s, LayerSet& out);
void p1_sums_from_layers(LayerSet& sums, const P1SumsShape& shape, P1Sums& s);
// total += block, elementwise (the horizons are not touched); total.k_end = block.k_end.
void p1_add_sums(P1Sums& total, const P1Sums& block);
P1Result p1_finish(const Scene& scene, const P1Params& params, P1Sums&& sums, const RunControl& rc);

// Bytes compute_p1 holds at peak beyond the layers it returns, for the memory estimate: per texel the sums
// beside the layers (the ao sum behind direct from a uniform sky when ao is not requested, one direction
// block's sums, P2's facet sums and their layer), plus, on clamp fields, the lane search's normals, slopes
// and layout, and on repeat fields the strip search's sweep of one direction block (sweep_buffer_bytes of
// p1_block_sweep_spec) and each thread's FarHorizonWorker.
double p1_working_bytes(const FieldShape& field, const P1Params& params, bool uniform_environment = false);
// The strip search's sweep (repeat fields): FarHorizonWorker's strips, no line heights, 8 directions a batch.
SweepSpec p1_sweep_spec(const P1Params& params);
// The sweep compute_p1 runs for directions [k_begin, k_end) of params.directions on a repeat field: one
// direction block's (core/direction_blocks.hpp), p1_sweep_spec at those directions' azimuths.
SweepSpec p1_block_sweep_spec(const P1Params& params, int k_begin, int k_end);

// Each texel's horizon at arbitrary azimuths, exactly as p1 computes its K directions' (radians from +x
// towards +y): on clamp fields the lane search's exact horizon over the texel's own ray; on repeat fields
// the larger of the exact near field marched from the texel centre (params.near_radius) and the exact far
// field on the texel's own ray, a sweep per azimuth (params.horizon_tolerance either way).
// visit(a, i, j, elevation) runs once per azimuth index a and texel (elevation in radians, -pi/2 where
// nothing lies behind), texels in parallel, and for one texel in a fixed order of a (clamp fields: the
// azimuths nearer the x axis first, each group ascending; repeat fields: ascending), so per-texel sums in
// the visitor's own storage are deterministic.
using HorizonVisitor = std::function<void(int a, int i, int j, float elevation)>;
// curvature: Scene::curvature (clamp fields; repeat fields are flat).
// floor: with P1Params::far_field, the coarse copy's floor (far_floor.hpp) each horizon is raised to, and
// the largest slack it left stored in *slack (when given).
void p1_horizons_at(const HeightField& field, const P1Params& params, const std::vector<double>& azimuths,
                    const RunControl& rc, const HorizonVisitor& visit, double curvature = 0,
                    const p1::FloorGrid* floor = nullptr, double* slack = nullptr);

// With params.far_field: the scene's floor grid over its window's coarse copy (Scene::window) or, when the
// scene has none, over a copy of its own field (held in `own`), each point lowered by `curvature` (the
// horizons' own). Null without a far field.
std::unique_ptr<p1::FloorGrid> p1_floor_grid(const Scene& scene, const P1Params& params, CoarseHeights& own,
                                             double curvature);

// Fraction of a light disk of angular radius `radius` (radians) centred at elevation `elevation` that lies
// above a horizon at elevation `horizon` (a straight horizon across the disk). radius 0: a step.
double disk_fraction_above(double elevation, double horizon, double radius);

}  // namespace hfbake
