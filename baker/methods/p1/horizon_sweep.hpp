// The P1 per-line visitor for the shared sweep driver (sweep/sweep_lines.hpp): the convex-hull stack of
// Algorithm 1 run over a line's terrain samples, writing every receiver's horizon elevation (radians,
// -pi/2 when nothing lies behind it, negative where the terrain falls away) and, optionally, the world
// distance to the sample casting it (+inf when none). Reused by P2 to get the same horizons.
#pragma once

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
    for (int n = 0; n < line.count; ++n) {
      HorizonCaster c;
      if (line.is_terrain(n))
        c = stack.add(n, line.z[n]);
      else if (has_terrain && n >= line.inside_end)
        c = stack.query(n, line.z[n]);
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
