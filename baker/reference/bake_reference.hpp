// The Embree path-traced reference: hfbake's ground truth for every layer a method bakes.
//
// Receivers are the texel centers with the P1 normal (Scene::normals), ray origins lifted vertically by
// EmbreeField::epsilon() (1e-3 texel, more for huge coordinates): above a point of a height field is always
// above the surface, where a step along a steep smoothed normal can end under a neighbouring facet (on rough
// terrain that hid whole wedges of sky and darkened the reference by 4-8 %). Geometry and the solid: see
// reference/embree_field.hpp. Estimators (each layer also gets "<layer>_stderr"):
//   ao          cosine-weighted directions about the normal, unlimited distance: mean of V.
//   vsky        directions uniform in solid angle over the upper (+z) hemisphere: mean of V, which is
//               1 - mean over azimuth of sin(max(h, 0)) (solid angle above elevation h is (1 - sin h) per
//               unit azimuth).
//   obscurance  cosine-weighted: 1 - mean of rho(d), d the hit distance (rho = 0 for a miss), the falloff
//               functions of methods/ao/falloff.hpp; only hits within the falloff's support (rho >= 1e-6)
//               count, whatever else is traced (alone, its rays end there).
//   direct      E_direct / pi: the environment by multiple importance sampling (balance heuristic, one
//               luminance-CDF sample and one cosine sample; cosine only for a uniform environment) and every
//               directional light sampled uniformly over its disk (radiance E / (pi sin^2 alpha)), all with
//               shadow rays.
//   indirect    E_indirect / pi by Lambertian path tracing: the cosine-sampled primary ray's hit x1 gives
//               emission(x1) + albedo(x1) * direct(x1), continued with cosine sampling up to exactly
//               `bounces` surface vertices. indirect_b<k> is the light whose path touched the surface k
//               times (emitted at, or reflected by, the k-th vertex). Albedo and emission are interpolated
//               with the triangle's barycentric weights; hits on the skirt use the nearest border texel.
//   total       direct + indirect.
//   bent_normal the unit mean of the unoccluded directions of the ao rays (cosine-weighted about the
//               normal, unlimited distance): normalize(integral of V w (N.w) dw), P1's definition; zero
//               where no ray escaped. Scored by the angle between the method's vector and it.
// Sampling: `replicates` (default 8) independently Owen-scrambled Sobol sequences per texel, each with
// ceil(samples / replicates) points; the value is the mean of the replicate means and the standard error
// is their standard deviation / sqrt(replicates) -- an honest estimate of the randomised-QMC error (the
// per-sample variance formula would overstate it). Measured on a fractal field against a 16k-sample
// truth, rms(stderr) matches the rms error within a few percent for ao, vsky and indirect; per texel,
// (estimate - truth) / stderr follows Student's t with replicates - 1 degrees of freedom (8 replicates:
// about 2 % of texels lie beyond 3 stderr; 32: 0.5 %). Fewer replicates keep more of the QMC gain
// (rms error at 1024 samples: 0.0036 with 4, 0.0041 with 8, 0.0058 with 32 replicates). Streams derive from
// (seed, texel, replicate, dimension pair) only: the bits do not depend on the thread count. With
// target_stderr, a pilot of 64 samples (on independent replicates) estimates each texel's spread; the texel
// is then sampled afresh with the power-of-two count predicted to reach the target (Monte Carlo rate, 1.5x
// margin, floor |value| / N when every pilot sample agreed, capped by `samples`), and only the fresh samples
// make the value and its stderr. (Stopping on the running stderr instead would be biased: replicates that
// happen to agree give stderr 0 -- measured, that doubled the true error.) The "samples" layer records each
// texel's count.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "methods/ao/falloff.hpp"
#include "methods/method_table.hpp"
#include "reference/embree_field.hpp"

namespace hfbake {

struct ReferenceOptions {
  std::vector<std::string> layers;  // output layers (their _stderr layers are added)
  int samples = 256;                // per texel (rounded up to a multiple of replicates)
  std::uint64_t seed = 1;
  double target_stderr = 0;  // 0: off
  int replicates = 8;
  Falloff falloff;  // obscurance
  // quads (default), grid or triangles: the same surface, and quads and grid the same bits (the same robust
  // intersector; tests/reference). Measured at 1024^2 (ao rays per CPU second, tests/reference/
  // bench_reference BM_AoRays1024, a loaded machine): grid 2.9 M, triangles 3.8 M, quads 4.1 M single rays
  // and 4.4 M in streams. A bake's peak while it traces grows by 54 (grid), 108 (quads) and 194
  // (triangles) bytes a texel (embree_bytes_per_texel). Quads trace one BVH (its skirt is quads too); grid
  // and triangles two.
  reference::GeometryKind geometry = reference::GeometryKind::quads;
  int repeat_tiles = 1;         // wrap repeat: tiles instanced on each side
  bool sh_environment = false;  // light with the environment band-limited to SH order 4
  // Trace each texel's batches with rtcOccluded1M / rtcIntersect1M instead of one rtcOccluded1 /
  // rtcIntersect1 per ray: the same bits. Measured (1024^2 fractal, ao, 32 rays a call, Embree 3.13.5
  // without ISPC): quads 4.4 M rays per CPU second in streams, 4.1 M single (grid: 3.0 M and 2.9 M). With 4
  // rays a call (32 samples, 8 replicates) streams were ~15 % slower on the grid.
  bool ray_streams = true;
  int tile_size = 16;
  // The farm's receiver tiles: only rows [row_begin, row_end) (-1: the last row) are traced, each against
  // the whole field; the result holds those rows only. Each texel's samples depend on (seed, texel) alone,
  // so the rows are the same bits as in a whole bake.
  int row_begin = 0, row_end = -1;
  // The job's "reference" object with every default filled in (what the bake used; read_reference_options).
  nlohmann::json resolved = nlohmann::json::object();
};

// The reference layers this scene's paths can trace: the layer table's LayerTrace::path_traced, in its order
// (a numbered family as indirect_b1 .. indirect_b<bounces>).
std::vector<std::string> reference_layer_names(int bounces);

// Reads the job's "reference" object (`reference`; null or absent keys: the defaults) with every check:
// InputError naming `file` and a "/reference/..." pointer. What it takes from the bake entries comes from
// their configs (`entries`, in the job's order): without its own "layers", the reference traces only the
// layers some entry is scored against (its layers that the reference can produce; a job without entries
// traces ao, vsky, [obscurance,] direct, indirect, total), and without its own falloff or radius, its
// obscurance is that of reference_falloff_entry.
ReferenceOptions read_reference_options(const nlohmann::json& reference,
                                        const std::vector<const MethodConfig*>& entries,
                                        const MethodContext& context, const std::string& file);
// The same from a whole job document (its entries read by their methods' readers here): code and tests
// that hold one. parse_reference_options: for a loaded scene (its shape and bounces), without a file name.
ReferenceOptions read_reference_options(const nlohmann::json& job_doc, const MethodContext& context,
                                        const std::string& file);
ReferenceOptions parse_reference_options(const Scene& scene, const nlohmann::json& job_doc);

// The entry whose falloff and radius the reference's obscurance uses: the first obscurance-family entry
// that writes a falloff or radius (MethodConfig::obscurance), when the reference has none of its own; else
// -1. Nothing else of the bake list reaches the reference (the reference cache keys on exactly this).
int reference_falloff_entry(const nlohmann::json& reference, const std::vector<const MethodConfig*>& entries);

// Resuming a reference that was killed: the traced rows are cut into bands of options.tile_size rows (band b:
// rows row_begin + b * tile_size ..., the last one shorter), and each texel's samples depend on (seed, texel)
// alone, so a band's floats are the same bits whenever and wherever it is traced. Before tracing,
// `load(band, values)` may fill a band from an earlier run (true: taken as is, not traced); each band traced
// here is handed to `store` once its last tile is done. `values` holds the band's rows of every layer of the
// result, in the result's layer order (reference_band_floats of them). The callbacks do the files (cli/);
// they must not throw. bands_resumed / bands_traced count what this bake did.
struct ReferenceResume {
  std::function<bool(int band, std::span<float> values)> load;
  std::function<void(int band, std::span<const float> values)> store;
  int bands_resumed = 0, bands_traced = 0;
};
// The number of bands of a reference over `rows` rows.
int reference_band_count(const ReferenceOptions& options, int rows);

LayerSet bake_reference(const Scene& scene, const ReferenceOptions& options, const RunControl& rc,
                        ReferenceResume* resume = nullptr);
LayerSet bake_reference(const Scene& scene, const nlohmann::json& job_doc, const RunControl& rc);

}  // namespace hfbake
