#include "methods/ao/hsao.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/direction_blocks.hpp"
#include "core/error.hpp"
#include "methods/ao/bake_ao.hpp"
#include "methods/ao/obscurance_params.hpp"
#include "methods/ao/slice_integral.hpp"
#include "methods/ao/triangle_profile.hpp"

namespace hfbake {
namespace {

// The height-field surface seen as a depth buffer: is the world point below it, and the surface height there.
// Clamp fields end at their border (nothing beyond: `inside` false); repeat fields tile.
struct DepthSurface {
  const HeightField& f;
  double inv_ts;
  bool inside(double x, double y) const {
    if (f.wrap == Wrap::repeat) return true;
    const double tx = x * inv_ts, ty = y * inv_ts;
    return tx >= -1e-9 && ty >= -1e-9 && tx <= f.width - 1 + 1e-9 && ty <= f.height - 1 + 1e-9;
  }
  double height(double x, double y) const { return f.bilinear(x * inv_ts, y * inv_ts); }
};

}  // namespace

HsaoSums hsao_texel_sums(const HeightField& field, Vec3 n, int i, int j, const HsaoSettings& s, int d0,
                         int d1) {
  const DepthSurface surf{field, 1.0 / field.texel_size};
  const double R = s.falloff.radius, step = R / s.steps;
  // Lift the receiver by a tiny offset along n so the flat ground around it does not count as "below"
  // (the offline replacement of the paper's staircase offset).
  const Vec3 p = field.position(i, j) + n * (1e-4 * field.texel_size);
  // Tangent frame: t1 = +x projected onto the tangent plane (n = up: t1 = +x, t2 = +y).
  Vec3 t1 = Vec3{1, 0, 0} - n * n.x;
  if (length(t1) < 1e-6) t1 = Vec3{0, 1, 0} - n * n.y;
  t1 = normalize(t1);
  const Vec3 t2 = cross(n, t1);
  const SliceFrame up = slice_frame(0, 1);  // the (n, T) plane with n as "up"

  HsaoTexel out;
  Vec3 bent{0, 0, 0};
  const bool triangles = s.surface == HsaoSurface::triangles;
  const double ts = field.texel_size, z0 = field.z[field.index(i, j)];
  for (int d = d0; d < d1; ++d) {
    const double theta = 2 * kPi * d / s.directions;
    const Vec3 T = t1 * std::cos(theta) + t2 * std::sin(theta);
    // Horizon ray.
    Vec3 h = T;
    double elev = 0, occl = 0;  // current horizon elevation above the tangent plane; 2 * band integrals
    SliceVec dir = open_direction(up, 0, kPi / 2);
    // The march point q (on ray h) is below the surface, whose height there is hq: deflect the ray towards
    // the surface point above q (or the highest point of its column within R). True when it deflected.
    auto deflect = [&](const Vec3& q, double hq) {
      Vec3 v = Vec3{q.x, q.y, hq} - p;
      if (!(length(v) < R)) {
        // The surface point I is beyond R, but the terrain is a solid: the column between Q and I is
        // occluder too, and its highest point within R lies on the sphere of radius R (refinement of the
        // paper's rule "deflect only if |I - P| < R", which stalls on a wall taller than R allows).
        const Vec3 qv = q - p;
        const double z2 = R * R - qv.x * qv.x - qv.y * qv.y;
        if (!(dot(qv, qv) < R * R) || !(z2 > 0)) return false;
        v = Vec3{qv.x, qv.y, std::sqrt(z2) * (1 - 1e-12)};
      }
      const double along = dot(v, T), up_n = dot(v, n);
      if (!(along > 0)) return false;
      const double e = std::atan2(up_n, along);
      if (!(e > elev)) return false;
      occl += 2 * band_occlusion(s.falloff, Weighting::cosine, up, elev, e, along);
      const SliceVec b = band_direction(s.falloff, up, elev, e, along);
      dir.h -= b.h, dir.v -= b.v;
      elev = e;
      h = normalize(T * along + n * up_n);
      return true;
    };
    if (triangles) {
      // Every vertex of the triangulated surface under the ray's ground track (triangle_profile.hpp): the
      // surface and the ray are both linear between them, so the ray is below the surface somewhere iff it
      // is at a vertex. After a deflection the new ray goes on from the same distance from p.
      double searched = 0;                            // distance from p along the rays already searched
      for (int turns = 0; turns < 100000; ++turns) {  // each turn raises elev (bounded: a guard only)
        const double ground = std::hypot(h.x, h.y);   // horizontal run per unit of ray
        if (!(ground > 1e-9)) break;
        const double gx = h.x / ground, gy = h.y / ground;
        const double t_begin = searched * ground / ts;
        const double t_end = profile_end(field, i, j, gx, gy, R * ground / ts);
        if (!(t_end > t_begin)) break;
        bool deflected = false;
        triangle_profile_span(field, i, j, gx, gy, t_begin, t_end, [&](double t, double z) {
          const double run = t * ts, along_ray = run / ground;
          const Vec3 q = p + h * along_ray;
          if (!(q.z < z) || !deflect(q, z)) return true;
          searched = along_ray;
          deflected = true;
          return false;
        });
        if (!deflected) break;
      }
    } else {
      for (int k = 1; k <= s.steps; ++k) {
        const Vec3 q = p + h * (k * step);
        if (!surf.inside(q.x, q.y)) break;
        const double hq = surf.height(q.x, q.y);
        if (!(q.z < hq)) continue;
        deflect(q, hq);
      }
    }
    out.horizon_occlusion += occl / s.directions;
    bent += T * dir.h + n * dir.v;
    // Normal rays above the horizon, equal cosine measure (1 - H^2) / N_n each.
    const double H2 = std::sin(elev) * std::sin(elev);
    for (int r = 0; r < s.normal_rays; ++r) {
      const double z2 = H2 + (r + 0.5) * (1 - H2) / s.normal_rays;
      const Vec3 ray = T * std::sqrt(std::max(0.0, 1 - z2)) + n * std::sqrt(z2);
      if (triangles) {
        // The first vertex above the ray; the hit lies on the straight piece before it.
        const double ground = std::hypot(ray.x, ray.y);
        if (!(ground > 1e-9)) continue;
        const double gx = ray.x / ground, gy = ray.y / ground;
        const double t_end = profile_end(field, i, j, gx, gy, R * ground / ts);
        if (!(t_end > 0)) continue;
        double t0 = 0, gap0 = z0 - p.z;  // the previous vertex and the surface minus the ray there
        triangle_profile_span(field, i, j, gx, gy, 0.0, t_end, [&](double t, double z) {
          const double gap = z - (p.z + ray.z * (t * ts / ground));
          if (gap > 0) {
            const double th = t0 + (t - t0) * (-gap0 / (gap - gap0));
            out.normal_occlusion += (1 - H2) * s.falloff(th * ts / ground) / (s.normal_rays * s.directions);
            return false;
          }
          t0 = t, gap0 = gap;
          return true;
        });
        continue;
      }
      for (int k = 1; k <= s.steps; ++k) {
        const Vec3 q = p + ray * (k * step);
        if (!surf.inside(q.x, q.y)) break;
        if (q.z < surf.height(q.x, q.y)) {
          out.normal_occlusion += (1 - H2) * s.falloff(k * step) / (s.normal_rays * s.directions);
          break;
        }
      }
    }
  }
  return {split_double(out.horizon_occlusion),
          split_double(out.normal_occlusion),
          {split_double(bent.x), split_double(bent.y), split_double(bent.z)}};
}

void hsao_add_sums(HsaoSums& total, const HsaoSums& block) {
  add_split(total.horizon, block.horizon);
  add_split(total.normal, block.normal);
  for (int c = 0; c < 3; ++c) add_split(total.bent[c], block.bent[c]);
}

HsaoTexel hsao_finish(const HsaoSums& sums, Vec3 n) {
  HsaoTexel t;
  t.horizon_occlusion = join_double(sums.horizon);
  t.normal_occlusion = join_double(sums.normal);
  const Vec3 bent{join_double(sums.bent[0]), join_double(sums.bent[1]), join_double(sums.bent[2])};
  t.bent_normal = length(bent) > 1e-12 ? normalize(bent) : n;
  return t;
}

HsaoTexel hsao_texel(const HeightField& field, Vec3 n, int i, int j, const HsaoSettings& s) {
  // Direction blocks (core/direction_blocks.hpp), each summed from zero, added in order: what `hfbake
  // merge` does with the blocks of other machines.
  const int K = s.directions, B = direction_block_count(K);
  HsaoSums total = hsao_texel_sums(field, n, i, j, s, 0, direction_block_begin(1, K));
  for (int b = 1; b < B; ++b)
    hsao_add_sums(total, hsao_texel_sums(field, n, i, j, s, direction_block_begin(b, K),
                                         direction_block_begin(b + 1, K)));
  return hsao_finish(total, n);
}

namespace {

// The texel's obscurance and bent normal into the layers' arrays (either may be null).
void hsao_store(const HsaoTexel& t, std::size_t idx, float* obscurance, float* bent_xyz) {
  if (obscurance) obscurance[idx] = float(std::clamp(1.0 - t.occluded(), 0.0, 1.0));
  if (bent_xyz) {
    const Vec3f b = Vec3f::from(t.bent_normal);
    bent_xyz[3 * idx] = b.x, bent_xyz[3 * idx + 1] = b.y, bent_xyz[3 * idx + 2] = b.z;
  }
}

}  // namespace

void hsao_field(const HeightField& field, const std::vector<Vec3f>& normals, const HsaoSettings& s,
                const RunControl& rc, float* obscurance, float* bent_xyz) {
  std::atomic<int> rows_done{0};
  tbb::parallel_for(0, field.height, [&](int j) {
    for (int i = 0; i < field.width; ++i) {
      rc.check();  // per texel: a texel's rays may cross a long radius (a repeat field's tiling)
      const std::size_t idx = field.index(i, j);
      const Vec3 n = normals.empty() ? normal_at(field, i, j).d() : normals[idx].d();
      hsao_store(hsao_texel(field, n, i, j, s), idx, obscurance, bent_xyz);
    }
    rc.report(double(++rows_done) / field.height);
  });
}

HsaoSettings read_hsao_settings(Params& in, const FieldShape& field) {
  if (!in.has("radius")) in.fail("radius", "hsao needs a radius of influence (world units)");
  HsaoSettings s;
  s.falloff = read_falloff(in);
  if (s.falloff.kind != FalloffKind::step && s.falloff.kind != FalloffKind::linear &&
      s.falloff.kind != FalloffKind::smooth)
    in.fail("falloff", "hsao searches within the radius: use \"step\", \"linear\" or \"smooth\"");
  s.directions = in.integer("directions", 16, 1, 4096);
  // The reference's triangulated surface by default (as hbao); a march given its steps is the stepped
  // bilinear one.
  const bool stepped = in.has("steps");
  const bool triangles =
      in.choice("surface", stepped ? "bilinear" : "triangles", {"bilinear", "triangles"}) == "triangles";
  s.surface = triangles ? HsaoSurface::triangles : HsaoSurface::bilinear;
  if (triangles && stepped)
    in.fail("surface", "\"triangles\" visits every vertex under each ray: no \"steps\"");
  s.steps = in.integer(
      "steps", std::max(1, int(std::min(65536.0, std::ceil(s.falloff.radius / field.texel_size)))), 1, 65536);
  // A repeat field's rays run the whole radius through its tiling (a clamp field's end at its border).
  if (field.wrap == Wrap::repeat && triangles && s.falloff.radius > 1e6 * std::min(field.dx(), field.dy()))
    in.fail("radius",
            "on a repeat field each ray crosses the tiling for the whole radius: at most 1e6 texels");
  s.normal_rays = in.integer("normal_rays", 2, 0, 64);
  in.layers({"obscurance", "bent_normal"}, {"obscurance", "bent_normal"});
  return s;
}

LayerSet bake_hsao(const Scene& scene, const MethodConfig& config, const RunControl& rc) {
  const HeightField& field = scene.field;
  const HsaoSettings& s = config.get<HsaoSettings>();
  const std::vector<std::string>& layers = config.layers;
  std::vector<float> obsc(field.texel_count());
  std::vector<float> bent(wants(layers, "bent_normal") ? 3 * field.texel_count() : 0);  // [3 * texel + c]
  hsao_field(field, scene.normals, s, rc, obsc.data(), bent.empty() ? nullptr : bent.data());
  return obscurance_layers_xyz(field.width, field.height, layers, std::move(obsc), std::move(bent));
}

namespace {

// Farm blocks: "sums#2f" (horizon hi, lo, normal hi, lo) and "bent#2f" (X hi, lo, ...): HsaoSums of block
// `block` per texel, normals from the heights (normal_at, as hsao_field without held normals).
LayerSet hsao_bake_block(const Scene& scene, const MethodConfig& config, int block, const RunControl& rc) {
  const HeightField& field = scene.field;
  const HsaoSettings& s = config.get<HsaoSettings>();
  LayerSet out;
  out.width = field.width, out.height = field.height;
  float* sums = out.add("sums#2f", {"T.hi", "T.lo", "N.hi", "N.lo"}).data.data();
  float* bent = out.add("bent#2f", {"X.hi", "X.lo", "Y.hi", "Y.lo", "Z.hi", "Z.lo"}).data.data();
  const int K = s.directions, d0 = direction_block_begin(block, K), d1 = direction_block_begin(block + 1, K);
  std::atomic<int> rows_done{0};
  tbb::parallel_for(0, field.height, [&](int j) {
    for (int i = 0; i < field.width; ++i) {
      rc.check();  // per texel: a texel's rays may cross a long radius (a repeat field's tiling)
      const std::size_t idx = field.index(i, j);
      const HsaoSums t = hsao_texel_sums(field, normal_at(field, i, j).d(), i, j, s, d0, d1);
      const SplitDouble v[5] = {t.horizon, t.normal, t.bent[0], t.bent[1], t.bent[2]};
      for (int c = 0; c < 2; ++c) sums[4 * idx + 2 * c] = v[c].hi, sums[4 * idx + 2 * c + 1] = v[c].lo;
      for (int c = 0; c < 3; ++c)
        bent[6 * idx + 2 * c] = v[2 + c].hi, bent[6 * idx + 2 * c + 1] = v[2 + c].lo;
    }
    rc.report(double(++rows_done) / field.height);
  });
  return out;
}

LayerSet hsao_finish_blocks(const Scene& scene, const MethodConfig& config, LayerSet&& sums,
                            const RunControl&) {
  const HeightField& field = scene.field;
  const std::vector<std::string>& layers = config.layers;
  std::vector<float> obsc(field.texel_count());
  std::vector<float> bent(wants(layers, "bent_normal") ? 3 * field.texel_count() : 0);
  const std::vector<float> t_sums = take_block_layer(sums, "sums#2f", 4);
  const std::vector<float> b_sums = take_block_layer(sums, "bent#2f", 6);
  const float* ts = t_sums.data();
  const float* bs = b_sums.data();
  tbb::parallel_for(0, field.height, [&](int j) {
    for (int i = 0; i < field.width; ++i) {
      const std::size_t idx = field.index(i, j);
      HsaoSums t;
      t.horizon = {ts[4 * idx], ts[4 * idx + 1]}, t.normal = {ts[4 * idx + 2], ts[4 * idx + 3]};
      for (int c = 0; c < 3; ++c) t.bent[c] = {bs[6 * idx + 2 * c], bs[6 * idx + 2 * c + 1]};
      hsao_store(hsao_finish(t, normal_at(field, i, j).d()), idx, obsc.data(),
                 bent.empty() ? nullptr : bent.data());
    }
  });
  sums = LayerSet();
  return obscurance_layers_xyz(field.width, field.height, layers, std::move(obsc), std::move(bent));
}

}  // namespace

MethodInfo hsao_method() {
  MethodInfo m;
  m.name = "hsao";
  m.reads_normals = false;  // normal_at per texel
  m.reads_albedo = false;
  m.summary = "horizon-split obscurance: a near-field march per direction plus normal-split rays";
  m.read = [](Params& in, const MethodContext& c) {
    const HsaoSettings s = read_hsao_settings(in, c.field);
    MethodConfig config = method_config(s, s.directions);
    config.obscurance = written_falloff(in, s.falloff);
    return config;
  };
  m.bake = bake_hsao;
  // Nothing beyond its layers (the bent normals are written interleaved, as their layer).
  m.memory_knob = "its layers (bent_normal: 12 bytes a texel)";
  m.working_bytes = [](const MethodConfig&, const MethodContext&) { return 0.0; };

  m.division = WorkDivision::directions;
  m.division_note = "partial sums over disjoint direction sets";
  m.bake_block = hsao_bake_block;
  m.finish_blocks = hsao_finish_blocks;
  return m;
}

}  // namespace hfbake
