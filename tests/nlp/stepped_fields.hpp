// Stepped fields for nlp's accuracy on steps (docs/methods/nlp.md "Steps"): a terraced hill of concentric
// circular terraces, each tread `width` texels deep and each riser `height` texels high, the riser spread
// over `ramp` texels of the tread (0: a cliff between neighbouring texels), scored against the Embree
// reference (reference/bake_reference.hpp) under the uniform-sky setting of docs/methods/nlp.md.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "env/environment.hpp"
#include "field/scene.hpp"
#include "methods/nlp/bake_nlp.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake::steps {

struct Steps {
  double height = 4;  // texels
  double width = 8;   // texels
  double ramp = 0;    // texels of each tread the riser takes (0 <= ramp < width)
};

// z = height * (k + clamp((f - (width - ramp)) / ramp, 0, 1)), k = floor(u / width), f = u - k width,
// u = max(0, R - r): r the distance from the field's centre, R half the field's smaller side.
inline HeightField make_stepped_hill(int size, Steps s) {
  HeightField f;
  f.width = f.height = size;
  f.texel_size = 1;
  f.wrap = Wrap::clamp;
  f.z.resize(f.texel_count());
  const double c = 0.5 * (size - 1), R = 0.5 * size;
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      const double u = std::max(0.0, R - std::hypot(i - c, j - c));
      const double k = std::floor(u / s.width), fr = u - k * s.width;
      const double rise = s.ramp > 0 ? std::clamp((fr - (s.width - s.ramp)) / s.ramp, 0.0, 1.0) : 0.0;
      f.z[f.index(i, j)] = float(s.height * (k + rise));
    }
  return f;
}

// The uniform-sky setting of docs/methods/nlp.md's table: sky (0.6, 0.7, 1.0), albedo 0.6, one bounce.
inline Scene make_steps_scene(int size, Steps s) {
  Scene scene;
  scene.field = make_stepped_hill(size, s);
  scene.normals = compute_normals(scene.field);
  scene.surface.albedo.assign(scene.field.texel_count(), Rgb{0.6f, 0.6f, 0.6f});
  scene.environment = make_uniform_environment(Rgb{0.6f, 0.7f, 1.0f});
  scene.bounces = 1;
  return scene;
}

inline LayerSet reference_of(const Scene& scene, int samples) {
  ReferenceOptions o;
  o.layers = {"indirect", "total"};
  o.samples = samples;
  o.seed = 1;
  return bake_reference(scene, o, RunControl{});
}

struct Score {
  double indirect_bias = 0;   // (sum of nlp's indirect - sum of the reference's) / sum of the reference's
  double total_rel_mae = 0;   // sum |nlp - reference| / sum reference, total
  double total_noise = 0;     // the reference's own: mean total_stderr / mean total
  double indirect_share = 0;  // mean indirect / mean total (reference)
};

// Over the texels `crop` or more from the border, every channel.
inline Score score(const LayerSet& nlp, const LayerSet& ref, int crop) {
  const int W = ref.width, H = ref.height;
  const auto& ni = nlp.find("indirect")->data;
  const auto& nt = nlp.find("total")->data;
  const auto& ri = ref.find("indirect")->data;
  const auto& rt = ref.find("total")->data;
  const auto& rs = ref.find("total_stderr")->data;
  double sni = 0, sri = 0, ad = 0, st = 0, se = 0;
  for (int j = crop; j < H - crop; ++j)
    for (int i = crop; i < W - crop; ++i)
      for (int c = 0; c < 3; ++c) {
        const std::size_t t = (std::size_t(j) * W + i) * 3 + c;
        sni += ni[t], sri += ri[t], ad += std::abs(nt[t] - rt[t]), st += rt[t], se += rs[t];
      }
  return {sni / sri - 1, ad / st, se / st, sri / st};
}

inline LayerSet bake_nlp_defaults(const Scene& scene, int m) {
  NlpOptions o;
  o.directions = m;
  o.layers = {"direct", "indirect", "total"};
  return bake_nlp(scene, o, RunControl{});
}

inline std::string describe(Steps s) {
  char b[96];
  std::snprintf(b, sizeof b, "height %g, width %g, ramp %g", s.height, s.width, s.ramp);
  return b;
}

}  // namespace hfbake::steps
