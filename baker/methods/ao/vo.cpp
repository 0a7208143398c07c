#include "methods/ao/vo.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>

#include "core/error.hpp"
#include "methods/ao/bake_ao.hpp"
#include "methods/ao/obscurance_params.hpp"

namespace hfbake {
namespace {

// The texel grid the tables cover: the field, plus a wrapped apron of b texels on repeating fields so every
// footprint is one rectangle. Apron texels keep their unwrapped world position (a tiled field continues).
struct Domain {
  const HeightField& f;
  int pad, w, h;  // apron and padded size
  Domain(const HeightField& field, int b)
      : f(field),
        pad(field.wrap == Wrap::repeat ? b : 0),
        w(field.width + 2 * pad),
        h(field.height + 2 * pad) {}
  std::size_t source(int pi, int pj) const { return f.index(f.wrap_i(pi - pad), f.wrap_j(pj - pad)); }
};

// Summed-area table with C channels over the padded domain: S(x, y) = sum of the values of texels
// [0, x) x [0, y); box sums are exact up to double rounding (double: differences of large prefix sums lose
// float precision).
template <int C>
struct Sat {
  int w = 0, h = 0;
  std::vector<double> s;  // (w + 1) x (h + 1) x C
  double* at(int x, int y) { return &s[(std::size_t(y) * (w + 1) + x) * C]; }
  const double* at(int x, int y) const { return &s[(std::size_t(y) * (w + 1) + x) * C]; }

  // value(pi, pj, out[C]) fills the texel's channels.
  template <class V>
  void build(int width, int height, const V& value, const RunControl& rc) {
    w = width, h = height;
    s.assign(std::size_t(w + 1) * (h + 1) * C, 0.0);
    tbb::parallel_for(0, h, [&](int y) {  // row prefix sums into row y + 1
      rc.check();
      double acc[C] = {}, v[C];
      for (int x = 0; x < w; ++x) {
        value(x, y, v);
        double* o = at(x + 1, y + 1);
        for (int c = 0; c < C; ++c) o[c] = (acc[c] += v[c]);
      }
    });
    tbb::parallel_for(1, w + 1, [&](int x) {  // column prefix sums
      for (int y = 1; y <= h; ++y) {
        double* o = at(x, y);
        const double* u = at(x, y - 1);
        for (int c = 0; c < C; ++c) o[c] += u[c];
      }
    });
  }
  // Sum over texels [x0, x1] x [y0, y1] (inclusive).
  void box(int x0, int y0, int x1, int y1, double out[C]) const {
    const double *a = at(x1 + 1, y1 + 1), *b = at(x0, y1 + 1), *c = at(x1 + 1, y0), *d = at(x0, y0);
    for (int k = 0; k < C; ++k) out[k] = a[k] - b[k] - c[k] + d[k];
  }
};

int half_width(const FieldShape& f, const VoSettings& s) {
  return std::max(0, int(std::lround(s.radius / f.texel_size)));
}

}  // namespace

double vo_response(double delta, double box_height, double fade) {
  if (!(delta > 0)) return 0.0;
  if (delta <= box_height) return delta / box_height;
  if (!(fade > 0)) return 0.0;
  return std::max(0.0, 1.0 - (delta - box_height) / fade);
}

std::vector<float> vo_occlusion(const HeightField& f, const std::vector<Vec3f>& normals, const VoSettings& s,
                                const RunControl& rc) {
  const int b = half_width(f, s);
  const Domain dom(f, b);
  const double ts = f.texel_size;
  const std::size_t n = f.texel_count();
  std::vector<std::uint16_t> label(n, 0), next(n, 0);
  // Footprint rectangle of real texel (i, j) in padded coordinates, clipped to the domain.
  auto rect = [&](int i, int j, int r[4]) {
    const int pi = i + dom.pad, pj = j + dom.pad;
    r[0] = std::max(0, pi - b), r[1] = std::max(0, pj - b);
    r[2] = std::min(dom.w - 1, pi + b), r[3] = std::min(dom.h - 1, pj + b);
  };
  const int total_stages = (1 << s.levels) - 1 + (1 << s.levels);
  int stage = 0;

  // Adaptive splits: each layer's texels above the layer's footprint mean go to the upper child.
  for (int level = 0; level < s.levels; ++level) {
    for (int node = 0; node < (1 << level); ++node) {
      Sat<2> sat;
      sat.build(
          dom.w, dom.h,
          [&](int pi, int pj, double* v) {
            const std::size_t src = dom.source(pi, pj);
            const bool in = label[src] == node;
            v[0] = in ? double(f.z[src]) : 0.0, v[1] = in ? 1.0 : 0.0;
          },
          rc);
      tbb::parallel_for(0, f.height, [&](int j) {
        for (int i = 0; i < f.width; ++i) {
          const std::size_t idx = f.index(i, j);
          if (label[idx] != node) continue;
          int r[4];
          double sum[2];
          rect(i, j, r);
          sat.box(r[0], r[1], r[2], r[3], sum);  // the texel itself is in it: sum[1] >= 1
          next[idx] = std::uint16_t(2 * node + (double(f.z[idx]) * sum[1] > sum[0] ? 1 : 0));
        }
      });
      rc.report(double(++stage) / total_stages);
    }
    label.swap(next);
  }

  // Leaf layers: mean position in the footprint -> offset along the normal -> response, count weighted.
  std::vector<double> num(n, 0.0), den(n, 0.0);
  for (int leaf = 0; leaf < (1 << s.levels); ++leaf) {
    Sat<4> sat;
    sat.build(
        dom.w, dom.h,
        [&](int pi, int pj, double* v) {
          const std::size_t src = dom.source(pi, pj);
          const bool in = label[src] == leaf;
          v[0] = in ? double(pi - dom.pad) : 0.0, v[1] = in ? double(pj - dom.pad) : 0.0;
          v[2] = in ? double(f.z[src]) : 0.0, v[3] = in ? 1.0 : 0.0;
        },
        rc);
    tbb::parallel_for(0, f.height, [&](int j) {
      rc.check();
      for (int i = 0; i < f.width; ++i) {
        int r[4];
        double sum[4];
        rect(i, j, r);
        sat.box(r[0], r[1], r[2], r[3], sum);
        if (!(sum[3] > 0.5)) continue;  // the layer has no texel in this footprint: weight 0
        const std::size_t idx = f.index(i, j);
        const Vec3 nn = normals.empty() ? normal_at(f, i, j).d() : normals[idx].d();
        const double inv = 1.0 / sum[3];
        const double delta = (sum[0] * inv - i) * ts * nn.x + (sum[1] * inv - j) * ts * nn.y +
                             (sum[2] * inv - double(f.z[idx])) * nn.z;
        num[idx] += vo_response(delta, s.box_height, s.fade) * sum[3];
        den[idx] += sum[3];
      }
    });
    rc.report(double(++stage) / total_stages);
  }
  std::vector<float> occ(n);
  for (std::size_t t = 0; t < n; ++t) occ[t] = den[t] > 0 ? float(num[t] / den[t]) : 0.0f;
  return occ;
}

double vo_brute_force(const HeightField& f, Vec3 nn, int i, int j, const VoSettings& s) {
  const int b = half_width(f, s);
  const double z0 = f.z[f.index(i, j)], ts = f.texel_size;
  double sum = 0;
  int count = 0;
  for (int y = j - b; y <= j + b; ++y)
    for (int x = i - b; x <= i + b; ++x) {
      if (f.wrap == Wrap::clamp && (x < 0 || y < 0 || x >= f.width || y >= f.height)) continue;
      const double delta = (x - i) * ts * nn.x + (y - j) * ts * nn.y + (double(f.at(x, y)) - z0) * nn.z;
      sum += vo_response(delta, s.box_height, s.fade);
      ++count;
    }
  return sum / count;
}

VoSettings read_vo_settings(Params& in, const FieldShape& field) {
  if (!in.has("radius")) in.fail("radius", "vo needs the footprint half-width (world units)");
  VoSettings s;
  s.radius = in.number("radius", 0, 1e-12, 1e9);
  s.box_height = in.number("box_height", s.radius, 1e-12, 1e9);
  s.fade = in.number("fade", s.radius, 0, 1e9);
  const int layers_wanted = in.integer("depth_layers", 4, 1, 8);
  s.levels = 0;
  while ((1 << s.levels) < layers_wanted) ++s.levels;
  if ((1 << s.levels) != layers_wanted) in.fail("depth_layers", "must be 1, 2, 4 or 8");
  if (half_width(field, s) > std::max(field.width, field.height))
    in.fail("radius", "the footprint is larger than the field");
  in.layers({"obscurance"}, {"obscurance"});
  return s;
}

LayerSet bake_vo(const Scene& scene, const MethodConfig& config, const RunControl& rc) {
  const HeightField& field = scene.field;
  const VoSettings& s = config.get<VoSettings>();
  LayerSet out;
  out.width = field.width;
  out.height = field.height;
  std::vector<float> occ = vo_occlusion(field, scene.normals, s, rc);
  for (float& v : occ) v = 1.0f - v;
  out.add("obscurance", mono_channels()).data = std::move(occ);
  out.attributes.emplace_back("hfbake:vo:quantity",
                              "1 - box volumetric obscurance (tangent-space box, ALSVO estimate); not the "
                              "hemisphere obscurance");
  return out;
}

MethodInfo vo_method() {
  MethodInfo m;
  m.name = "vo";
  m.reads_normals = false;  // normal_at per texel
  m.reads_albedo = false;
  m.summary =
      "volumetric obscurance (Hendrickx 2015, adaptively layered): the occupied fraction of a tangent-space "
      "box per texel";
  m.read = [](Params& in, const MethodContext& c) {
    const VoSettings s = read_vo_settings(in, c.field);
    MethodConfig config = method_config(s);
    // Its footprint's radius as a step falloff: what the reference's obscurance compares it against.
    config.obscurance = Falloff{FalloffKind::step, s.radius};
    return config;
  };
  m.bake = bake_vo;
  // The occupancy's summed-area tables (measured: 44 bytes a texel at 2048^2, docs/large-fields.md).
  m.memory_knob = "a smaller field (its summed-area tables take 44 bytes a texel whatever its parameters)";
  m.working_bytes = [](const MethodConfig&, const MethodContext& c) {
    return 44.0 * double(c.field.width) * double(c.field.height);
  };
  m.division = WorkDivision::texel_tiles;
  // The farm runs it whole in one shard (no bake_block): a tile's own summed-area tables would round
  // differently from the whole field's (differences of large prefix sums), so tiles could not merge to the
  // single bake's bits, and vo is one pass over the field (cheap beside the reference and the sweeps).
  m.division_note =
      "whole, in one shard: tiles with a halo of the footprint would work, but their own summed-area tables "
      "round differently from the whole field's (not bit-identical), and the pass is cheap";
  return m;
}

}  // namespace hfbake
