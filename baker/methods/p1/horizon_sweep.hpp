// The P1 per-line visitor for the shared sweep driver (sweep/sweep_lines.hpp): the convex-hull stack of
// Algorithm 1 run over a line's terrain samples, writing every receiver's horizon elevation (radians,
// -pi/2 when nothing lies behind it, negative where the terrain falls away) and, optionally, the world
// distance to the sample casting it (+inf when none). Samples off a clamp field get -pi/2 without any
// work (the driver never hands their results to a texel). Reused by P2 to get the same horizons.
#pragma once

#include <algorithm>
#include <limits>

#include "methods/p1/fast_math.hpp"
#include "methods/p1/hull_stack.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake::p1 {

// Output layout per receiver: [elevation] or [elevation, distance] (channels() floats).
struct HorizonLineWorker {
  bool distance = false;
  HullStack stack;

  int channels() const { return distance ? 2 : 1; }

  void operator()(const SweepLine& line, float* out) {
    stack.reset(line.count);
    const int C = channels();
    const float step = float(line.step);
    const bool has_terrain = line.inside_end > line.inside_begin;
    // Samples off a clamp field are never receivers (sweep_lines.hpp): mark them and skip the work.
    auto mark = [&](int n0, int n1) {
      for (int n = std::max(n0, line.first_receiver); n < n1; ++n) {
        float* o = out + std::size_t(n - line.first_receiver) * C;
        o[0] = -kHalfPiF;
        if (distance) o[1] = std::numeric_limits<float>::infinity();
      }
    };
    mark(0, has_terrain ? line.inside_begin : line.count);
    if (has_terrain) mark(line.inside_end, line.count);
    if (!has_terrain) return;
    for (int n = line.inside_begin; n < line.inside_end; ++n) {
      const HorizonCaster c = stack.add(n, line.z[n]);
      if (n < line.first_receiver) continue;
      float* o = out + std::size_t(n - line.first_receiver) * C;
      if (c.n < 0) {
        o[0] = -kHalfPiF;
        if (distance) o[1] = std::numeric_limits<float>::infinity();
      } else {
        const float run = float(c.dn) * step;
        o[0] = fast_elevation(float(c.dz), run);
        if (distance) o[1] = std::sqrt(run * run + float(c.dz * c.dz));
      }
    }
  }
};

}  // namespace hfbake::p1
