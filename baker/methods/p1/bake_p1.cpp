#include "methods/p1/bake_p1.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "core/direction_blocks.hpp"
#include "methods/p1/far_horizons.hpp"
#include "methods/p1/fast_math.hpp"
#include "methods/p1/horizon_sweep.hpp"
#include "methods/p1/lane_horizons.hpp"
#include "methods/p1/p1.hpp"

namespace hfbake {

namespace {

// The layers of a P1Result, in the order the job lists them (moved, never copied).
LayerSet p1_layers(P1Result&& r, const P1Params& p, const std::vector<std::string>& order) {
  LayerSet out;
  out.width = r.width;
  out.height = r.height;
  // Layers in the order the job lists them (default: ao, vsky, direct); compute_p1's arrays are the
  // layers' data already (moved, never copied).
  for (const std::string& name : order) {
    if (name == "ao") {
      out.adopt("ao", mono_channels(), std::move(r.ao));
    } else if (name == "vsky") {
      out.adopt("vsky", mono_channels(), std::move(r.vsky));
    } else if (name == "direct") {
      out.adopt("direct", rgb_channels(), std::move(r.direct));
    } else if (name == "horizon") {
      out.adopt("horizon", indexed_channels(r.directions), std::move(r.horizon));
    } else if (name == "horizon_distance") {
      out.adopt("horizon_distance", indexed_channels(r.directions), std::move(r.horizon_distance));
    } else if (name == "bent_normal") {
      out.adopt("bent_normal", xyz_channels(), std::move(r.bent_normal));
    }
  }
  out.attributes.emplace_back("hfbake:p1:horizon",
                              "sin(elevation) per direction k, azimuth 2 pi k / K from +x towards +y; "
                              "horizon_distance: world units to the caster, inf where none");
  if (p.far_field) {
    char b[200];
    std::snprintf(b, sizeof b,
                  "beyond %.9g world units: a floor from coarse cells of %d texels (docs/methods/p1.md, Far "
                  "field)",
                  p.far_field->beyond, p.far_field->cell);
    out.attributes.emplace_back("hfbake:p1:far_field", b);
    // Certified per bake: every horizon's tangent (so its sine, and its elevation in radians) is at least
    // the exact one's and exceeds it by at most this.
    std::snprintf(b, sizeof b, "%.6g", r.far_field_bound.value_or(0.0));
    out.attributes.emplace_back("hfbake:p1:far_field_bound", b);
  }
  return out;
}

}  // namespace

void p1_sums_to_layers(P1Sums& s, LayerSet& out) {
  const std::size_t N = std::size_t(out.width) * out.height;
  auto put = [&](const char* name, std::vector<float>& v) {
    if (v.empty()) return;
    std::vector<std::string> channels = indexed_channels(int(v.size() / N));  // before the move
    out.adopt(name, std::move(channels), std::move(v));
  };
  put("ao", s.ao), put("vsky", s.vsky), put("rgb", s.rgb), put("bent", s.bent);
  put("fao", s.fao), put("fdr", s.fdr), put("fdg", s.fdg), put("fdb", s.fdb);
}

void p1_sums_from_layers(LayerSet& sums, const P1SumsShape& shape, P1Sums& s) {
  auto take = [&](const char* name, std::size_t per_texel, std::vector<float>& v) {
    if (per_texel > 0) v = take_block_layer(sums, name, per_texel);
  };
  take("ao", shape.ao, s.ao), take("vsky", shape.vsky, s.vsky), take("rgb", shape.rgb, s.rgb);
  take("bent", shape.bent, s.bent), take("fao", shape.fao, s.fao);
  take("fdr", shape.fd, s.fdr), take("fdg", shape.fd, s.fdg), take("fdb", shape.fd, s.fdb);
}

LayerSet bake_p1(const Scene& scene, const MethodConfig& config, const RunControl& rc) {
  return p1_layers(compute_p1(scene, config.get<P1Params>(), rc), config.get<P1Params>(), config.layers);
}

// Farm blocks: the raw sums as layers named after P1Sums' members; each block's horizons as
// "horizon@<k_begin>" ("horizon_distance@<k_begin>"), kept apart and placed by p1_finish_blocks; with a far
// field, the block's largest slack as "far_slack@<k_begin>" (every texel the same value), of which
// p1_finish_blocks takes the largest, as compute_p1 does.
LayerSet p1_bake_block(const Scene& scene, const MethodConfig& config, int block, const RunControl& rc) {
  const P1Params& p = config.get<P1Params>();
  const int K = p.directions;
  P1Sums s =
      p1_direction_sums(scene, p, direction_block_begin(block, K), direction_block_begin(block + 1, K), rc);
  LayerSet out;
  out.width = scene.field.width, out.height = scene.field.height;
  p1_sums_to_layers(s, out);
  std::string at = "@";  // appended, not "@" + ...: GCC 12's false -Wrestrict on that form
  at += std::to_string(s.k_begin);
  const std::vector<std::string> block_channels = indexed_channels(s.k_end - s.k_begin);
  if (!s.horizon.empty()) out.adopt("horizon" + at, block_channels, std::move(s.horizon));
  if (!s.horizon_distance.empty())
    out.adopt("horizon_distance" + at, block_channels, std::move(s.horizon_distance));
  if (p.far_field)
    out.adopt("far_slack" + at, mono_channels(),
              std::vector<float>(scene.field.texel_count(), float(s.far_slack)));
  return out;
}

LayerSet p1_finish_blocks(const Scene& scene, const MethodConfig& config, LayerSet&& sums,
                          const RunControl& rc) {
  const P1Params& p = config.get<P1Params>();
  const int K = p.directions;
  const std::size_t N = scene.field.texel_count();
  P1Sums s;
  s.k_begin = 0, s.k_end = K;
  p1_sums_from_layers(sums, p1_sums_shape(scene, p), s);
  for (const Layer& l : sums.layers)
    if (l.name.rfind("far_slack@", 0) == 0) {
      if (l.data.size() != N)
        throw InputError("", "",
                         "the direction blocks' far_slack layers are not of this field: bake them again");
      s.far_slack = std::max(s.far_slack, double(l.data[0]));
    }
  // The blocks' horizons into [texel * K + k].
  auto place = [&](const std::string& name, std::vector<float>& all) {
    all.assign(N * std::size_t(K), 0.0f);
    place_block_layers(sums, name, K, [&](const Layer& l, int k0) {
      const int n = l.channel_count();
      for (std::size_t t = 0; t < N; ++t)
        for (int c = 0; c < n; ++c) all[t * K + std::size_t(k0 + c)] = l.data[t * std::size_t(n) + c];
    });
  };
  if (p.horizon) place("horizon", s.horizon);
  if (p.horizon_distance) place("horizon_distance", s.horizon_distance);
  sums = LayerSet();
  return p1_layers(p1_finish(scene, p, std::move(s), rc), p, config.layers);
}

namespace {

// The lane search (lane_horizons.hpp; a repeat field's through its tiling, lane_tiles) per azimuth, the
// azimuths of one lane layout's axis at a time (x-major ones first), so one layout is held at a time.
// floor: raised to the far field's floor (far_floor.hpp), the largest slack left returned.
double lane_horizons_at(const HeightField& f, const P1Params& p, const std::vector<double>& azimuths,
                        const RunControl& rc, const HorizonVisitor& visit, double curvature,
                        const p1::FloorGrid* floor) {
  SweepSpec probe;
  probe.azimuths = azimuths;
  std::vector<int> ks;
  for (std::size_t a = 0; a < azimuths.size(); ++a) ks.push_back(int(a));
  int done = 0;
  p1::DirectionFloor df;
  std::vector<double> row_slack(floor ? std::size_t(f.height) : 0, 0.0);  // one slot a row: any thread count
  p1::lane_directions(
      f, probe, ks, curvature, float(p.horizon_tolerance), /*casters=*/false, rc,
      [&](const SweepDirection& sd, const p1::LaneDirection&, const float* slope, const std::int32_t*) {
        if (floor) p1::direction_floor(*floor, f.width, f.height, azimuths[std::size_t(sd.k)], df);
        tbb::parallel_for(0, f.height, [&](int j) {
          for (int i = 0; i < f.width; ++i) {
            const std::size_t t = f.index(i, j);
            float m = slope[t];
            if (floor) m = p1::raise_to_floor(*floor, df, i, j, f.z[t], m, row_slack[std::size_t(j)]);
            visit(sd.k, i, j, p1::fast_atan(m));
          }
        });
        rc.report(double(++done) / double(azimuths.size()));
      },
      nullptr, p.wrap_periods);
  return row_slack.empty() ? 0.0 : *std::max_element(row_slack.begin(), row_slack.end());
}

}  // namespace

void p1_horizons_at(const HeightField& f, const P1Params& p, const std::vector<double>& azimuths,
                    const RunControl& rc, const HorizonVisitor& visit, double curvature,
                    const p1::FloorGrid* floor, double* slack) {
  if (slack) *slack = 0;
  if (azimuths.empty()) return;
  if (p1::lane_tiles(f.width, f.height, f.wrap, p.wrap_periods)) {
    const double s = lane_horizons_at(f, p, azimuths, rc, visit, curvature, floor);
    if (slack) *slack = s;
    return;
  }
  if (floor) throw std::logic_error("p1_horizons_at: a far field on a repeat field");
  SweepSpec spec;
  spec.channels = p1::FarHorizonWorker::channels();
  spec.sampling.heights = false;  // the far-field worker builds its own profiles
  spec.wrap_periods = p.wrap_periods;
  spec.azimuths = azimuths;
  std::vector<std::vector<p1::NearCrossing>> near;
  near.reserve(azimuths.size());
  for (std::size_t a = 0; a < azimuths.size(); ++a) {
    const SweepDirection d = plan_direction(f, spec, int(a));
    near.push_back(p1::near_field_stencil(d.dx, d.dy, p1::near_radius_of(d, p.near_radius), f.texel_size));
  }
  auto make_worker = [&] {
    p1::FarHorizonWorker w;
    w.far_radius = p.near_radius * f.texel_size;
    w.field = &f;
    w.tolerance = p.horizon_tolerance;
    w.beat_near = true;
    return w;
  };
  sweep_lines(f, spec, rc, make_worker, [&](int a, int i, int j, const TexelTaps& t) {
    int which;
    const float near_e = p1::fast_atan(p1::near_slope(f, near[std::size_t(a)], i, j, &which));
    visit(a, i, j, std::max(near_e, p1::caster_elevation(t.strip[0], t.strip[1])));
  });
}

MethodInfo p1_method() {
  MethodInfo m;
  m.name = "p1";
  m.reads_normals = false;  // recomputed per tile from the heights (normal_at)
  m.reads_albedo = false;
  // The lane search drops each crossing by the curvature (clamp fields; a repeating field has no
  // curvature: cli/scene_loader job_curvature). Directional lights' shadows are flat (docs/gis.md).
  m.applies_curvature = true;
  m.rectangular_texels = true;  // the lane search; the reader refuses the rest
  m.summary = "exact horizons of every texel's own ray in K azimuths; ao, vsky, direct light from them";
  m.read = [](Params& in, const MethodContext& c) {
    const P1Params p = read_p1_params(in, c.field);
    // Rectangular texels: the lane search only (clamp fields), without the directional lights' sweeps.
    if (!c.field.square_texels() && c.field.wrap == Wrap::repeat)
      in.fail("method", "bakes rectangular texels (a geographic raster) on clamp fields only");
    if (!c.field.square_texels() && p.direct && p.lights)
      in.fail("lights",
              "is on (the default) with the direct layer, and p1's directional lights need square texels; "
              "this field's are rectangles (a geographic raster): set \"lights\": false or leave \"direct\" "
              "out of the layers");
    return method_config(p, p.directions);
  };
  m.bake = bake_p1;
  // Beyond its layers (the accumulators become the layers): see p1_working_bytes.
  m.memory_knob = "its layers (horizon and horizon_distance: 4 bytes a texel per direction each)";
  m.working_bytes = [](const MethodConfig& config, const MethodContext& c) {
    return p1_working_bytes(c.field, config.get<P1Params>(), c.uniform_environment);
  };
  m.division = WorkDivision::directions;
  // A far field bounds the heights p1 reads exactly: a tile with a halo of `beyond` and the raster's coarse
  // copy bakes the whole bake's texels (far_floor.hpp).
  m.reach = [](const MethodConfig& config) {
    return far_field_reach(config.get<P1Params>().far_field, std::numeric_limits<double>::infinity());
  };
  m.far_cell = [](const MethodConfig& config) { return far_field_cell(config.get<P1Params>().far_field); };
  m.bake_block = p1_bake_block;
  m.finish_blocks = p1_finish_blocks;
  m.division_note = "partial sums over disjoint direction sets (each direction's sweep is independent)";
  return m;
}

}  // namespace hfbake
