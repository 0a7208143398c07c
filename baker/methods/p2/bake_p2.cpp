#include "methods/p2/bake_p2.hpp"

#include "sweep/sweep_lines.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>

#include "core/direction_blocks.hpp"
#include "core/error.hpp"
#include "core/page_buffer.hpp"
#include "core/threads.hpp"
#include "field/subdivide.hpp"
#include "job/params.hpp"
#include "methods/p1/p1.hpp"

namespace hfbake {
namespace {

// The facets' exit radiance (P2State::facet_exit) from their corners' (corner_exit): each facet's the mean
// of the values at its three corners, texel (i, j)'s facet q = 0 at (i, j), (i + 1, j), (i, j + 1), q = 1
// at (i, j), (i - 1, j), (i, j - 1). A corner off a clamp field (the facet lies outside it and no ray meets
// it) counts as the facet's own texel.
void facets_of_corners(const HeightField& f, const std::vector<Rgb>& corner_exit, std::vector<Rgb>& out) {
  out.resize(2 * f.texel_count());
  tbb::parallel_for(0, f.height, [&](int j) {
    for (int i = 0; i < f.width; ++i) {
      const std::size_t t = f.index(i, j);
      for (int q = 0; q < 2; ++q) {
        const int d = q == 0 ? 1 : -1;
        const Rgb own = corner_exit[kCornerFacets * t + q];
        auto corner = [&](int ci, int cj, int c) {
          const bool on = f.wrap == Wrap::repeat || (ci >= 0 && cj >= 0 && ci < f.width && cj < f.height);
          return on ? corner_exit[kCornerFacets * f.index(f.wrap_i(ci), f.wrap_j(cj)) + c] : own;
        };
        // The corner facet that this facet is at (i + d, j) and at (i, j + d) (kCornerFacet's order).
        out[2 * t + q] =
            (own + corner(i + d, j, q == 0 ? 2 : 4) + corner(i, j + d, q == 0 ? 3 : 5)) * (1.0f / 3);
      }
    }
  });
}

}  // namespace

P2Params read_p2_params(Params& in, int job_bounces) {
  P2Params p;
  p.directions = in.integer("directions", 64, 1, 4096);
  p.bounces = in.integer("bounces", -1, 0, 64);
  p.wrap_periods = in.integer("wrap_periods", 1, 1, 16);
  p.supersampling = in.integer("supersampling", 1, 1, 16);
  p.subdivide = in.integer("subdivide", 1, 1, 4);
  if (p.subdivide == 3) in.fail("subdivide", "must be 1, 2 or 4");
  p.visibility =
      in.choice("visibility", "tree", {"tree", "naive"}) == "tree" ? P2Visibility::tree : P2Visibility::naive;
  p.near_radius = in.number("near_radius", p.near_radius, 0, 16);
  if (p.near_radius != 0 && p.near_radius < 1)
    in.fail("near_radius", "must be 0 (off) or a number in [1, 16]");
  p.facet_senders = in.choice("senders", "facets", {"facets", "texels"}) == "facets";
  p.exact_profile = in.choice("line_profile", "exact", {"exact", "columns"}) == "exact";
  const int B = p.bounces >= 0 ? p.bounces : std::max(0, job_bounces);
  std::vector<std::string> known = {"indirect", "total", "direct"};
  for (int b = 1; b <= B; ++b) known.push_back("indirect_b" + std::to_string(b));
  p.layers = in.layers(known, {"indirect", "total", "direct"});
  p.bounces = B;
  in.resolve("bounces", B);
  p.keep_bounces = std::any_of(p.layers.begin(), p.layers.end(),
                               [](const std::string& l) { return l.rfind("indirect_b", 0) == 0; });
  return p;
}

P1Params p2_direct_params(const P2Params& params, bool horizons) {
  P1Params p1;
  p1.directions = params.directions;
  p1.wrap_periods = params.wrap_periods;
  p1.ao = p1.vsky = false;
  p1.direct = true;
  p1.horizon = horizons;  // the lobe split uses P1's own horizons (p2_keeps_horizons)
  p1.facet_direct = params.facet_senders;
  // P1's exact near field reaches at least as far as the texels' own near-field gather.
  if (params.facet_senders) p1.near_radius = std::max(p1.near_radius, params.near_radius);
  p1.horizon_by_direction = true;
  p1.scene_normals = params.scene_normals;
  return p1;
}

P1Params p2_horizon_params(const P2Params& params) {
  P1Params p1 = p2_direct_params(params, true);
  p1.ao = p1.vsky = p1.direct = p1.facet_direct = p1.lights = false;
  p1.horizon = true;
  return p1;
}

bool p2_keeps_horizons(const FieldShape& field, const P2Params& p, int job_bounces) {
  if ((p.bounces >= 0 ? p.bounces : job_bounces) <= 0) return false;  // no bounce reads them
  if (p.keep_horizons >= 0) return p.keep_horizons == 1;
  return 4.0 * p.directions * double(field.width) * double(field.height) <= kP2KeptHorizonBytes;
}

namespace {
double field_working_bytes(const FieldShape& shape, const P2Params& p, bool uniform_environment) {
  const double N = double(shape.width) * double(shape.height);
  const int B = std::max(0, p.bounces), K = p.directions;
  const bool kept = p2_keeps_horizons(shape, p, B);
  const double horizons = kept ? 4.0 * K * N : 0;  // P1's horizons of every direction, kept
  // The layers the estimate counts separately, allocated only at the end (from direct and indirect).
  const double layers = 12.0 * double(p.layers.size()) * N;
  const bool keep = std::any_of(p.layers.begin(), p.layers.end(),
                                [](const std::string& l) { return l.rfind("indirect_b", 0) == 0; });
  // P1: its kept horizons and direct (and the facets' light) plus its own working memory.
  const double p1_phase =
      horizons + 12 * N + p1_working_bytes(shape, p2_direct_params(p, kept), uniform_environment);
  // A bounce, one direction block at a time: P1's kept horizons, or the block's recomputed (4 bytes a
  // texel per direction of the largest block) and P1's sweep recomputing them (before the block's own
  // sweep); direct, the exit radiance, the facets' and their corners' (24 + 72), the block's double sums
  // (24) and the blocks' total (24, SplitDouble), the indirect sum from the second bounce on; before the
  // last bounce the corner facets' block sums (144) and total (144); the bounces kept for indirect_b
  // layers (12 each); the line buffers of one block's sweep.
  const int blocks = direction_block_count(K), largest = (K + blocks - 1) / blocks;
  IndirectSweepSpec is;
  is.directions = K;
  is.k_begin = 0, is.k_end = largest;
  is.wrap_periods = p.wrap_periods;
  HeightField field;  // the sweep's plan needs only the shape
  static_cast<FieldShape&>(field) = shape;
  // ... and each thread's line worker (its longest line: the repeat warm-up included).
  const int longest =
      std::max(shape.width, shape.height) * (shape.wrap == Wrap::repeat ? p.wrap_periods + 1 : 1);
  double line_buffers =
      double(sweep_buffer_bytes(field, indirect_sweep_spec(is))) +
      double(worker_threads()) *
          double(indirect_line_scratch_bytes(longest, p.supersampling, p.facet_senders && p.exact_profile));
  double block_horizons = 0;
  if (!kept) {
    block_horizons = 4.0 * largest * N;
    line_buffers = std::max(line_buffers, p1_working_bytes(shape, p2_horizon_params(p), uniform_environment));
  }
  double bounce_phase = 0;
  for (int b = 1; b <= B; ++b) {
    double t = 12 + 12 + (p.facet_senders ? 24 + 12 * kCornerFacets : 0) + 24 + 24 + (b > 1 ? 12 : 0) +
               (keep ? 12.0 * (b - 1) : 0);
    if (p.facet_senders && b < B) t += 2 * 24.0 * kCornerFacets;
    bounce_phase = std::max(bounce_phase, horizons + block_horizons + t * N + line_buffers);
  }
  // Writing the layers: direct and indirect (and the kept bounces) beside them.
  const double output = (24 + (keep ? 12.0 * B : 0)) * N;
  return std::max(output, std::max(p1_phase, bounce_phase) - layers);
}
}  // namespace

double p2_working_bytes(const FieldShape& shape, const P2Params& p, double environment_bytes,
                        bool uniform_environment) {
  if (p.subdivide == 1) return field_working_bytes(shape, p, uniform_environment);
  // Subdivided: the fine scene (heights, normals, and albedo and emission counted as images: 40 bytes a
  // fine texel, and its copy of the environment) beside the fine bake, whose layers (counted here) are then
  // read into the coarse ones (which the estimate counts itself).
  const FieldShape fine = subdivided_shape(shape, p.subdivide);
  const double Nf = double(fine.width) * double(fine.height), N = double(shape.width) * double(shape.height);
  const double fine_layers = 12.0 * double(p.layers.size()) * Nf;
  const double bake = 40 * Nf + environment_bytes +
                      field_working_bytes(fine, p2_fine_params(p), uniform_environment) + fine_layers;
  const double read_back = fine_layers + 12.0 * double(p.layers.size()) * N;
  return std::max(bake, read_back) - 12.0 * double(p.layers.size()) * N;
}

Scene p2_subdivided_scene(const Scene& scene, int s) {
  Scene fine;
  fine.name = scene.name;
  fine.environment = scene.environment;
  fine.lights = scene.lights;
  fine.bounces = scene.bounces;
  fine.curvature = scene.curvature;
  fine.refraction = scene.refraction;
  const HeightField& c = scene.field;
  fine.field = subdivided_field(c, s);
  fine.normals = compute_normals(fine.field);
  const bool own = scene.normals.size() == c.texel_count();
  tbb::parallel_for(0, c.height, [&](int j) {
    for (int i = 0; i < c.width; ++i)
      fine.normals[fine_index_of(fine.field, s, i, j)] =
          own ? scene.normals[c.index(i, j)] : normal_at(c, i, j);
  });
  const SurfaceMap& albedo = scene.surface.albedo;
  if (albedo.size() == c.texel_count() && albedo.bytes() > 0) {
    std::vector<Rgb> v(c.texel_count());
    for (std::size_t t = 0; t < v.size(); ++t) v[t] = albedo[t];
    fine.surface.albedo.assign(subdivided_values(c, s, v));
  } else if (!albedo.empty()) {
    fine.surface.albedo.assign(fine.field.texel_count(), albedo[0]);
  }
  if (scene.surface.emission.size() == c.texel_count())
    fine.surface.emission = subdivided_values(c, s, scene.surface.emission);
  return fine;
}

P2Params p2_fine_params(const P2Params& params) {
  P2Params p = params;
  p.near_radius = params.near_radius * params.subdivide;
  p.subdivide = 1;
  p.scene_normals = true;
  return p;
}

LayerSet p2_original_texels(const LayerSet& fine, const FieldShape& coarse, int s) {
  LayerSet out;
  out.width = coarse.width, out.height = coarse.height;
  out.attributes = fine.attributes;
  const FieldShape shape = subdivided_shape(coarse, s);
  for (const Layer& l : fine.layers) {
    Layer& o = out.add(l.name, l.channels);
    const std::size_t C = l.channels.size();
    tbb::parallel_for(0, coarse.height, [&](int j) {
      for (int i = 0; i < coarse.width; ++i) {
        const std::size_t from = C * fine_index_of(shape, s, i, j);
        std::copy_n(l.data.begin() + std::ptrdiff_t(from), C,
                    o.data.begin() + std::ptrdiff_t(C * (std::size_t(j) * std::size_t(coarse.width) + i)));
      }
    });
  }
  return out;
}

P2State p2_stage0(const Scene& scene, const P2Params& params, const RunControl& rc) {
  // Direct light: P1 on the same driver (its horizons, its lighting tables, its sun shadows).
  const P1Params p1 = p2_direct_params(params, p2_keeps_horizons(scene.field, params, scene.bounces));
  return p2_state_of_direct(scene, params, compute_p1(scene, p1, rc));
}

P2State p2_state_of_direct(const Scene& scene, const P2Params& params, P1Result&& direct) {
  const HeightField& f = scene.field;
  const std::size_t N = f.texel_count();
  P2State r;
  r.direct.resize(N);
  for (std::size_t i = 0; i < N; ++i) r.direct[i] = direct.direct_at(i);
  std::vector<float>().swap(direct.direct);
  r.p1_sin_horizon = std::move(direct.horizon);

  // Exit radiance of bounce 0: reflected direct light plus emission.
  r.exit.resize(N);
  const bool emits = scene.surface.emission.size() == N;
  for (std::size_t i = 0; i < N; ++i)
    r.exit[i] = scene.surface.albedo[i] * r.direct[i] + (emits ? scene.surface.emission[i] : Rgb{});
  // Facet senders: the exit radiance of the six facets that meet at each texel, at the texel (P1's
  // direct light of each at the texel, P1Result::direct_facets, times the texel's albedo, plus its
  // emission), replacing P1's corner light in place; each facet's mean over its corners (facets_of_corners).
  // The reference interpolates albedo and emission over a facet, and its light varies over it: on ground
  // rough at the texel scale a facet is lit very differently at its three corners.
  if (params.facet_senders) {
    r.corner_exit = std::move(direct.direct_facets);
    tbb::parallel_for(std::size_t(0), N, [&](std::size_t t) {
      const Rgb em = emits ? scene.surface.emission[t] : Rgb{};
      for (int c = 0; c < kCornerFacets; ++c)
        r.corner_exit[kCornerFacets * t + c] =
            scene.surface.albedo[t] * r.corner_exit[kCornerFacets * t + c] + em;
    });
    facets_of_corners(f, r.corner_exit, r.facet_exit);
  }
  std::vector<Rgb>().swap(direct.direct_facets);
  return r;
}

P2BlockSums p2_bounce_block(const Scene& scene, const P2Params& params, int B, const P2State& r, int block,
                            const RunControl& rc) {
  const HeightField& f = scene.field;
  const std::size_t N = f.texel_count();
  const int b = r.bounces_done + 1, K = params.directions;
  IndirectSweepSpec spec;
  spec.directions = K;
  spec.k_begin = direction_block_begin(block, K), spec.k_end = direction_block_begin(block + 1, K);
  spec.visibility = params.visibility;
  spec.wrap_periods = params.wrap_periods;
  spec.supersampling = params.supersampling;
  spec.exact_profile = params.exact_profile;
  // P1's horizons of the block: kept from stage 0, or recomputed now (the same bits: p1_direction_sums of
  // the same block, as compute_p1 runs it).
  std::vector<float> recomputed;
  double p1_share = 0;
  if (r.p1_sin_horizon.empty()) {
    p1_share = 0.2;
    P1Sums h = p1_direction_sums(scene, p2_horizon_params(params), spec.k_begin, spec.k_end,
                                 p2_sub_range(rc, 0, p1_share));
    recomputed = std::move(h.horizon);
    spec.p1_sin_horizon = recomputed.data();
  } else {
    spec.p1_sin_horizon = r.p1_sin_horizon.data() + std::size_t(spec.k_begin) * N;
  }
  if (params.facet_senders) {
    spec.exit_facets = &r.facet_exit;
    spec.corner_exit = &r.corner_exit;
    spec.near_radius = params.near_radius;
  }
  P2BlockSums s;
  sweep_indirect_sums(f, scene.normals, r.exit, spec, p2_sub_range(rc, p1_share, 1 - p1_share), &s.stats,
                      s.texel, params.facet_senders && b < B ? &s.facet : nullptr);
  return s;
}

void p2_finish_bounce(const Scene& scene, const P2Params& params, int B, P2State& r, const float* total,
                      const float* facet_total, const P2SweepStats& st) {
  const HeightField& f = scene.field;
  const std::size_t N = f.texel_count();
  const int b = r.bounces_done + 1;
  std::vector<Rgb> e = indirect_of_total(total, N);
  if (params.facet_senders && b < B) {  // the corners' light gathered at the corner facets' normals
    const std::vector<Rgb> corner_e = indirect_of_total(facet_total, kCornerFacets * N);
    tbb::parallel_for(std::size_t(0), N, [&](std::size_t t) {
      for (int c = 0; c < kCornerFacets; ++c)
        r.corner_exit[kCornerFacets * t + c] = scene.surface.albedo[t] * corner_e[kCornerFacets * t + c];
    });
    facets_of_corners(f, r.corner_exit, r.facet_exit);
  }
  add_sweep_stats(r.stats, st);
  if (b < B)
    for (std::size_t i = 0; i < N; ++i) r.exit[i] = scene.surface.albedo[i] * e[i];
  else
    std::vector<Rgb>().swap(r.exit);
  if (b == 1) {  // 0 + e: the same values (the sums never hold -0)
    if (params.keep_bounces)
      r.indirect = e;
    else
      r.indirect = std::move(e);
  } else {
    for (std::size_t i = 0; i < N; ++i) r.indirect[i] += e[i];
  }
  if (params.keep_bounces) r.indirect_b.push_back(std::move(e));
  r.bounces_done = b;
  if (b == B) std::vector<float>().swap(r.p1_sin_horizon);
}

void p2_bounce(const Scene& scene, const P2Params& params, int B, P2State& r, const RunControl& rc) {
  // Direction blocks (core/direction_blocks.hpp): each summed from zero, the blocks added in order -- the
  // order `hfbake merge` adds the farm's blocks in (p2_finish_stage_blocks).
  const int K = params.directions, blocks = direction_block_count(K);
  std::vector<float> total, facet_total;
  P2SweepStats st;
  for (int k = 0; k < blocks; ++k) {
    const int k0 = direction_block_begin(k, K), k1 = direction_block_begin(k + 1, K);
    const P2BlockSums s =
        p2_bounce_block(scene, params, B, r, k, p2_sub_range(rc, double(k0) / K, double(k1 - k0) / K));
    add_indirect_block(total, s.texel);
    if (!s.facet.empty()) add_indirect_block(facet_total, s.facet);
    add_sweep_stats(st, s.stats);
    release_freed_memory();  // the block's sweep buffers, before the next block's
  }
  p2_finish_bounce(scene, params, B, r, total.data(), facet_total.data(), st);
}

P2Result p2_result(P2State&& s, int width, int height) {
  P2Result r;
  r.width = width, r.height = height;
  r.direct = std::move(s.direct);
  r.indirect = std::move(s.indirect);
  r.indirect_b = std::move(s.indirect_b);
  r.stats = s.stats;
  if (s.bounces_done == 0) r.indirect.assign(std::size_t(width) * std::size_t(height), Rgb{});
  return r;
}

P2Result compute_p2(const Scene& scene, const P2Params& params, const RunControl& rc) {
  const int B = params.bounces >= 0 ? params.bounces : std::max(0, scene.bounces);
  const double phase = 1.0 / (1 + B);
  P2State s = p2_stage0(scene, params, p2_sub_range(rc, 0, phase));
  release_freed_memory();  // the direct light's P1 buffers, before the bounces
  for (int b = 1; b <= B; ++b) {
    rc.check();
    p2_bounce(scene, params, B, s, p2_sub_range(rc, b * phase, phase));
  }
  rc.report(1.0);
  return p2_result(std::move(s), scene.field.width, scene.field.height);
}

LayerSet bake_p2(const Scene& scene, const MethodConfig& config, const RunControl& rc) {
  const P2Params& p = config.get<P2Params>();
  if (p.subdivide == 1) return p2_layers(p, p.bounces, compute_p2(scene, p, rc));
  LayerSet fine;
  {
    const Scene subdivided = p2_subdivided_scene(scene, p.subdivide);
    fine = p2_layers(p, p.bounces, compute_p2(subdivided, p2_fine_params(p), rc));
  }
  return p2_original_texels(fine, scene.field, p.subdivide);
}

LayerSet p2_layers(const P2Params& p, int B, const P2Result& r) {
  const std::size_t N = std::size_t(r.width) * std::size_t(r.height);
  LayerSet out;
  out.width = r.width;
  out.height = r.height;
  auto put = [&](const std::string& name, auto value) {
    Layer& l = out.add(name, rgb_channels());
    for (std::size_t i = 0; i < N; ++i) {
      const Rgb v = value(i);
      l.data[3 * i] = v.r, l.data[3 * i + 1] = v.g, l.data[3 * i + 2] = v.b;
    }
  };
  for (const std::string& name : p.layers) {
    if (name == "indirect")
      put(name, [&](std::size_t i) { return r.indirect[i]; });
    else if (name == "total")
      put(name, [&](std::size_t i) { return r.direct[i] + r.indirect[i]; });
    else if (name == "direct")
      put(name, [&](std::size_t i) { return r.direct[i]; });
    else
      put(name, [&, b = std::stoi(name.substr(10))](std::size_t i) { return r.indirect_b[b - 1][i]; });
  }
  out.attributes.emplace_back("hfbake:p2:bounces", std::to_string(B));
  if (r.stats.receivers > 0) {
    const double pts = double(r.stats.receivers);
    out.attributes.emplace_back("hfbake:p2:horizons_per_point_direction",
                                std::to_string(r.stats.horizons / pts));
    out.attributes.emplace_back("hfbake:p2:iterations_per_point_direction",
                                std::to_string(r.stats.iterations / pts));
  }
  return out;
}

namespace {

// The farm's stages (MethodInfo::stages): the P2State between them as float layers (Rgb arrays as 3
// channels, the horizons as K channels in their own [k * texels + texel] order) and the sweep's counts as
// attributes. The last stage keeps only what the layers need.
std::vector<float> rgb_floats(std::vector<Rgb>&& v) {
  std::vector<float> f(3 * v.size());
  for (std::size_t i = 0; i < v.size(); ++i) f[3 * i] = v[i].r, f[3 * i + 1] = v[i].g, f[3 * i + 2] = v[i].b;
  std::vector<Rgb>().swap(v);
  return f;
}
std::vector<Rgb> rgb_of(const Layer* l) {
  std::vector<Rgb> v(l ? l->data.size() / 3 : 0);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = {l->data[3 * i], l->data[3 * i + 1], l->data[3 * i + 2]};
  return v;
}

LayerSet state_layers(P2State&& s, int width, int height, bool last) {
  LayerSet out;
  out.width = width, out.height = height;
  const std::size_t N = std::size_t(width) * std::size_t(height);
  auto put = [&](const std::string& name, std::vector<Rgb>& v, int per_texel) {
    if (v.empty()) return;
    std::vector<std::string> ch;
    for (int q = 0; q < per_texel; ++q)
      for (const char* c : {"R", "G", "B"}) ch.push_back(std::to_string(q) + "." + c);
    out.adopt(name, std::move(ch), rgb_floats(std::move(v)));
  };
  put("direct", s.direct, 1);
  put("indirect", s.indirect, 1);
  for (std::size_t b = 0; b < s.indirect_b.size(); ++b)
    put("indirect_b" + std::to_string(b + 1), s.indirect_b[b], 1);
  if (!last) {
    put("exit", s.exit, 1);
    put("facet_exit", s.facet_exit, 2);
    put("corner_exit", s.corner_exit, kCornerFacets);
    if (!s.p1_sin_horizon.empty()) {
      const int K = int(s.p1_sin_horizon.size() / N);  // before the move (argument order is unspecified)
      out.adopt("horizon", indexed_channels(K), std::move(s.p1_sin_horizon));
    }
  }
  const P2SweepStats& t = s.stats;
  out.attributes = {{"bounces_done", std::to_string(s.bounces_done)},
                    {"receivers", std::to_string(t.receivers)},
                    {"iterations", std::to_string(t.iterations)},
                    {"naive_iterations", std::to_string(t.naive_iterations)},
                    {"horizons", std::to_string(t.horizons)},
                    {"run_starts", std::to_string(t.run_starts)},
                    {"pushed", std::to_string(t.pushed)},
                    {"horizons_pushed", std::to_string(t.horizons_pushed)}};
  return out;
}

P2State state_of(LayerSet&& l) {
  P2State s;
  s.direct = rgb_of(l.find("direct"));
  s.indirect = rgb_of(l.find("indirect"));
  for (int b = 1; const Layer* x = l.find("indirect_b" + std::to_string(b)); ++b)
    s.indirect_b.push_back(rgb_of(x));
  s.exit = rgb_of(l.find("exit"));
  s.facet_exit = rgb_of(l.find("facet_exit"));
  s.corner_exit = rgb_of(l.find("corner_exit"));
  if (Layer* h = l.find("horizon")) s.p1_sin_horizon = std::move(h->data);
  auto count = [&](const char* key) -> std::uint64_t {
    for (const auto& [k, v] : l.attributes)
      if (k == key) return std::stoull(v);
    return 0;
  };
  s.bounces_done = int(count("bounces_done"));
  s.stats.receivers = count("receivers"), s.stats.iterations = count("iterations");
  s.stats.naive_iterations = count("naive_iterations"), s.stats.horizons = count("horizons");
  s.stats.run_starts = count("run_starts"), s.stats.pushed = count("pushed");
  s.stats.horizons_pushed = count("horizons_pushed");
  l = LayerSet();
  return s;
}

// The state before stage `stage` (the previous stage's).
P2State stage_state_before(int stage, LayerSet&& previous) {
  P2State s = state_of(std::move(previous));
  if (s.bounces_done != stage - 1)
    throw std::runtime_error("p2 stage " + std::to_string(stage) + " after stage " +
                             std::to_string(s.bounces_done));
  return s;
}

int p2_stages(const MethodConfig& config) {
  return 1 + config.get<P2Params>().bounces;
}

LayerSet bake_stage(const Scene& scene, const P2Params& p, int stage, LayerSet&& previous,
                    const RunControl& rc) {
  const int B = p.bounces;
  P2State s = stage == 0 ? p2_stage0(scene, p, rc) : stage_state_before(stage, std::move(previous));
  if (stage > 0) p2_bounce(scene, p, B, s, rc);
  return state_layers(std::move(s), scene.field.width, scene.field.height, stage == B);
}

// A bounce's direction blocks on the farm: block b's double sums as SplitDouble pairs ("indirect#2f": 3
// values a texel, "facet#2f": 18 (the corner facets'), before the last bounce with facet senders), which
// the merge adds by
// add_split in block order (farm/merge_blocks.cpp) as p2_bounce does; its sweep counts as attributes
// "<count>@<b>" (kept apart by the merge, summed here).
// Stage 0 (p1's direct light) divides by the same blocks: block b's P1Sums (p1_direction_sums) as layers
// named after their members, its horizons (when kept) as "horizon@<k_begin>", added in float in block
// order by the merge as compute_p1 adds them (p1_add_sums), then finished by p1_finish.
int p2_stage_blocks(const MethodConfig& config, int) {
  return direction_block_count(config.get<P2Params>().directions);
}

LayerSet p1_block_layers(const Scene& scene, const P2Params& p, int block, const RunControl& rc) {
  const int K = p.directions;
  const P1Params p1 = p2_direct_params(p, p2_keeps_horizons(scene.field, p, scene.bounces));
  P1Sums s =
      p1_direction_sums(scene, p1, direction_block_begin(block, K), direction_block_begin(block + 1, K), rc);
  LayerSet out;
  out.width = scene.field.width, out.height = scene.field.height;
  const std::size_t N = scene.field.texel_count();
  p1_sums_to_layers(s, out);
  if (!s.horizon.empty()) {  // [(k - k_begin) * N + texel]
    std::vector<std::string> channels = indexed_channels(int(s.horizon.size() / N));  // before the move
    out.adopt("horizon@" + std::to_string(s.k_begin), std::move(channels), std::move(s.horizon));
  }
  return out;
}

P1Result p1_of_block_layers(const Scene& scene, const P2Params& p, LayerSet&& sums, const RunControl& rc) {
  const int K = p.directions;
  const std::size_t N = scene.field.texel_count();
  const P1Params p1 = p2_direct_params(p, p2_keeps_horizons(scene.field, p, scene.bounces));
  P1Sums s;
  s.k_begin = 0, s.k_end = K;
  p1_sums_from_layers(sums, p1_sums_shape(scene, p1), s);
  if (p1.horizon) {  // the blocks' horizons into [k * N + texel]
    s.horizon.assign(N * std::size_t(K), 0.0f);
    place_block_layers(sums, "horizon", K, [&](const Layer& l, int k0) {
      std::copy(l.data.begin(), l.data.end(), s.horizon.begin() + std::ptrdiff_t(std::size_t(k0) * N));
    });
  }
  sums = LayerSet();
  return p1_finish(scene, p1, std::move(s), rc);
}

const char* const kStatNames[] = {"receivers",  "iterations", "naive_iterations", "horizons",
                                  "run_starts", "pushed",     "horizons_pushed"};
std::uint64_t* stat_field(P2SweepStats& t, int i) {
  std::uint64_t* f[] = {&t.receivers,  &t.iterations, &t.naive_iterations, &t.horizons,
                        &t.run_starts, &t.pushed,     &t.horizons_pushed};
  return f[i];
}

LayerSet bake_stage_block(const Scene& scene, const P2Params& p, int stage, int block, LayerSet&& previous,
                          const RunControl& rc) {
  const int B = p.bounces;
  if (stage == 0) return p1_block_layers(scene, p, block, rc);
  const P2State s = stage_state_before(stage, std::move(previous));
  P2BlockSums sums = p2_bounce_block(scene, p, B, s, block, rc);
  LayerSet out;
  out.width = scene.field.width, out.height = scene.field.height;
  auto put = [&](const std::string& name, std::vector<double>& v, int per_texel) {
    if (v.empty()) return;
    std::vector<std::string> ch;
    for (int q = 0; q < per_texel; ++q)
      for (const char* c : {"R", "G", "B"})
        for (const char* h : {"hi", "lo"})
          ch.push_back((per_texel > 1 ? std::to_string(q) + "." : std::string()) + c + "." + h);
    std::vector<float> split;
    add_indirect_block(split, v);
    std::vector<double>().swap(v);
    out.adopt(name, std::move(ch), std::move(split));
  };
  put("indirect#2f", sums.texel, 1);
  put("facet#2f", sums.facet, kCornerFacets);
  for (int i = 0; i < 7; ++i)
    out.attributes.emplace_back(std::string(kStatNames[i]) + "@" + std::to_string(block),
                                std::to_string(*stat_field(sums.stats, i)));
  return out;
}

LayerSet finish_stage_blocks(const Scene& scene, const P2Params& p, int stage, LayerSet&& previous,
                             LayerSet&& sums, const RunControl& rc) {
  const int B = p.bounces;
  if (stage == 0)
    return state_layers(p2_state_of_direct(scene, p, p1_of_block_layers(scene, p, std::move(sums), rc)),
                        scene.field.width, scene.field.height, B == 0);
  P2State s = stage_state_before(stage, std::move(previous));
  const std::size_t N = scene.field.texel_count();
  const Layer* total = sums.find("indirect#2f");
  const Layer* facet = sums.find("facet#2f");
  const bool want_facet = p.facet_senders && stage < B;
  if (!total || total->data.size() != 6 * N || want_facet != (facet != nullptr) ||
      (facet && facet->data.size() != 6 * kCornerFacets * N))
    throw std::runtime_error("p2 stage " + std::to_string(stage) + ": blocks of another layout");
  P2SweepStats st;
  const int blocks = direction_block_count(p.directions);
  for (int b = 0; b < blocks; ++b)
    for (int i = 0; i < 7; ++i) {
      const std::string key = std::string(kStatNames[i]) + "@" + std::to_string(b);
      auto it = std::find_if(sums.attributes.begin(), sums.attributes.end(),
                             [&](const auto& a) { return a.first == key; });
      if (it == sums.attributes.end())
        throw std::runtime_error("p2 stage " + std::to_string(stage) + ": direction block " +
                                 std::to_string(b) + " missing from the sums");
      *stat_field(st, i) += std::stoull(it->second);
    }
  p2_finish_bounce(scene, p, B, s, total->data.data(), facet ? facet->data.data() : nullptr, st);
  sums = LayerSet();
  return state_layers(std::move(s), scene.field.width, scene.field.height, stage == B);
}

// A subdivided bake's stages (P2Params::subdivide) run on the subdivided scene; the farm's files hold the
// fine state in layers of the job's field (the shard file's size): each fine layer's values in their order,
// zero-padded to width * height * channels * s^2 floats, channels "f<k>.<channel>" (k < s^2), unpacked
// before use. The merge adds same-named layers value by value, so packed blocks add as the fine ones do.
LayerSet packed(LayerSet&& fine, const FieldShape& coarse, int s) {
  if (s == 1) return std::move(fine);
  LayerSet out;
  out.width = coarse.width, out.height = coarse.height;
  out.attributes = std::move(fine.attributes);
  const std::size_t room = std::size_t(coarse.width) * std::size_t(coarse.height) * std::size_t(s * s);
  for (Layer& l : fine.layers) {
    std::vector<std::string> ch;
    for (int k = 0; k < s * s; ++k)
      for (const std::string& c : l.channels) {
        std::string name = "f";
        name += std::to_string(k);
        name += '.';
        ch.push_back(name + c);
      }
    l.data.resize(room * l.channels.size(), 0.0f);
    out.adopt(l.name, std::move(ch), std::move(l.data));
  }
  return out;
}
LayerSet unpacked(LayerSet&& in, const FieldShape& coarse, int s) {
  if (s == 1) return std::move(in);
  const FieldShape fine = subdivided_shape(coarse, s);
  LayerSet out;
  out.width = fine.width, out.height = fine.height;
  out.attributes = std::move(in.attributes);
  const std::size_t N = std::size_t(fine.width) * std::size_t(fine.height);
  for (Layer& l : in.layers) {
    const std::size_t C = l.channels.size() / std::size_t(s * s);
    std::vector<std::string> ch;
    for (std::size_t c = 0; c < C; ++c) ch.push_back(l.channels[c].substr(l.channels[c].find('.') + 1));
    l.data.resize(N * C);
    l.data.shrink_to_fit();
    out.adopt(l.name, std::move(ch), std::move(l.data));
  }
  return out;
}

// run(scene, params, unpack) on the scene as the entry bakes it: the subdivided scene with p2_fine_params
// when P2Params::subdivide > 1, its farm inputs unpacked with unpack and its result packed.
template <class Run>
LayerSet on_baked_scene(const Scene& scene, const P2Params& p, Run&& run) {
  const int s = p.subdivide;
  const auto unpack = [&](LayerSet&& l) { return unpacked(std::move(l), scene.field, s); };
  if (s == 1) return run(scene, p, unpack);
  const Scene fine = p2_subdivided_scene(scene, s);
  return packed(run(fine, p2_fine_params(p), unpack), scene.field, s);
}

LayerSet p2_bake_stage(const Scene& scene, const MethodConfig& config, int stage, LayerSet&& previous,
                       const RunControl& rc) {
  return on_baked_scene(scene, config.get<P2Params>(), [&](const Scene& sc, const P2Params& p, auto unpack) {
    return bake_stage(sc, p, stage, unpack(std::move(previous)), rc);
  });
}

LayerSet p2_bake_stage_block(const Scene& scene, const MethodConfig& config, int stage, int block,
                             LayerSet&& previous, const RunControl& rc) {
  return on_baked_scene(scene, config.get<P2Params>(), [&](const Scene& sc, const P2Params& p, auto unpack) {
    return bake_stage_block(sc, p, stage, block, unpack(std::move(previous)), rc);
  });
}

LayerSet p2_finish_stage_blocks(const Scene& scene, const MethodConfig& config, int stage,
                                LayerSet&& previous, LayerSet&& sums, const RunControl& rc) {
  return on_baked_scene(scene, config.get<P2Params>(), [&](const Scene& sc, const P2Params& p, auto unpack) {
    return finish_stage_blocks(sc, p, stage, unpack(std::move(previous)), unpack(std::move(sums)), rc);
  });
}

LayerSet p2_finish_stages(const Scene& scene, const MethodConfig& config, LayerSet&& last,
                          const RunControl&) {
  const P2Params& p = config.get<P2Params>();
  const int s = p.subdivide;
  const FieldShape fine = s == 1 ? FieldShape(scene.field) : subdivided_shape(scene.field, s);
  LayerSet l = p2_layers(
      p, p.bounces, p2_result(state_of(unpacked(std::move(last), scene.field, s)), fine.width, fine.height));
  return s == 1 ? l : p2_original_texels(l, scene.field, s);
}

}  // namespace

MethodInfo p2_method() {
  MethodInfo m;
  m.name = "p2";
  m.summary =
      "direct light from p1, then indirect bounces gathered over the exactly visible terrain (hull tree)";
  m.read = [](Params& in, const MethodContext& c) {
    const P2Params p = read_p2_params(in, c.bounces);
    return method_config(p, p.directions);
  };
  m.bake = bake_p2;
  m.memory_knob =
      "its directions (p1's horizons: 4 bytes a texel per direction, kept up to 1 GiB), its bounces and "
      "the indirect_b layers";
  m.working_bytes = [](const MethodConfig& config, const MethodContext& c) {
    return p2_working_bytes(c.field, config.get<P2Params>(), c.environment_bytes, c.uniform_environment);
  };
  m.division = WorkDivision::bounce_stages;
  m.stages = p2_stages;
  m.bake_stage = p2_bake_stage;
  m.finish_stages = p2_finish_stages;
  m.stage_blocks = p2_stage_blocks;
  m.bake_stage_block = p2_bake_stage_block;
  m.finish_stage_blocks = p2_finish_stage_blocks;
  m.division_note =
      "bounces as successive stages (stage 0 direct light, stage b bounce b, needing the previous stage of "
      "the whole field), each by direction blocks across the shards: stage 0 p1's float block sums, a "
      "bounce's "
      "double sums passed as two floats (SplitDouble), merged in block order as the single-machine bake sums "
      "them";
  return m;
}

}  // namespace hfbake
