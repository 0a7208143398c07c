#include "methods/ao/hbao.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "core/azimuth.hpp"
#include "core/direction_blocks.hpp"
#include "core/error.hpp"
#include "methods/ao/bake_ao.hpp"
#include "methods/ao/slice_integral.hpp"
#include "methods/ao/triangle_profile.hpp"

namespace hfbake {

std::vector<MarchDirection> uniform_directions(int count) {
  std::vector<MarchDirection> d(count);
  for (int k = 0; k < count; ++k) {
    const double phi = azimuth(k, count);
    d[k] = {std::cos(phi), std::sin(phi), 1.0};
  }
  return d;
}

double default_reach(const FieldShape& field, const Falloff& f) {
  const double whole = field.wrap == Wrap::repeat
                           ? std::max(field.width, field.height) * field.texel_size
                           : std::hypot(field.width - 1, field.height - 1) * field.texel_size;
  const double support = f.support(1e-4);
  return std::isfinite(support) ? support : whole;
}

HbaoSums hbao_texel_sums(const HeightField& field, Vec3 n, int i, int j, const HbaoSettings& s, int d0,
                         int d1) {
  const double z0 = field.z[field.index(i, j)];
  const double ts = field.texel_size;
  const bool clamp = field.wrap == Wrap::clamp;
  const double xmax = field.width - 1, ymax = field.height - 1;
  const bool segment = s.estimator == HorizonEstimator::segment;

  double occluded = 0;
  Vec3 bent{0, 0, 0};
  for (int di = d0; di < d1; ++di) {
    const MarchDirection& d = s.directions[std::size_t(di)];
    const SliceFrame frame = slice_frame(n.x * d.dx + n.y * d.dy, n.z);
    const double step_w = d.step > 0 ? d.step * ts : s.step;  // world units per step
    const double step_t = step_w / ts;                        // texels per step
    const int steps = std::max(1, int(std::floor(s.reach / step_w + 1e-9)));
    double max_slope = -std::numeric_limits<double>::infinity();
    double max_elev = -kPi / 2;
    double occl = 0;
    SliceVec dir = s.bent ? open_direction(frame, frame.tangent, kPi / 2) : SliceVec{};
    const double sin_t = s.real_tangent ? std::sin(frame.tangent) : s.sin_tangent;
    double largest = sin_t;  // P3: "no occluder"
    // With falloff none the bands telescope: only the final horizon matters.
    const bool telescopes = s.falloff.kind == FalloffKind::none;
    SliceVec prev{0, 0};  // the previous sample (segment estimator), the receiver first
    // One sample at world distance x, height dz above the receiver.
    auto sample = [&](double x, double dz) {
      const double slope = dz / x;
      if (s.estimator == HorizonEstimator::largest_occluder && (!s.visible_only || slope >= max_slope)) {
        const double len = std::hypot(x, dz), sin_h = dz / len;
        largest = std::max(largest, sin_t + std::max(0.0, sin_h - sin_t) * s.falloff(len));
      }
      if (slope > max_slope) {
        max_slope = slope;
        if (!telescopes) {
          const double e = std::atan(slope);
          if (segment) {
            occl += segment_band_occlusion(s.falloff, s.weighting, frame, max_elev, e, prev, {x, dz});
            if (s.bent) {
              const SliceVec b = segment_band_direction(s.falloff, frame, max_elev, e, prev, {x, dz});
              dir.h -= b.h, dir.v -= b.v;
            }
          } else {
            occl += band_occlusion(s.falloff, s.weighting, frame, max_elev, e, x);
            if (s.bent) {
              const SliceVec b = band_direction(s.falloff, frame, max_elev, e, x);
              dir.h -= b.h, dir.v -= b.v;
            }
          }
          max_elev = e;
        }
      }
      prev = {x, dz};
    };
    if (s.surface == MarchSurface::triangles) {
      const double t_end = profile_end(field, i, j, d.dx, d.dy, s.reach / ts);  // clamp: the border
      if (t_end > 1e-9)
        triangle_profile(field, i, j, d.dx, d.dy, t_end, [&](double t, double z) { sample(t * ts, z - z0); });
    } else {
      // Clamp fields end at their border: the last step inside (so the loop needs no bounds test).
      int last = steps;
      if (clamp) {
        auto limit = [&](double start, double dv, double hi) {
          if (std::abs(dv) < 1e-12) return steps;
          const double t = dv > 0 ? (hi - start) / (dv * step_t) : -start / (dv * step_t);
          return int(std::min<double>(steps, std::floor(t + 1e-9)));
        };
        last = std::min(limit(i, d.dx, xmax), limit(j, d.dy, ymax));
      }
      for (int m = 1; m <= last; ++m) {
        const double px = i + m * step_t * d.dx, py = j + m * step_t * d.dy;
        sample(m * step_w, double(field.bilinear(px, py)) - z0);
      }
    }
    if (telescopes && max_slope > -std::numeric_limits<double>::infinity()) {
      const double e = std::atan(max_slope);
      occl = band_occlusion(s.falloff, s.weighting, frame, -kPi / 2, e, 1.0);
      if (s.bent) {
        const SliceVec b = band_direction(s.falloff, frame, -kPi / 2, e, 1.0);
        dir.h -= b.h, dir.v -= b.v;
      }
    }
    if (s.estimator == HorizonEstimator::largest_occluder)
      occluded += d.weight * largest;
    else
      occluded += d.weight * (s.weighting == Weighting::cosine ? 2 * occl : occl);
    bent += d.weight * Vec3{dir.h * d.dx, dir.h * d.dy, dir.v};
  }
  return {split_double(occluded), {split_double(bent.x), split_double(bent.y), split_double(bent.z)}};
}

void hbao_add_sums(HbaoSums& total, const HbaoSums& block) {
  add_split(total.occluded, block.occluded);
  for (int c = 0; c < 3; ++c) add_split(total.bent[c], block.bent[c]);
}

double hbao_weight_sum(const HbaoSettings& s) {
  double wsum = 0;
  for (const MarchDirection& d : s.directions) wsum += d.weight;
  return wsum;
}

HorizonTexel hbao_finish(const HbaoSums& sums, double weight_sum, Vec3 n, const HbaoSettings&) {
  HorizonTexel t;
  // The occluded share lies in [0, 1]; a sum over few directions (K = 1 or 2: one ray, or two opposite
  // ones, stand for every azimuth) can estimate it outside on steep terrain, where one direction holds
  // most of the normal's lobe. Such an estimate is taken to the nearer end.
  t.occluded = std::clamp(join_double(sums.occluded) / weight_sum, 0.0, 1.0);
  const Vec3 bent{join_double(sums.bent[0]), join_double(sums.bent[1]), join_double(sums.bent[2])};
  t.bent_normal = length(bent) > 1e-12 ? normalize(bent) : n;
  return t;
}

HorizonTexel hbao_texel(const HeightField& field, Vec3 n, int i, int j, const HbaoSettings& s) {
  // Direction blocks (core/direction_blocks.hpp), each summed from zero, added in order: what `hfbake
  // merge` does with the blocks of other machines.
  const int K = int(s.directions.size()), B = direction_block_count(K);
  HbaoSums total = hbao_texel_sums(field, n, i, j, s, 0, direction_block_begin(1, K));
  for (int b = 1; b < B; ++b)
    hbao_add_sums(total, hbao_texel_sums(field, n, i, j, s, direction_block_begin(b, K),
                                         direction_block_begin(b + 1, K)));
  return hbao_finish(total, hbao_weight_sum(s), n, s);
}

void hbao_field(const HeightField& field, const std::vector<Vec3f>& normals, const HbaoSettings& s,
                const RunControl& rc, float* obscurance, float* bent_xyz) {
  std::atomic<int> rows_done{0};
  HbaoSettings st = s;
  st.bent = bent_xyz != nullptr;
  tbb::parallel_for(0, field.height, [&](int j) {
    rc.check();
    for (int i = 0; i < field.width; ++i) {
      const std::size_t idx = field.index(i, j);
      const Vec3 n = normals.empty() ? normal_at(field, i, j).d() : normals[idx].d();
      const HorizonTexel t = hbao_texel(field, n, i, j, st);
      if (obscurance) obscurance[idx] = float(1.0 - t.occluded);
      if (bent_xyz) {
        const Vec3f b = Vec3f::from(t.bent_normal);
        bent_xyz[3 * idx] = b.x, bent_xyz[3 * idx + 1] = b.y, bent_xyz[3 * idx + 2] = b.z;
      }
    }
    rc.report(double(++rows_done) / field.height);
  });
}

void hbao_field_block(const HeightField& field, const HbaoSettings& s, int block, const RunControl& rc,
                      float* occluded, float* bent_xyz) {
  std::atomic<int> rows_done{0};
  HbaoSettings st = s;
  st.bent = bent_xyz != nullptr;
  const int K = int(s.directions.size());
  const int d0 = direction_block_begin(block, K), d1 = direction_block_begin(block + 1, K);
  tbb::parallel_for(0, field.height, [&](int j) {
    rc.check();
    for (int i = 0; i < field.width; ++i) {
      const std::size_t idx = field.index(i, j);
      const HbaoSums t = hbao_texel_sums(field, normal_at(field, i, j).d(), i, j, st, d0, d1);
      occluded[2 * idx] = t.occluded.hi, occluded[2 * idx + 1] = t.occluded.lo;
      if (bent_xyz)
        for (int c = 0; c < 3; ++c)
          bent_xyz[6 * idx + 2 * c] = t.bent[c].hi, bent_xyz[6 * idx + 2 * c + 1] = t.bent[c].lo;
    }
    rc.report(double(++rows_done) / field.height);
  });
}

void hbao_field_finish(const HeightField& field, const HbaoSettings& s, const float* occluded,
                       const float* bent_sums, float* obscurance, float* bent_xyz) {
  const double wsum = hbao_weight_sum(s);
  tbb::parallel_for(0, field.height, [&](int j) {
    for (int i = 0; i < field.width; ++i) {
      const std::size_t idx = field.index(i, j);
      HbaoSums sums;
      sums.occluded = {occluded[2 * idx], occluded[2 * idx + 1]};
      if (bent_sums)
        for (int c = 0; c < 3; ++c)
          sums.bent[c] = {bent_sums[6 * idx + 2 * c], bent_sums[6 * idx + 2 * c + 1]};
      const HorizonTexel t = hbao_finish(sums, wsum, normal_at(field, i, j).d(), s);
      if (obscurance) obscurance[idx] = float(1.0 - t.occluded);
      if (bent_xyz) {
        const Vec3f b = Vec3f::from(t.bent_normal);
        bent_xyz[3 * idx] = b.x, bent_xyz[3 * idx + 1] = b.y, bent_xyz[3 * idx + 2] = b.z;
      }
    }
  });
}

HbaoSettings read_hbao_settings(Params& in, const FieldShape& field) {
  HbaoSettings s;
  s.falloff = read_falloff(in);
  s.weighting = read_weighting(in, true);
  s.directions = uniform_directions(in.integer("directions", 16, 1, 4096));
  // The reference's triangulated surface by default (on rough ground the bilinear march is several times
  // further from the reference: docs/methods/obscurance.md); a march given a step is the stepped bilinear
  // one.
  const bool stepped = in.has("step") || in.has("steps");
  const bool triangles =
      in.choice("surface", stepped ? "bilinear" : "triangles", {"bilinear", "triangles"}) == "triangles";
  s.surface = triangles ? MarchSurface::triangles : MarchSurface::bilinear;
  // The triangulated surface's exact slice integral needs the segment estimator: its default there.
  const std::string estimator =
      in.choice("estimator", triangles ? "segment" : "slab", {"slab", "segment", "largest_occluder"});
  s.estimator = estimator == "slab"      ? HorizonEstimator::slab
                : estimator == "segment" ? HorizonEstimator::segment
                                         : HorizonEstimator::largest_occluder;
  const bool largest = s.estimator == HorizonEstimator::largest_occluder;
  if (in.has("tangent")) {
    const std::optional<double> t = in.word_or_number(
        "tangent", "normal", -1, 0, "must be \"normal\" or a number in [-1, 0] (sin of the fixed tangent)");
    s.real_tangent = !t;
    if (t) s.sin_tangent = *t;
    if (!largest) in.fail("tangent", "applies only to estimator \"largest_occluder\"");
  }
  if (largest && s.real_tangent) in.resolve("tangent", "normal");
  if (largest && !s.real_tangent) in.resolve("tangent", s.sin_tangent);
  if (in.has("occluders") && !largest) in.fail("occluders", "applies only to estimator \"largest_occluder\"");
  const std::string occluders = in.choice("occluders", "visible", {"visible", "all"});
  s.visible_only = occluders == "visible";
  s.reach = in.number("max_distance", default_reach(field, s.falloff), 1e-9, 1e12);
  if (triangles && (in.has("step") || in.has("steps")))
    in.fail("surface", "\"triangles\" visits every vertex of the profile: no \"step\" or \"steps\"");
  s.step = in.number("step", 1.0, 1e-3, 1e6) * field.texel_size;
  if (in.has("steps")) {
    if (in.has("step")) in.fail("steps", "give \"step\" or \"steps\", not both");
    s.step = s.reach / in.integer("steps", 1, 1, 1000000);
  }
  if (s.reach / s.step > 1e7) in.fail("max_distance", "more than 1e7 steps per direction");
  // A repeat field's marches run the whole distance through its tiling (a clamp field's end at its border):
  // every texel's, so the steps a direction takes are bounded per texel, as hsao's radius is.
  // (The distance defaults to a multiple of the falloff's radius: then the radius is what was given.)
  if (field.wrap == Wrap::repeat && s.reach > 1e6 * field.texel_size)
    in.fail(
        in.has("max_distance") ? "max_distance" : "radius",
        "on a repeat field each march crosses the tiling for the whole distance (max_distance, by default "
        "a multiple of the radius): at most 1e6 texels");
  const bool ao_ok = s.falloff.kind == FalloffKind::none && s.weighting == Weighting::cosine && !largest;
  std::vector<std::string> defaults = {"obscurance", "bent_normal"};
  if (ao_ok) defaults.push_back("ao");
  const std::vector<std::string> layers = in.layers({"obscurance", "bent_normal", "ao"}, defaults);
  if (wants(layers, "ao") && !ao_ok)
    in.fail("layers",
            "\"ao\" needs falloff \"none\", weighting \"cosine\" and estimator \"slab\" or \"segment\" (use "
            "\"obscurance\")");
  return s;
}

namespace {

// The layers of a finished hbao (bake and the farm's merge alike), tagged with how it marched.
LayerSet hbao_layers(const HeightField& field, const HbaoSettings& s, const std::vector<std::string>& layers,
                     std::vector<float>&& obsc, std::vector<float>&& bent) {
  LayerSet out = obscurance_layers_xyz(field.width, field.height, layers, std::move(obsc), std::move(bent));
  if (s.surface == MarchSurface::triangles)
    out.attributes.emplace_back("hfbake:hbao:surface", "triangles");
  else
    out.attributes.emplace_back("hfbake:hbao:steps_per_direction", std::to_string(int(s.reach / s.step)));
  return out;
}

}  // namespace

LayerSet bake_hbao(const Scene& scene, const MethodConfig& config, const RunControl& rc) {
  const HeightField& field = scene.field;
  const HbaoSettings& s = config.get<HbaoSettings>();
  const std::vector<std::string>& layers = config.layers;
  std::vector<float> obsc(field.texel_count());
  std::vector<float> bent(wants(layers, "bent_normal") ? 3 * field.texel_count() : 0);  // [3 * texel + c]
  hbao_field(field, scene.normals, s, rc, obsc.data(), bent.empty() ? nullptr : bent.data());
  return hbao_layers(field, s, layers, std::move(obsc), std::move(bent));
}

namespace {

// Farm blocks: "occluded#2f" and, with bent_normal, "bent#2f" (the raw sums: HbaoSums, as hi/lo pairs).
LayerSet hbao_bake_block(const Scene& scene, const MethodConfig& config, int block, const RunControl& rc) {
  const HeightField& field = scene.field;
  const HbaoSettings& s = config.get<HbaoSettings>();
  const std::vector<std::string>& layers = config.layers;
  LayerSet out;
  out.width = field.width, out.height = field.height;
  float* occluded = out.add("occluded#2f", {"hi", "lo"}).data.data();
  float* bent = wants(layers, "bent_normal")
                    ? out.add("bent#2f", {"X.hi", "X.lo", "Y.hi", "Y.lo", "Z.hi", "Z.lo"}).data.data()
                    : nullptr;
  hbao_field_block(field, s, block, rc, occluded, bent);
  return out;
}

LayerSet hbao_finish_blocks(const Scene& scene, const MethodConfig& config, LayerSet&& sums,
                            const RunControl&) {
  const HeightField& field = scene.field;
  const HbaoSettings& s = config.get<HbaoSettings>();
  const std::vector<std::string>& layers = config.layers;
  std::vector<float> obsc(field.texel_count());
  std::vector<float> bent(wants(layers, "bent_normal") ? 3 * field.texel_count() : 0);
  const std::vector<float> occluded = take_block_layer(sums, "occluded#2f", 2);
  const std::vector<float> bs = bent.empty() ? std::vector<float>() : take_block_layer(sums, "bent#2f", 6);
  hbao_field_finish(field, s, occluded.data(), bs.empty() ? nullptr : bs.data(), obsc.data(),
                    bent.empty() ? nullptr : bent.data());
  sums = LayerSet();
  return hbao_layers(field, s, layers, std::move(obsc), std::move(bent));
}

}  // namespace

MethodInfo hbao_method() {
  MethodInfo m;
  m.name = "hbao";
  m.reads_normals = false;  // normal_at per texel
  m.reads_albedo = false;
  m.summary = "brute-force horizon march per texel and direction (the obscurance family's baseline)";
  m.read = [](Params& in, const MethodContext& c) {
    const HbaoSettings s = read_hbao_settings(in, c.field);
    MethodConfig config = method_config(s, int(s.directions.size()));
    config.obscurance = written_falloff(in, s.falloff);
    config.cosine_weighted = s.weighting == Weighting::cosine;
    return config;
  };
  m.bake = bake_hbao;
  // Nothing beyond its layers (the bent normals are written interleaved, as their layer).
  m.memory_knob = "its layers (bent_normal: 12 bytes a texel)";
  m.working_bytes = [](const MethodConfig&, const MethodContext&) { return 0.0; };

  m.division = WorkDivision::directions;
  m.reach = [](const MethodConfig& c) { return c.get<HbaoSettings>().reach; };
  m.division_note = "partial sums over disjoint direction sets (texel tiles would need a halo of the reach)";
  m.bake_block = hbao_bake_block;
  m.finish_blocks = hbao_finish_blocks;
  return m;
}

}  // namespace hfbake
