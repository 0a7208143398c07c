// The CLI entry of method "p2": direct light from P1 (compute_p1, the shared sweep), then `bounces`
// indirect bounces by the convex hull tree intervisibility of P2 (Timonen 2012) with exact per-point
// gathering (P2 §10.1 method 3), emitting surfaces included (P2 Figure 12).
//
//   L_0 = albedo * direct + emission           (exit radiance of a Lambertian surface; direct = E/pi)
//   indirect_b = gather(L_{b-1}),  L_b = albedo * indirect_b   (b = 1..bounces)
//   indirect = sum_b indirect_b,   total = direct + indirect
//
// Each texel's cosine lobe is split once, at the horizon P1 computes: above it P1's sky (direct), below it
// the terrain, whose mean exit radiance P2 gathers from the exactly visible stretches (indirect_sweep.hpp).
// So a uniform furnace closes exactly: direct + indirect -> 1 at every texel as bounces grow.
// Senders (the terrain a receiver sees) radiate per facet of the reference's triangulated surface by
// default: P1 lights each texel's two facets with their own normals at the texel's horizons
// (P1Result::direct_facets), a line segment radiates the length-weighted mean of the facets it crosses
// (indirect_sweep.hpp), and later bounces re-light the facets from each texel's gathered terrain radiance.
// `senders: "texels"` is the method as published: each sender radiates with its texel's smoothed normal.
// On smooth fields the two agree; where the field is rough at the texel scale the facets a receiver sees
// lean towards it (less sky, more bounce light than the smoothed normal says): per-bounce field means
// against the Embree reference on the rough furnace field (tests/accuracy/p2_furnace.json), bounces 1-4:
// texel senders +9.4/-3.7/-13.1/-20.8 %, facet senders with the near field -1.2/+0.3/+1.4/+3.0 %.
// Each line carries the triangulated surface along it exactly (line_profile "exact", default): its column
// samples and every row and diagonal crossing between them (indirect_sweep.hpp, exact_profile). With the
// column samples alone ("columns", the paper's) a line takes the straight segment between two columns for
// the surface and misses its bends; on stepped terrain those are a cliff's top edge and foot, the whole of
// the sweep's bias against the exact gather from the texel centres (terraces, K = 64, measure_p2_centre:
// +0.00096 of a mean 0.039 with "columns", +0.00001 with "exact"; against the reference under a uniform
// sky +1.2 % and -0.2 %, tests/accuracy/senders_terraces.json).
// The receivers of the sweep sit on its lines, up to half a texel from the texel centres; the nearest
// terrain subtends the largest angles. So each
// texel gathers its first `near_radius` texels (default 4) itself, from its centre over every column, row
// and diagonal crossing of P1's near stencil (each piece radiating its facet's light, both facets for a
// piece along an edge), and the lines' receivers, through a hull tree that lags that far, gather only the
// terrain beyond: their mean radiance fills the texel's lobe from the near field's horizon up to P1's.
// Accuracy (docs/methods/p2.md): the azimuthal error of a bounce falls about as 1/K; against
// the reference what remains is the receivers' place on the lines beyond the near field (raise
// `near_radius`), K, and the facets' light, evaluated at their right-angle corner (tests/p2/
// measure_p2_centre splits the parts; on terraces at K = 64 the exact centre gather itself is +1.5 %).
//
// Parameters (schemas/methods/p2.schema.json): directions (K, default 64), bounces (default: the job's
// "bounces"), visibility ("tree" or "naive": the same output, the naive march is for benchmarks and
// checks), supersampling (S, default 1), subdivide (1, 2 or 4, default 1), senders ("facets", default, or
// "texels"), near_radius (texels, default 4; 0 = off; facet senders only), line_profile ("exact", default, or
// "columns"; facet senders only), wrap_periods, layers: indirect, total, direct (default: all three),
// indirect_b1 .. indirect_b<bounces>.
#pragma once

#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "job/params.hpp"
#include "methods/method_table.hpp"
#include "methods/p2/indirect_sweep.hpp"

namespace hfbake {

struct P2Params {
  int directions = 64;
  int bounces = -1;  // -1: the scene's
  P2Visibility visibility = P2Visibility::tree;
  int wrap_periods = 1;
  int supersampling = 1;  // S: terrain samples per line step (indirect_sweep.hpp)
  // Senders radiate per facet of the triangulated surface (true, default) or per texel with its smoothed
  // normal (false, the method as published).
  bool facet_senders = true;
  // Texels gather their first near_radius texels exactly from their centres (facet senders only;
  // IndirectSweepSpec::near_radius); 0: every receiver gathers on its line (the method as published).
  double near_radius = 4;  // (P1's exact near field then reaches as far: compute_p2)
  // The lines' terrain is the triangulated surface along them exactly (true, default: a sample at every
  // row and diagonal bend between columns; facet senders only; IndirectSweepSpec::exact_profile), or
  // straight between column samples (false, job key line_profile "columns": the method as published).
  bool exact_profile = true;
  // The field subdivided this many times a texel on its triangulation (1, 2 or 4; p2_subdivided_scene),
  // baked, and every layer read at the original texels (docs/methods/p2.md, rough ground). Lengths in
  // texels (near_radius) keep their world length: p2_fine_params scales them.
  int subdivide = 1;
  // P1 reads the receivers' normals from the scene (P1Params::scene_normals; not a job parameter): set by
  // p2_fine_params for the subdivided scene, whose original texels keep the original field's normals.
  bool scene_normals = false;
  std::vector<std::string> layers;  // empty: indirect, total, direct
  // Keep each bounce's indirect apart (P2Result::indirect_b); bake_p2 keeps them only for indirect_b
  // layers (12 bytes a texel and bounce).
  bool keep_bounces = true;
  // P1's horizons between stage 0 and the bounces (not a job parameter; tests set it): 1 kept whole from
  // stage 0, 0 recomputed a direction block at a time in each bounce, -1 by p2_keeps_horizons' rule.
  int keep_horizons = -1;
};

// The rule that decides whether P2 keeps P1's horizons of every direction from stage 0 for its bounces
// (4 bytes a texel per direction) or recomputes each bounce's direction block of them when it runs
// (p1_direction_sums of the block, as compute_p1 runs it: the same bits, P1's horizon sweep once more per
// bounce, 4 bytes a texel per direction of one block): kept while they take at most
// kP2KeptHorizonBytes, or as P2Params::keep_horizons says. Never kept without bounces (none reads them).
inline constexpr double kP2KeptHorizonBytes = double(1 << 30);
bool p2_keeps_horizons(const FieldShape& field, const P2Params& params, int job_bounces);

// Reads the bake entry (schemas/methods/p2.schema.json) with every check; indirect_b<b> layers are known up
// to the bounces it bakes (its own "bounces", else job_bounces), which it sets as P2Params::bounces, and
// keep_bounces follows the indirect_b layers.
P2Params read_p2_params(Params& in, int job_bounces);

struct P2Result {
  int width = 0, height = 0;
  std::vector<Rgb> direct;                   // E_direct / pi (from P1)
  std::vector<std::vector<Rgb>> indirect_b;  // E / pi of bounce b = 1..bounces (index b - 1); empty
                                             // without P2Params::keep_bounces
  std::vector<Rgb> indirect;                 // sum over the bounces
  P2SweepStats stats;                        // summed over the bounces' sweeps
};

// Bakes the scene it is given: params.subdivide is bake_p2's (and the farm's stages'), which hand it the
// subdivided scene and p2_fine_params.
P2Result compute_p2(const Scene& scene, const P2Params& params, const RunControl& rc);

// compute_p2 as its stages (the farm runs them as successive tasks, baker/farm): stage 0 P1's direct light
// (and horizons, when kept), stage b (1..bounces) bounce b, each from the state the previous stage left.
// compute_p2 is p2_stage0, then p2_bounce for b = 1..bounces, then p2_result: the same operations in the same
// order. Each stage sums its directions in the direction blocks (core/direction_blocks.hpp), which the farm
// computes as separate tasks (MethodInfo::stage_blocks) and adds in the same order.
struct P2State {
  int bounces_done = 0;
  std::vector<Rgb> direct;                   // E_direct / pi
  std::vector<float> p1_sin_horizon;         // P1's kept horizons ([k * texels + texel], sin e), or empty
  std::vector<Rgb> exit;                     // the exit radiance the next bounce gathers
  std::vector<Rgb> facet_exit;               // facet senders: [2 * texel + q], its corners' mean
  std::vector<Rgb> corner_exit;              // facet senders: [kCornerFacets * texel + c] at the texel
  std::vector<Rgb> indirect;                 // the sum of the bounces done (empty before bounce 1)
  std::vector<std::vector<Rgb>> indirect_b;  // with P2Params::keep_bounces
  P2SweepStats stats;
};
P2State p2_stage0(const Scene& scene, const P2Params& params, const RunControl& rc);
// Stage 0's state from P1's result (p2_direct_params): what p2_stage0 does after compute_p1.
struct P1Result;
P2State p2_state_of_direct(const Scene& scene, const P2Params& params, P1Result&& direct);
// Bounce state.bounces_done + 1 of `bounces` (the last frees what no later bounce needs): its direction
// blocks (core/direction_blocks.hpp) by p2_bounce_block, added by add_indirect_block in block order, then
// p2_finish_bounce. The farm runs the blocks as separate tasks and merges them the same way.
void p2_bounce(const Scene& scene, const P2Params& params, int bounces, P2State& state, const RunControl& rc);
struct P2BlockSums {
  std::vector<double> texel, facet;  // sweep_indirect_sums' acc and facet_acc (facet: before the last bounce)
  P2SweepStats stats;
};
P2BlockSums p2_bounce_block(const Scene& scene, const P2Params& params, int bounces, const P2State& state,
                            int block, const RunControl& rc);
// total, facet_total: the blocks' totals (add_indirect_block; facet_total only before the last bounce with
// facet senders); stats: the blocks' counts summed.
void p2_finish_bounce(const Scene& scene, const P2Params& params, int bounces, P2State& state,
                      const float* total, const float* facet_total, const P2SweepStats& stats);
P2Result p2_result(P2State&& state, int width, int height);

// The P1 bake compute_p2 runs for direct light (and, horizons: the horizons that split each texel's lobe,
// p2_keeps_horizons), and the one a bounce runs to recompute a direction block's horizons.
struct P1Params;
P1Params p2_direct_params(const P2Params& params, bool horizons);
P1Params p2_horizon_params(const P2Params& params);
// With subdivide s > 1, p2 bakes the scene subdivided on its triangulation (field/subdivide.hpp): the fine
// field; albedo and emission interpolated over the coarse facets as the reference interpolates them (so the
// fine facets carry the same light); the fine field's normals (compute_normals), except at the original
// texels (s i, s j), which keep the scene's, the normals the reference's receivers there have. Its
// parameters: subdivide 1, near_radius times s (the same world length), P1 reading the scene's normals.
// bake_p2 reads each layer back at the original texels (p2_original_texels).
Scene p2_subdivided_scene(const Scene& scene, int s);
P2Params p2_fine_params(const P2Params& params);
// The layers of the fine bake at the original texels: texel (i, j) of `coarse` is fine texel (s i, s j).
LayerSet p2_original_texels(const LayerSet& fine, const FieldShape& coarse, int s);

// Bytes compute_p2 and bake_p2 hold at their peak beyond the output layers (P1's horizons, kept or one
// block's, the exit radiance, the sweep's sums, the line buffers): the method table's working_bytes.
// params with bounces resolved (>= 0); environment_bytes: the scene's world lat-long (MethodContext), which a
// subdivided bake's fine scene copies; uniform_environment: its sky is uniform (P1's sums of the facets'
// light are then one float a facet, not RGB).
double p2_working_bytes(const FieldShape& field, const P2Params& params, double environment_bytes = 0,
                        bool uniform_environment = false);

LayerSet bake_p2(const Scene& scene, const MethodConfig& config, const RunControl& rc);
// bake_p2's layers of a result (B: the bounces baked).
LayerSet p2_layers(const P2Params& params, int bounces, const P2Result& result);

// p2's line of the method table.
MethodInfo p2_method();

}  // namespace hfbake
