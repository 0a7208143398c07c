// The P1 per-line visitor for the shared sweep driver (sweep/sweep_lines.hpp): the convex-hull stack of
// Algorithm 1 run over a line's terrain samples. For every receiver it writes what casts its horizon --
// [dz: caster height above the sample, run: horizontal distance (+inf: nothing behind), the sample's
// height] -- so the texel visitor can evaluate each tap's horizon from the texel's own height
// (tap_elevation below): the two samples a texel blends lie up to a texel away, at other heights, and far
// casters seen from the texel's height remove most of the bias that blending the samples' own angles has
// (measured in tests/p1, P1Measure.MappingErrorAgainstTexelCenterMarch). Samples off a clamp field get
// "nothing" without any work (the driver never hands their results to a texel).
#pragma once

#include <algorithm>
#include <limits>

#include "methods/p1/fast_math.hpp"
#include "methods/p1/hull_stack.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake::p1 {

// The horizon of a texel from one of its two taps: the tap sample sees its caster dz above it at
// horizontal distance run (+inf: nothing). `lift` is the sample's height above the texel's tangent plane
// (z_sample - z_texel - grad h . offset: zero on any plane). A far caster is seen from the texel's tangent
// plane rather than from the sample (the sample lies up to a texel aside: in a valley it sits higher than
// the texel, and blending the samples' own angles biases valleys open); a near caster lies as far aside as
// the sample, so the sample's own angle is kept (at a crease, lifting it would be wrong). Weight 0 for the
// adjacent sample, 1 from 4 steps on. Exact on planes either way; -pi/2 when nothing lies behind.
inline float tap_elevation(float dz, float run, float lift, float step) {
  const float own = fast_atan2_pos(dz, run);
  const float seen = fast_atan2_pos(dz + lift, run);
  float w = (run / step - 1.0f) * (1.0f / 3.0f);
  w = w < 0 ? 0.0f : (w > 1 ? 1.0f : w);
  return run == std::numeric_limits<float>::infinity() ? -kHalfPiF : own + (seen - own) * w;
}
// World distance from a texel at height z_texel to a tap's caster (+inf for none).
inline float tap_distance(float dz, float run, float z_sample, float z_texel) {
  const float h = dz + (z_sample - z_texel);
  return std::sqrt(run * run + h * h);
}

struct HorizonLineWorker {
  HullStack stack;

  static constexpr int channels() { return 3; }

  void operator()(const SweepLine& line, float* out) {
    stack.reset(line.count);
    const float step = float(line.step);
    const bool has_terrain = line.inside_end > line.inside_begin;
    auto mark = [&](int n0, int n1) {
      for (int n = std::max(n0, line.first_receiver); n < n1; ++n) {
        float* o = out + std::size_t(n - line.first_receiver) * 3;
        o[0] = 0.0f;
        o[1] = std::numeric_limits<float>::infinity();
        o[2] = line.z[n];
      }
    };
    mark(0, has_terrain ? line.inside_begin : line.count);
    if (!has_terrain) return;
    mark(line.inside_end, line.count);
    for (int n = line.inside_begin; n < line.inside_end; ++n) {
      const HorizonCaster c = stack.add(n, line.z[n]);
      if (n < line.first_receiver) continue;
      float* o = out + std::size_t(n - line.first_receiver) * 3;
      o[0] = float(c.dz);
      o[1] = c.n < 0 ? std::numeric_limits<float>::infinity() : float(c.dn) * step;
      o[2] = line.z[n];
    }
  }
};

}  // namespace hfbake::p1
