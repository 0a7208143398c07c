// Independent truth for the P1 tests and measurements: brute-force horizon marches (no hull stack).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "field/procedural.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake::truth {

inline constexpr double kNone = -kPi / 2;  // elevation when nothing lies behind a point

// Uniform random heights in [0, amplitude) (a field with no spatial coherence: the hardest hull input).
inline HeightField random_field(int w, int h, double amplitude, std::uint64_t seed, Wrap wrap) {
  HeightField f;
  f.width = w, f.height = h, f.wrap = wrap, f.texel_size = 1.0;
  f.z.resize(f.texel_count());
  std::uint64_t x = seed * 0x9e3779b97f4a7c15ull + 1;
  for (float& v : f.z) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    v = float(amplitude * double(x >> 11) / 9007199254740992.0);
  }
  return f;
}

inline HeightField procedural(ProceduralKind kind, int w, int h, Wrap wrap, double texel = 1.0) {
  ProceduralSpec s;
  s.kind = kind;
  s.width = w, s.height = h, s.seed = 5;
  return make_procedural(s, texel, wrap);
}

inline SweepLine make_line(const HeightField& f, const SweepDirection& d, int l, std::vector<float>& z) {
  z.resize(d.count);
  return sampled_line(f, d, l, z.data());
}

// The same-points march: the steepest elevation (double atan2) from sample n to every terrain sample before
// it on the line (before sample `end` when given: the far field); kNone when there is none.
inline double march_same_points(const SweepLine& line, int n, int end = 1 << 30) {
  double best = kNone;
  end = std::min(end, n);
  for (int m = 0; m < end && m < line.inside_end; ++m) {
    if (!line.is_terrain(m)) continue;
    best = std::max(best, std::atan2(double(line.z[m]) - double(line.z[n]), (n - m) * line.step));
  }
  return best;
}

// A march from the texel center (i, j) itself towards azimuth phi, samples every `step` texels on the
// bilinear surface (clamp: while on the field; repeat: for `reach` texels); the horizon elevation.
inline double march_from_texel(const HeightField& f, int i, int j, double phi, double step, double reach) {
  const double dx = std::cos(phi), dy = std::sin(phi), z0 = f.z[f.index(i, j)];
  double best = kNone;
  for (int m = 1;; ++m) {
    const double s = m * step, x = i + s * dx, y = j + s * dy;
    if (f.wrap == Wrap::clamp) {
      if (x < -1e-9 || y < -1e-9 || x > f.width - 1 + 1e-9 || y > f.height - 1 + 1e-9) break;
    } else if (s > reach) {
      break;
    }
    const bool clamp = f.wrap == Wrap::clamp;
    const double xs = clamp ? std::clamp(x, 0.0, double(f.width - 1)) : x;
    const double ys = clamp ? std::clamp(y, 0.0, double(f.height - 1)) : y;
    const double z = f.bilinear(xs, ys);
    best = std::max(best, std::atan2(z - z0, s * f.texel_size));
  }
  return best;
}

}  // namespace hfbake::truth
