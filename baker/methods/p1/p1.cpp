#include "methods/p1/p1.hpp"

#include "field/triangulation.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <xmmintrin.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/azimuth.hpp"
#include "core/direction_blocks.hpp"
#include "core/error.hpp"
#include "core/page_buffer.hpp"
#include "core/threads.hpp"
#include "field/coarse_heights.hpp"
#include "job/params.hpp"
#include "methods/p1/far_horizons.hpp"
#include "methods/p1/horizon_sweep.hpp"
#include "methods/p1/lane_horizons.hpp"
#include "methods/p1/lighting_table.hpp"
#include "methods/p1/row_shading.hpp"

namespace hfbake {

using p1::fast_atan;
using p1::near_slope;

namespace {

// A RunControl reporting into [begin, begin + span) of the caller's progress.
RunControl sub_progress(const RunControl& rc, double begin, double span) {
  RunControl sub;
  sub.cancel = rc.cancel;
  if (rc.progress) sub.progress = [&rc, begin, span](double x) { rc.report(begin + span * x); };
  return sub;
}

// A texel's far caster: its strip's FarHorizonWorker result (channel 0: dz, 1: run; run +inf: none), at
// stride `plane` apart from index `at`.
struct FarPick {
  float dz, run;
};
inline FarPick far_pick(const float* strip, std::size_t plane, std::size_t at) {
  return {strip[at], strip[plane + at]};
}

// One line worker per thread, for the K directions and for the lights' own directions.
p1::FarHorizonWorker make_ray_worker(const HeightField& f, const P1Params& p) {
  p1::FarHorizonWorker w;
  w.far_radius = p.near_radius * f.texel_size;
  w.field = &f;
  w.tolerance = p.horizon_tolerance;
  w.beat_near = true;  // the near field is marched from each texel anyway: its slope prunes the far search
  return w;
}

// The lane search (lane_horizons.hpp) for directions [k_begin, k_end) of a clamp field or of a repeat one
// whose tiling it takes (lane_tiles): per axis the field's lane layout (its tiling's), per direction every
// texel's exact horizon (slope and caster), then shade(k, base, w, NX, NY, NZ, FX, FY, FZ, e, dist) per run
// of at most 32 texels of a row. The directions are visited by axis (x-major ones first), so one layout is
// held at a time. Every texel's normal (normal_at) and, for P2's facet sums, its corner facets'
// (corner_facet_normals, [c * N + texel]), as the lane path's shading reads them: computed once per bake,
// shared by its direction blocks.
struct FieldNormals {
  std::vector<float> nx, ny, nz, fx, fy, fz;  // empty when the lighting reads no normals
};
// The receivers' normals (P1Params::scene_normals): Scene::normals when set, else normal_at; null: normal_at.
const Vec3f* given_normals(const Scene& scene, const P1Params& p) {
  if (!p.scene_normals) return nullptr;
  if (scene.normals.size() != scene.field.texel_count())
    throw std::invalid_argument("compute_p1: scene_normals without the scene's normals");
  return scene.normals.data();
}
Vec3f texel_normal(const HeightField& f, const Vec3f* given, int i, int j) {
  return given ? given[f.index(i, j)] : normal_at(f, i, j);
}
// Whether the row lighting reads the texels' normals: for the lobe (ao, bent normals, an exact environment's
// direct light) and a binned environment's direct light; vsky and the horizon layers need none.
bool shading_reads_normals(const P1Params& p) {
  return p.ao || p.bent_normal || p.direct;
}
FieldNormals field_normals(const Scene& scene, const P1Params& p) {
  const HeightField& f = scene.field;
  const bool facets = p.direct && p.facet_direct;
  const std::size_t N = f.texel_count();
  FieldNormals n;
  if (!shading_reads_normals(p)) return n;
  n.nx.resize(N), n.ny.resize(N), n.nz.resize(N);
  n.fx.resize(facets ? kCornerFacets * N : 0), n.fy.resize(n.fx.size()), n.fz.resize(n.fx.size());
  const Vec3f* given = given_normals(scene, p);
  tbb::parallel_for(0, f.height, [&](int j) {
    for (int i = 0; i < f.width; ++i) {
      const std::size_t at = f.index(i, j);
      const Vec3f v = texel_normal(f, given, i, j);
      n.nx[at] = v.x, n.ny[at] = v.y, n.nz[at] = v.z;
      if (facets) {
        Vec3f fn[kCornerFacets];
        corner_facet_normals(f, i, j, fn);
        for (std::size_t q = 0; q < kCornerFacets; ++q)
          n.fx[q * N + at] = fn[q].x, n.fy[q * N + at] = fn[q].y, n.fz[q * N + at] = fn[q].z;
      }
    }
  });
  return n;
}

// curvature: Scene::curvature, each crossing dropped by it (lane_horizons.hpp). floor: with a far field,
// each horizon raised to the coarse copy's floor (far_floor.hpp); returns the largest slack it left. reuse:
// lane_directions' between the bake's blocks (or null).
template <class Shade>
double lane_direction_sums(const HeightField& f, double curvature, const P1Params& p, int k_begin, int k_end,
                           const RunControl& rc, bool facets, const FieldNormals& normals,
                           const p1::FloorGrid* floor, const Shade& shade, p1::LaneReuse* reuse) {
  const std::size_t N = f.texel_count();
  const int K = p.directions;
  const std::vector<float>&nx = normals.nx, &ny = normals.ny, &nz = normals.nz;
  const std::vector<float>&fx = normals.fx, &fy = normals.fy, &fz = normals.fz;
  const bool lit = !nx.empty();  // the lighting reads normals (shading_reads_normals)
  SweepSpec probe;
  probe.directions = K;
  std::vector<int> ks;
  for (int k = k_begin; k < k_end; ++k) ks.push_back(k);
  int done = 0;
  p1::DirectionFloor df;
  std::vector<double> row_slack(floor ? std::size_t(f.height) : 0, 0.0);  // one slot a row: any thread count
  p1::lane_directions(
      f, probe, ks, curvature, float(p.horizon_tolerance), p.horizon_distance, rc,
      [&](const SweepDirection& sd, const p1::LaneDirection& d, const float* slope,
          const std::int32_t* which) {
        const int k = sd.k;
        if (floor) p1::direction_floor(*floor, f.width, f.height, azimuth(k, K), df);
        tbb::parallel_for(0, f.height, [&](int j) {
          constexpr int kRun = p1::kShadeRun;
          alignas(64) float m[kRun], dist[kRun];
          for (int i0 = 0; i0 < f.width; i0 += kRun) {
            const int w = std::min(kRun, f.width - i0);
            const std::size_t base = f.index(i0, j);
            for (int x = 0; x < w; ++x) m[x] = slope[base + x];
            if (p.horizon_distance)
              for (int x = 0; x < w; ++x) {
                const std::int32_t c = which[base + x];
                dist[x] = c < 0 ? std::numeric_limits<float>::infinity()
                                : std::sqrt(1 + m[x] * m[x]) / d.crossings[std::size_t(c)].inv_s;
              }
            if (floor)
              for (int x = 0; x < w; ++x)
                m[x] = p1::raise_to_floor(*floor, df, i0 + x, j, f.z[base + x], m[x],
                                          row_slack[std::size_t(j)], &dist[x]);
            const float *FX[kCornerFacets] = {}, *FY[kCornerFacets] = {}, *FZ[kCornerFacets] = {};
            if (facets)
              for (std::size_t q = 0; q < kCornerFacets; ++q)
                FX[q] = fx.data() + q * N + base, FY[q] = fy.data() + q * N + base,
                FZ[q] = fz.data() + q * N + base;
            shade(k, base, w, lit ? nx.data() + base : nullptr, lit ? ny.data() + base : nullptr,
                  lit ? nz.data() + base : nullptr, FX, FY, FZ, m,
                  /*slopes=*/true, dist);
          }
        });
        rc.report(double(++done) / double(k_end - k_begin));
      },
      reuse, p.wrap_periods);
  if (row_slack.empty()) return 0.0;
  // Rounded up to a float, as the farm's blocks carry it (bake_p1.cpp far_slack@): the same bound either way.
  return double(p1::round_up_to_float(*std::max_element(row_slack.begin(), row_slack.end())));
}

}  // namespace

const std::vector<std::string>& p1_layer_names() {
  static const std::vector<std::string> names = {
      "ao", "vsky", "direct", "horizon", "horizon_distance", "bent_normal"};
  return names;
}

P1Params read_p1_params(Params& in, const FieldShape& field) {
  P1Params p;
  p.directions = in.integer("directions", p.directions, 1, 4096);
  p.normal_bins = in.integer("normal_bins", p.normal_bins, 0, 1023);
  if (p.normal_bins != 0 && (p.normal_bins < 3 || p.normal_bins % 2 == 0))
    in.fail("normal_bins",
            "must be 0 (exact) or odd and >= 3 (7, 15, 31, ...: odd counts make up-facing normals exact)");
  p.horizon_bins = in.integer("horizon_bins", p.horizon_bins, 2, 65536);
  p.wrap_periods = in.integer("wrap_periods", p.wrap_periods, 1, 16);
  p.near_radius = in.number("near_radius", p.near_radius, 1, 64);
  p.horizon_tolerance = in.number("horizon_tolerance", p.horizon_tolerance, 0, 0.5);
  in.boolean("far_crossings", true);  // accepted and ignored: the far field is exact (far_horizons.hpp)
  p.lights = in.boolean("lights", p.lights);
  const std::vector<std::string> layers = in.layers(p1_layer_names(), {"ao", "vsky", "direct"});
  auto wants = [&](const char* name) {
    return std::find(layers.begin(), layers.end(), name) != layers.end();
  };
  p.ao = wants("ao");
  p.vsky = wants("vsky");
  p.direct = wants("direct");
  p.horizon = wants("horizon");
  p.horizon_distance = wants("horizon_distance");
  p.bent_normal = wants("bent_normal");
  p.far_field = read_field_wide_far_field(in, field);
  return p;
}

SweepSpec p1_sweep_spec(const P1Params& p) {
  SweepSpec spec;
  spec.directions = p.directions;
  spec.channels = p1::FarHorizonWorker::channels();
  spec.wrap_periods = p.wrap_periods;
  spec.tile.nearest = false;
  spec.tile.strip = true;
  spec.tile.values = false;
  // FarHorizonWorker writes every receiver, from its own profiles of the field (LinePattern), not the
  // line's heights.
  spec.buffers.zero = false;
  spec.sampling.heights = false;
  // 8 directions per gather pass: the per-texel accumulators cross memory K / 8 times.
  spec.buffers.batch = 8;
  return spec;
}

SweepSpec p1_block_sweep_spec(const P1Params& p, int k_begin, int k_end) {
  SweepSpec spec = p1_sweep_spec(p);
  for (int k = k_begin; k < k_end; ++k) spec.azimuths.push_back(azimuth(k, p.directions));
  return spec;
}

double p1_working_bytes(const FieldShape& shape, const P1Params& p, bool uniform_environment) {
  const bool facets = p.direct && p.facet_direct;
  const double texels = double(shape.width) * double(shape.height);
  // A far field: the field's own coarse copy (a tile's is the raster's, counted by the tile plan) and one
  // direction's floor.
  const double far = p.far_field ? coarse_bytes(shape.width, shape.height, p.far_field->cell) +
                                       p1::floor_bytes(shape.width, shape.height, p.far_field->cell)
                                 : 0.0;
  // A direction block's horizon layers by direction before they are placed (HorizonPlanes), bytes a texel.
  const int B = direction_block_count(p.directions);
  const double planes = p.horizon_by_direction ? 0.0
                                               : 4.0 * double((p.directions + B - 1) / B) *
                                                     ((p.horizon ? 1 : 0) + (p.horizon_distance ? 1 : 0));
  HeightField field;  // the sweeps' plans need only the shape
  static_cast<FieldShape&>(field) = shape;
  const int longest =
      std::max(shape.width, shape.height) * (shape.wrap == Wrap::repeat ? p.wrap_periods + 1 : 1);
  const double workers = double(worker_threads()) * double(p1::FarHorizonWorker::scratch_bytes(longest));
  // The corner facets' (field/triangulation.hpp): a sum (4 bytes, or RGB 12) and a layer (RGB 12) each.
  const double CF = kCornerFacets;
  const double facet_sums = facets ? (uniform_environment ? 4 : 12) * CF : 0;
  // Bytes a texel: the sums (p1_sums_shape) and the layers the caller counts, which the sums become.
  const double sums = (p.ao || (p.direct && uniform_environment) ? 4 : 0) + (p.vsky ? 4 : 0) +
                      (p.direct && !uniform_environment ? 12 : 0) + (p.bent_normal ? 12 : 0) + facet_sums;
  const double caller_layers =
      (p.ao ? 4 : 0) + (p.vsky ? 4 : 0) + (p.direct ? 12 : 0) + (p.bent_normal ? 12 : 0);
  // While the sums are finished (p1_finish): the layers, the ao sum behind a uniform sky's direct, and P2's
  // facets' layer beside their sums (no caller counts either).
  const double finished = caller_layers + (p.direct && !p.ao && uniform_environment ? 4 : 0) +
                          (facets ? 12 * CF + facet_sums : 0);
  if (p1::lane_tiles(shape.width, shape.height, shape.wrap, p.wrap_periods)) {
    // ... and what the lane search holds.
    const double normals = shading_reads_normals(p) ? 12 + (facets ? 12 * CF : 0) : 0;
    const double block = direction_block_count(p.directions) > 1 ? sums : 0;  // one block's beside the total
    // While the directions are summed: the sums, a block's, the normals, one direction's slopes (and casters
    // for horizon_distance), and one axis' lane layout (a repeat field's: its tiling's).
    const double layout = p1::lane_layout_bytes(shape.width, shape.height, shape.wrap, p.wrap_periods);
    const double search = p.horizon_distance ? 8 : 4;
    const double summing = (sums + block + normals + search + planes) * texels + layout;
    // While they are finished: the normals beside them, and the lights' sweeps.
    // A repeat field's lights search its tiling too.
    const double lights = shape.wrap == Wrap::repeat && p.direct && p.lights ? layout : 0.0;
    const double finishing = (finished + normals) * texels +
                             double(sweep_buffer_bytes(field, p1_sweep_spec(p))) / 8 + workers + lights;
    return std::max(summing, finishing) - caller_layers * texels + far;
  }
  // Repeat fields: the strip search sums one direction block at a time (compute_p1), each through its own
  // sweep, whose line buffers FarHorizonWorker fills whole (every receiver slot of every line); the largest
  // block's is the one counted.
  const int largest = (p.directions + B - 1) / B;
  const double block_sweep = double(sweep_buffer_bytes(field, p1_block_sweep_spec(p, 0, largest)));
  // While summing: the sums, the block's beside them (their arrays reused from block to block), the
  // block's horizon planes, its sweep and the workers.
  const double summing_repeat = (sums + (B > 1 ? sums : 0) + planes) * texels + block_sweep + workers;
  // While finishing: the directional lights' sweep (p1_horizons_at) beside them, counted as one direction's.
  const double light_sweep =
      p.direct && p.lights ? double(sweep_buffer_bytes(field, p1_block_sweep_spec(p, 0, 1))) + workers : 0.0;
  const double finishing_repeat = finished * texels + light_sweep;
  return std::max(summing_repeat, finishing_repeat) - caller_layers * texels;
}

double disk_fraction_above(double elevation, double horizon, double radius) {
  if (radius <= 0) return elevation > horizon ? 1.0 : 0.0;
  const double x = (elevation - horizon) / radius;
  if (x >= 1) return 1.0;
  if (x <= -1) return 0.0;
  return (std::acos(-x) + x * std::sqrt(1 - x * x)) / kPi;
}

P1SumsShape p1_sums_shape(const Scene& scene, const P1Params& p) {
  const bool uniform_env = scene.environment.is_uniform();
  const bool facets = p.direct && p.facet_direct;
  P1SumsShape s;
  s.ao = p.ao || (p.direct && uniform_env) ? 1 : 0;
  s.vsky = p.vsky ? 1 : 0;
  s.rgb = p.direct && !uniform_env ? 3 : 0;
  s.bent = p.bent_normal ? 3 : 0;
  s.fao = facets && uniform_env ? kCornerFacets : 0;
  s.fd = facets && !uniform_env ? kCornerFacets : 0;
  return s;
}

namespace {

// A bake of directions [k_begin, k_end) in three phases: the block's sums, zero, shaped for the layers
// asked for (zero_sums); the lighting of a row run of texels from their horizons (RowShading); and the
// horizons themselves, by the lane search (lane_direction_sums) or, on a repeat field too large for its
// tiling (lane_tiles), the strip search (strip_direction_sums), each handing RowShading its horizons a row
// run at a time.

// The block's accumulators: only what the requested layers need, each the layer it becomes (p1_finish
// finishes them in place); the horizon layers' own arrays when the caller gives none (own_horizon,
// own_distance): [texel * nb + k - k_begin] ([(k - k_begin) * N + texel] by direction). spare: arrays to
// reuse (a finished block's), or empty.
P1Sums zero_sums(const Scene& scene, const P1Params& p, int k_begin, int k_end, bool own_horizon,
                 bool own_distance, P1Sums&& spare) {
  const std::size_t N = scene.field.texel_count();
  const std::size_t nb = std::size_t(k_end - k_begin);
  const P1SumsShape shape = p1_sums_shape(scene, p);
  P1Sums r = std::move(spare);  // a previous block's arrays, zeroed in place (no fresh pages to fault in)
  r.far_slack = 0;
  r.k_begin = k_begin, r.k_end = k_end;
  r.ao.assign(shape.ao * N, 0.0f), r.vsky.assign(shape.vsky * N, 0.0f);
  r.rgb.assign(shape.rgb * N, 0.0f);    // [3 * texel + c]
  r.bent.assign(shape.bent * N, 0.0f);  // [3 * texel + c]
  // The facets' direct-light sums, [q * N + texel] (facet q of P1Result::direct_facets).
  r.fao.assign(shape.fao * N, 0.0f);
  r.fdr.assign(shape.fd * N, 0.0f), r.fdg.assign(r.fdr.size(), 0.0f), r.fdb.assign(r.fdr.size(), 0.0f);
  if (p.horizon && own_horizon) r.horizon.assign(N * nb, 0.0f);
  if (p.horizon_distance && own_distance) r.horizon_distance.assign(N * nb, 0.0f);
  return r;
}

// A direction block's horizon layer (horizon or horizon_distance) as RowShading writes it, one plane of N
// texels per direction of the block, and where it goes: into `out` of `per_texel` directions per texel at
// direction `first` ([texel * per_texel + first + j] for the block's j-th), or, by direction, into
// [(first + j) * N + texel], which are the planes themselves.
struct HorizonPlanes {
  float* planes = nullptr;  // `out`'s own when by direction, else a BlockScratch's
  float* out = nullptr;
  std::size_t N = 0;
  int per_texel = 0, first = 0, count = 0;
  bool by_direction = false;

  // Into the layer's order: each texel's `count` values contiguous, read from `count` sequential planes.
  void place() const {
    if (!planes || by_direction) return;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, N, 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) { place_texels(r.begin(), r.end()); });
  }

  // Texels [t0, t1): four texels of four planes at a time as a 4x4 transpose (SSE2, the x86-64 baseline: a
  // copy, the same bits), which reads and writes whole vectors where a texel at a time reads one float of
  // each plane.
  void place_texels(std::size_t t0, std::size_t t1) const {
    const std::size_t P = std::size_t(per_texel);
    const int c4 = count / 4 * 4;
    std::size_t t = t0;
    for (; t + 4 <= t1; t += 4) {
      float* o = out + t * P + std::size_t(first);
      for (int j = 0; j < c4; j += 4) {
        const float* p = planes + std::size_t(j) * N + t;
        __m128 a = _mm_loadu_ps(p), b = _mm_loadu_ps(p + N), c = _mm_loadu_ps(p + 2 * N),
               d = _mm_loadu_ps(p + 3 * N);
        _MM_TRANSPOSE4_PS(a, b, c, d);
        _mm_storeu_ps(o + j, a), _mm_storeu_ps(o + P + j, b), _mm_storeu_ps(o + 2 * P + j, c),
            _mm_storeu_ps(o + 3 * P + j, d);
      }
      for (int j = c4; j < count; ++j)
        for (std::size_t x = 0; x < 4; ++x) o[x * P + std::size_t(j)] = planes[std::size_t(j) * N + t + x];
    }
    for (; t < t1; ++t) {
      float* o = out + t * P + std::size_t(first);
      for (int j = 0; j < count; ++j) o[j] = planes[std::size_t(j) * N + t];
    }
  }
};

// What a bake's direction blocks reuse: the horizon planes, allocated once (on huge pages, uninitialised:
// RowShading writes every texel of a plane before it is placed), and the lane search's layout and arrays.
struct BlockScratch {
  p1::LaneReuse lanes;
  P1Sums spare;  // the last block's sums once added to the total
  PageBuffer<float> horizon, distance;
  std::size_t horizon_n = 0, distance_n = 0;
  float* get(bool distance_layer, std::size_t n) {
    PageBuffer<float>& b = distance_layer ? distance : horizon;
    std::size_t& have = distance_layer ? distance_n : horizon_n;
    if (have < n) b = make_page_buffer<float>(n), have = n;
    return b.get();
  }
};

HorizonPlanes horizon_planes(float* out, int per_texel, int first, bool by_direction, std::size_t N,
                             int count, BlockScratch& scratch, bool distance_layer) {
  HorizonPlanes h;
  h.out = out, h.N = N, h.per_texel = per_texel, h.first = first, h.count = count;
  h.by_direction = by_direction;
  h.planes =
      by_direction ? out + std::size_t(first) * N : scratch.get(distance_layer, std::size_t(count) * N);
  return h;
}

// The lighting of one row run of texels (base .. base + w - 1, at most 32) in direction k from their
// horizons, at the texels' normals (and the facets' normals FX[q], FY[q], FZ[q]), added to the block's sums;
// the horizon layers' values written (row_shading.hpp: the kernel for this processor's instruction set).
// Called from many threads at once for disjoint texels.
struct RowShading {
  std::optional<p1::LightingTables> tables;
  std::optional<p1::SwathProfiles> profiles;
  std::vector<float> cs, sn;  // the azimuths' cosines and sines
  p1::ShadeRowTarget target;
  p1::ShadeRowFn kernel = nullptr;

  // The block's sums r, sized by zero_sums (not resized while this lives); the block's horizon layers by
  // direction, [(k - k_begin) * N + texel] (HorizonPlanes): each direction writes a contiguous run, where
  // the layers' own order would scatter a store over K floats per texel.
  RowShading(const Scene& scene, const P1Params& p, int k_begin, P1Sums& r, float* horizon_planes,
             float* distance_planes)
      : kernel(p1::shade_row_kernel()) {
    const Environment& env = scene.environment;
    p1::ShadeRowTarget& t = target;
    t.N = scene.field.texel_count();
    t.k_begin = k_begin;
    t.uniform_env = env.is_uniform();
    t.facets = p.direct && p.facet_direct;
    if (p.direct && !t.uniform_env) {
      if (p.normal_bins > 0)
        tables = p1::build_lighting_tables(env, p.directions, p.normal_bins, p.horizon_bins);
      else
        profiles = p1::build_swath_profiles(env, p.directions);
    }
    const bool need_ao = p1_sums_shape(scene, p).ao > 0;
    t.need_theta = need_ao || p.bent_normal || profiles;
    t.normals = shading_reads_normals(p);
    azimuth_table(p.directions, cs, sn);
    t.cs = cs.data(), t.sn = sn.data();
    t.ao = need_ao ? r.ao.data() : nullptr;
    t.vsky = p.vsky ? r.vsky.data() : nullptr;
    t.rgb = r.rgb.empty() ? nullptr : r.rgb.data();
    t.bent = p.bent_normal ? r.bent.data() : nullptr;
    t.fao = r.fao.empty() ? nullptr : r.fao.data();
    t.fdr = r.fdr.empty() ? nullptr : r.fdr.data();
    t.fdg = r.fdg.empty() ? nullptr : r.fdg.data();
    t.fdb = r.fdb.empty() ? nullptr : r.fdb.data();
    t.hz = p.horizon ? horizon_planes : nullptr;
    t.hd = p.horizon_distance ? distance_planes : nullptr;
    t.tables = tables ? &*tables : nullptr;
    t.profiles = profiles ? &*profiles : nullptr;
  }
  RowShading(const RowShading&) = delete;
  RowShading& operator=(const RowShading&) = delete;

  // h: the texels' horizons, slopes (rise / run) when `slopes`, else elevations in radians; dist: the
  // horizon_distance layer's values, or null.
  void operator()(int k, std::size_t base, int w, const float* NX, const float* NY, const float* NZ,
                  const float* const* FX, const float* const* FY, const float* const* FZ, const float* h,
                  bool slopes, const float* dist) const {
    p1::ShadeRowRun run;
    run.k = k, run.base = base, run.w = w;
    run.nx = NX, run.ny = NY, run.nz = NZ;
    if (target.facets)
      for (int q = 0; q < kCornerFacets; ++q) run.fx[q] = FX[q], run.fy[q] = FY[q], run.fz[q] = FZ[q];
    run.horizon = h, run.slopes = slopes, run.distance = dist;
    kernel(target, run);
  }
};

// The strip search's horizons (repeat fields): the near field by each direction's stencil from the texel
// centre, the far field by the sweep's strips (far_horizons.hpp), shade(...) per row run of a sweep tile.
template <class Shade>
void strip_direction_sums(const HeightField& f, const Vec3f* given, const P1Params& p, int k_begin, int k_end,
                          const RunControl& rc, bool facets, const Shade& shade) {
  const int K = p.directions;
  // The tile's normals, per thread: recomputed (normal_at) when the sweep hands the thread a new tile, kept
  // while the batch's directions visit it.
  constexpr int kTileTexels = 32 * 32;  // sweep_lines_tiled's tiles
  struct TileNormals {
    int i0 = -1, j0 = -1;
    // [y * width + x]; the corner facets' [q * kTileTexels + y * width + x]
    alignas(64) float nx[kTileTexels], ny[kTileTexels], nz[kTileTexels];
    alignas(64) float fx[kCornerFacets * kTileTexels], fy[kCornerFacets * kTileTexels],
        fz[kCornerFacets * kTileTexels];
  };
  tbb::enumerable_thread_specific<TileNormals> tile_normals;
  auto normals_of = [&](const SweepTile& t) -> const TileNormals& {
    TileNormals& n = tile_normals.local();
    if (n.i0 == t.i0 && n.j0 == t.j0) return n;
    n.i0 = t.i0, n.j0 = t.j0;
    for (int y = 0; y < t.height; ++y)
      for (int x = 0; x < t.width; ++x) {
        const int at = y * t.width + x;
        const Vec3f v = texel_normal(f, given, t.i0 + x, t.j0 + y);
        n.nx[at] = v.x, n.ny[at] = v.y, n.nz[at] = v.z;
        if (facets) {
          Vec3f fn[kCornerFacets];
          corner_facet_normals(f, t.i0 + x, t.j0 + y, fn);
          for (int q = 0; q < kCornerFacets; ++q)
            n.fx[q * kTileTexels + at] = fn[q].x, n.fy[q * kTileTexels + at] = fn[q].y,
                                   n.fz[q * kTileTexels + at] = fn[q].z;
        }
      }
    return n;
  };
  // The near field of each direction of the block (horizon_sweep.hpp, near_stencil).
  std::vector<p1::NearStencil> near(K);
  {
    SweepSpec probe;
    probe.directions = K;
    for (int k = k_begin; k < k_end; ++k)
      near[k] = p1::near_stencil(f, plan_direction(f, probe, k), p.near_radius);
  }
  auto near_slope_border = [&](int k, int i, int j, int* which) {
    return near_slope(f, near[k].crossings, i, j, which);
  };

  const SweepSpec spec = p1_block_sweep_spec(p, k_begin, k_end);
  auto make_worker = [&] { return make_ray_worker(f, p); };
  sweep_lines_tiled(f, spec, rc, make_worker, [&](const SweepTile& t) {
    constexpr int kMax = p1::kShadeRun;
    const int k = k_begin + t.k, w = t.width;
    alignas(64) float e[kMax], en[kMax];
    const std::size_t plane = std::size_t(t.width) * t.height;
    const TileNormals& tn = normals_of(t);
    for (int y = 0; y < t.height; ++y) {
      const std::size_t base = f.index(t.i0, t.j0 + y);
      {
        // Near field: the steepest crossing within near_radius, marched from the texel center itself
        // (interior texels by the direction's fixed stencil, vectorised; border texels one by one).
        p1::near_slopes_row(f, near[k], t.i0, t.j0 + y, w, en);
        for (int x = 0; x < w; ++x) en[x] = fast_atan(en[x]);
        // Far field: the steepest point of the texel's own ray at least near_radius away, exact on the
        // triangulated surface (FarHorizonWorker, by the texel's strip).
        const std::size_t row = std::size_t(y) * w;
        for (int x = 0; x < w; ++x) {
          const FarPick fp = far_pick(t.strip, plane, row + x);
          e[x] = std::max(en[x], p1::caster_elevation(fp.dz, fp.run));
        }
      }
      float dist[kMax];
      if (p.horizon_distance) {  // the near crossing, or the far caster on the texel's own ray
        const std::size_t row = std::size_t(y) * w;
        for (int x = 0; x < w; ++x) {
          int which;
          const float near_m = near_slope_border(k, t.i0 + x, t.j0 + y, &which);
          const FarPick fp = far_pick(t.strip, plane, row + x);
          const float far_e = p1::caster_elevation(fp.dz, fp.run);
          if (which >= 0 && fast_atan(near_m) >= far_e)
            dist[x] = std::sqrt(1 + near_m * near_m) /
                      near[k].crossings[which].inv_s;  // run 1 / inv_s, rise m * run
          else
            dist[x] = fp.run == std::numeric_limits<float>::infinity() ? fp.run : std::hypot(fp.run, fp.dz);
        }
      }
      const std::size_t ft = std::size_t(y) * w;
      const float *FX[kCornerFacets], *FY[kCornerFacets], *FZ[kCornerFacets];
      for (int q = 0; q < kCornerFacets; ++q)
        FX[q] = tn.fx + q * kTileTexels + ft, FY[q] = tn.fy + q * kTileTexels + ft,
        FZ[q] = tn.fz + q * kTileTexels + ft;
      shade(k, base, w, tn.nx + y * w, tn.ny + y * w, tn.nz + y * w, FX, FY, FZ, e, /*slopes=*/false, dist);
    }
  });
}

P1Sums direction_sums(const Scene& scene, const P1Params& p, int k_begin, int k_end, const RunControl& rc,
                      float* horizon_out, float* distance_out, const FieldNormals* normals,
                      const p1::FloorGrid* floor, BlockScratch& scratch) {
  const HeightField& f = scene.field;
  const bool facets = p.direct && p.facet_direct;
  P1Sums r = zero_sums(scene, p, k_begin, k_end, !horizon_out, !distance_out, std::move(scratch.spare));
  const int K = p.directions, nb = k_end - k_begin;
  HorizonPlanes hz, hd;
  if (p.horizon)
    hz = horizon_planes(horizon_out ? horizon_out : r.horizon.data(), horizon_out ? K : nb,
                        horizon_out ? k_begin : 0, p.horizon_by_direction, f.texel_count(), nb, scratch,
                        false);
  if (p.horizon_distance)
    hd = horizon_planes(distance_out ? distance_out : r.horizon_distance.data(), distance_out ? K : nb,
                        distance_out ? k_begin : 0, false, f.texel_count(), nb, scratch, true);
  const RowShading shade(scene, p, k_begin, r, hz.planes, hd.planes);
  if (!p1::lane_tiles(f.width, f.height, f.wrap, p.wrap_periods)) {
    strip_direction_sums(f, given_normals(scene, p), p, k_begin, k_end, rc, facets, shade);
  } else if (normals) {
    r.far_slack = lane_direction_sums(f, scene.curvature, p, k_begin, k_end, rc, facets, *normals, floor,
                                      shade, &scratch.lanes);
  } else {
    const FieldNormals own = field_normals(scene, p);
    r.far_slack = lane_direction_sums(f, scene.curvature, p, k_begin, k_end, rc, facets, own, floor, shade,
                                      &scratch.lanes);
  }
  hz.place(), hd.place();
  return r;
}

}  // namespace

P1Sums p1_direction_sums(const Scene& scene, const P1Params& p, int k_begin, int k_end, const RunControl& rc,
                         float* horizon_out, float* distance_out) {
  CoarseHeights own;
  const std::unique_ptr<p1::FloorGrid> floor = p1_floor_grid(scene, p, own, scene.curvature);
  BlockScratch scratch;
  return direction_sums(scene, p, k_begin, k_end, rc, horizon_out, distance_out, nullptr, floor.get(),
                        scratch);
}

std::unique_ptr<p1::FloorGrid> p1_floor_grid(const Scene& scene, const P1Params& p, CoarseHeights& own,
                                             double curvature) {
  if (!p.far_field) return nullptr;
  const HeightField& f = scene.field;
  if (f.wrap != Wrap::clamp) throw std::logic_error("p1_floor_grid: a far field on a repeat field");
  const CoarseHeights* coarse = scene.window.coarse_of(p.far_field->cell);
  if (!coarse) {
    own = coarse_heights(f, p.far_field->cell);
    coarse = &own;
  }
  auto grid = std::make_unique<p1::FloorGrid>(
      p1::floor_grid(*coarse, scene.window.x0, scene.window.y0, f, p.far_field->beyond, curvature));
  grid->kept = scene.window.kept;
  return grid;
}

void p1_add_sums(P1Sums& total, const P1Sums& block) {
  auto add = [](std::vector<float>& t, const std::vector<float>& b) {
    for (std::size_t i = 0; i < t.size(); ++i) t[i] += b[i];
  };
  add(total.ao, block.ao), add(total.vsky, block.vsky), add(total.rgb, block.rgb),
      add(total.bent, block.bent);
  add(total.fao, block.fao), add(total.fdr, block.fdr), add(total.fdg, block.fdg), add(total.fdb, block.fdb);
  total.far_slack = std::max(total.far_slack, block.far_slack);
  total.k_end = block.k_end;
}

P1Result compute_p1(const Scene& scene, const P1Params& p, const RunControl& rc) {
  const std::size_t N = scene.field.texel_count();
  const int K = p.directions, B = direction_block_count(K);
  // The horizon layers are written once, so they stay on 4 KiB pages, faulted in by one call
  // (populated_zeros): a huge page is taken from the large free blocks a virtual machine hands back to its
  // host (free page reporting), and first-touching 256 MiB of them cost up to 0.6 s of system time on this
  // project's VM, as much as 4 KiB pages faulted one at a time. The scratch that is written again and again
  // (core/page_buffer.hpp) keeps its huge pages.
  std::vector<float> horizon = populated_zeros<float>(p.horizon ? N * K : 0),
                     distance = populated_zeros<float>(p.horizon_distance ? N * K : 0);
  BlockScratch scratch;
  const double lights_share = p.direct && p.lights && !scene.lights.empty()
                                  ? double(scene.lights.size()) / double(K + scene.lights.size())
                                  : 0.0;
  // Direction blocks (core/direction_blocks.hpp): each summed from zero, the blocks added in order -- the
  // order `hfbake merge` adds the farm's shards in.
  P1Sums total;
  std::optional<FieldNormals> normals;  // the lane path's, shared by the blocks
  if (p1::lane_tiles(scene.field.width, scene.field.height, scene.field.wrap, p.wrap_periods))
    normals = field_normals(scene, p);
  CoarseHeights own;
  const std::unique_ptr<p1::FloorGrid> floor = p1_floor_grid(scene, p, own, scene.curvature);
  for (int b = 0; b < B; ++b) {
    const int k0 = direction_block_begin(b, K), k1 = direction_block_begin(b + 1, K);
    P1Sums part = direction_sums(
        scene, p, k0, k1, sub_progress(rc, (1 - lights_share) * k0 / K, (1 - lights_share) * (k1 - k0) / K),
        horizon.empty() ? nullptr : horizon.data(), distance.empty() ? nullptr : distance.data(),
        normals ? &*normals : nullptr, floor.get(), scratch);
    if (b == 0) {
      total = std::move(part);
    } else {
      p1_add_sums(total, part);
      scratch.spare = std::move(part);
    }
  }
  scratch = BlockScratch();  // not held while the sums are finished
  total.horizon = std::move(horizon);
  total.horizon_distance = std::move(distance);
  return p1_finish(scene, p, std::move(total), sub_progress(rc, 1 - lights_share, lights_share));
}

P1Result p1_finish(const Scene& scene, const P1Params& p, P1Sums&& sums, const RunControl& rc) {
  const HeightField& f = scene.field;
  const std::size_t N = f.texel_count();
  const int K = p.directions;
  P1Result r;
  r.width = f.width;
  r.height = f.height;
  r.directions = K;
  r.horizon = std::move(sums.horizon);
  r.horizon_distance = std::move(sums.horizon_distance);
  double far_slack = sums.far_slack;
  const Vec3f* given = given_normals(scene, p);
  const Environment& env = scene.environment;
  const bool uniform_env = env.is_uniform();
  const bool facets = p.direct && p.facet_direct;
  const std::size_t NF = facets ? kCornerFacets * N : 0;
  std::vector<float>&ao_sum = sums.ao, &vsky_sum = sums.vsky, &rgb_sum = sums.rgb, &bent_sum = sums.bent;
  const std::vector<float>&fao = sums.fao, &fdr = sums.fdr, &fdg = sums.fdg, &fdb = sums.fdb;
  std::vector<const DirectionalLight*> lights;
  if (p.direct && p.lights)
    for (const DirectionalLight& l : scene.lights)
      if (l.irradiance.r > 0 || l.irradiance.g > 0 || l.irradiance.b > 0) lights.push_back(&l);

  // The sums become the layers in place.
  const float inv_k = 1.0f / float(K);
  if (p.direct) {
    if (uniform_env)
      r.direct.resize(3 * N);
    else
      r.direct = std::move(rgb_sum);
  }
  tbb::parallel_for(std::size_t(0), N, [&](std::size_t idx) {
    if (p.direct && uniform_env) {
      const Rgb d = env.uniform_radiance * (ao_sum[idx] * inv_k);
      r.direct[3 * idx] = d.r, r.direct[3 * idx + 1] = d.g, r.direct[3 * idx + 2] = d.b;
    }
    // A share: a rounding above 1 is 1, below 0 (a texel whose every direction is a sliver of sky) 0.
    if (p.ao) ao_sum[idx] = std::clamp(ao_sum[idx] * inv_k, 0.0f, 1.0f);
    if (p.vsky) vsky_sum[idx] = 1.0f - vsky_sum[idx] * inv_k;
    if (p.bent_normal) {
      float* b = bent_sum.data() + 3 * idx;
      const Vec3 v{b[0], b[1], b[2]};
      const Vec3f n = length(v) > 1e-12 ? Vec3f::from(normalize(v))
                                        : texel_normal(f, given, int(idx % std::size_t(f.width)),
                                                       int(idx / std::size_t(f.width)));
      b[0] = n.x, b[1] = n.y, b[2] = n.z;
    }
  });
  if (p.ao) r.ao = std::move(ao_sum);
  std::vector<float>().swap(ao_sum);
  if (p.vsky) r.vsky = std::move(vsky_sum);
  if (p.bent_normal) r.bent_normal = std::move(bent_sum);

  std::vector<Rgb> direct_facets(NF);
  if (facets)
    tbb::parallel_for(std::size_t(0), N, [&](std::size_t idx) {
      for (std::size_t q = 0; q < kCornerFacets; ++q) {
        const std::size_t t = q * N + idx;
        direct_facets[kCornerFacets * idx + q] =
            uniform_env ? env.uniform_radiance * (fao[t] * inv_k) : Rgb{fdr[t], fdg[t], fdb[t]};
      }
    });

  // Directional lights: each texel's horizon at each light's azimuth (p1_horizons_at, as the K directions').
  CoarseHeights own;
  const std::unique_ptr<p1::FloorGrid> floor =
      lights.empty() ? nullptr : p1_floor_grid(scene, p, own, scene.curvature);
  double light_slack = 0;
  if (!lights.empty()) {
    std::vector<double> elevation, radius, azimuths;
    std::vector<Vec3> dir;
    for (const DirectionalLight* l : lights) {
      const Vec3 d = normalize(l->direction);
      dir.push_back(d);
      elevation.push_back(std::asin(std::clamp(d.z, -1.0, 1.0)));
      radius.push_back(l->angular_diameter / 2);
      azimuths.push_back(std::hypot(d.x, d.y) > 1e-12 ? std::atan2(d.y, d.x) : 0.0);
    }
    p1_horizons_at(
        f, p, azimuths, rc,
        [&](int li, int i, int j, float horizon) {
          const std::size_t idx = f.index(i, j);
          const double ndl = dot(texel_normal(f, given, i, j).d(), dir[li]);
          if (ndl <= 0 && !facets) return;
          const double frac = disk_fraction_above(elevation[li], horizon, radius[li]);
          if (frac <= 0) return;
          if (ndl > 0) {
            const Rgb add = lights[li]->irradiance * float(ndl * frac / kPi);
            float* d = r.direct.data() + 3 * idx;
            d[0] += add.r, d[1] += add.g, d[2] += add.b;
          }
          if (facets) {
            Vec3f fn[kCornerFacets];
            corner_facet_normals(f, i, j, fn);
            for (std::size_t q = 0; q < kCornerFacets; ++q) {
              const double fdl = fn[q].x * dir[li].x + fn[q].y * dir[li].y + fn[q].z * dir[li].z;
              if (fdl > 0)
                direct_facets[kCornerFacets * idx + q] += lights[li]->irradiance * float(fdl * frac / kPi);
            }
          }
        },
        scene.curvature, floor.get(), &light_slack);
  }
  r.direct_facets = std::move(direct_facets);
  if (p.far_field) r.far_field_bound = std::max(far_slack, light_slack);
  rc.report(1.0);
  return r;
}

}  // namespace hfbake
