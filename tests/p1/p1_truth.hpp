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

// Differences against a truth: mean (bias), rms, and with the reference's own per-texel variances the
// excess rms (the part that is the method's, as report.json's excess_rmse).
struct ErrorStats {
  double n = 0, sum = 0, sum2 = 0, var_ref = 0;
  void add(double d, double v = 0) { n += 1, sum += d, sum2 += d * d, var_ref += v; }
  double mean() const { return sum / n; }
  double rms() const { return std::sqrt(sum2 / n); }
  double excess() const { return std::sqrt(std::max(0.0, (sum2 - var_ref) / n)); }
};

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

// The exact surface of the reference (baker/reference/embree_field.hpp): two triangles per quad, split
// along (i+1, j)-(i, j+1). Along a ray its profile is piecewise linear with kinks only at the crossings of
// columns, rows and diagonals, so the steepest crossing is the exact horizon.
// Height of the reference's triangulated surface at (x, y) (texel coordinates, inside the field).
inline double tri_height(const HeightField& f, double x, double y) {
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const int i = int(fx0), j = int(fy0);
  const double fx = x - fx0, fy = y - fy0;
  const double z00 = f.at(i, j), z10 = f.at(i + 1, j), z01 = f.at(i, j + 1), z11 = f.at(i + 1, j + 1);
  if (fx + fy <= 1) return z00 + fx * (z10 - z00) + fy * (z01 - z00);
  return z11 + (1 - fx) * (z01 - z11) + (1 - fy) * (z10 - z11);
}

// Steepest caster seen from the point (x0, y0) on the surface towards (dx, dy) over the crossings of the
// chosen families (1: columns x = int, 2: rows y = int, 4: diagonals x + y = int) at distance >= smin
// (texels along the ray), clamp field: *dz above the point, *run horizontal world distance; false: none.
// curvature c > 0 lowers a point at horizontal distance d by c d^2 (the Earth's curvature).
inline bool march_from(const HeightField& f, double x0, double y0, double dx, double dy, int families,
                       double smin, double* dz_out, double* run_out, double smax = 1e300,
                       double curvature = 0) {
  const double z0 = tri_height(f, x0, y0);
  double best_num = 0, best_den = 0;  // best slope = num / den
  bool any = false;
  auto consider = [&](double s) {
    const double x = x0 + s * dx, y = y0 + s * dy;
    if (s > smax || x < -1e-9 || y < -1e-9 || x > f.width - 1 + 1e-9 || y > f.height - 1 + 1e-9) return false;
    if (s < smin) return true;
    const double z =
        tri_height(f, std::clamp(x, 0.0, double(f.width - 1)), std::clamp(y, 0.0, double(f.height - 1)));
    const double den = s * f.texel_size, num = z - curvature * den * den - z0;
    if (!any || num * best_den > best_num * den) best_num = num, best_den = den, any = true;
    return true;
  };
  auto family = [&](double origin, double d) {  // crossings of origin + s * d = integer, s > 0
    if (std::fabs(d) < 1e-12) return;
    const double first = d > 0 ? std::floor(origin + 1e-9) + 1 : std::ceil(origin - 1e-9) - 1;
    for (long m = 0;; ++m) {
      const double c = first + (d > 0 ? 1.0 : -1.0) * double(m);
      if (!consider((c - origin) / d)) break;
    }
  };
  if (families & 1) family(x0, dx);
  if (families & 2) family(y0, dy);
  if (families & 4) family(x0 + y0, dx + dy);
  *dz_out = best_num, *run_out = best_den;
  return any;
}

// Steepest elevation from texel (i, j) (see march_from).
inline double march_tri(const HeightField& f, int i, int j, double dx, double dy, int families,
                        double curvature = 0) {
  double dz, run;
  return march_from(f, i, j, dx, dy, families, 0, &dz, &run, 1e300, curvature) ? std::atan2(dz, run)
                                                                               : truth::kNone;
}

// Rough fBm at the texel scale (like a rough DSM): value noise (bilinear lattice, hashed) from `largest`
// texels down to 1 texel, each octave's amplitude `gain` times the last, then scaled so that the median
// forward difference |z(i+1, j) - z(i, j)| is tan(slope_deg) (texel size 1): slope_deg 60-80 gives the
// rough fields of tests/p1/test_p1_rough.cpp.
inline HeightField rough_field(int w, int h, double slope_deg, double gain, std::uint64_t seed,
                               int largest = 64) {
  HeightField f;
  f.width = w, f.height = h, f.wrap = Wrap::clamp, f.texel_size = 1.0;
  std::vector<double> z(std::size_t(w) * h, 0.0);
  auto hash = [&](std::uint64_t o, std::int64_t a, std::int64_t b) {
    std::uint64_t x = seed * 0x9e3779b97f4a7c15ull ^ (o * 0xbf58476d1ce4e5b9ull) ^
                      (std::uint64_t(a) * 0x94d049bb133111ebull) ^ (std::uint64_t(b) * 0x2545f4914f6cdd1dull);
    x ^= x >> 31, x *= 0x9e3779b97f4a7c15ull, x ^= x >> 29, x *= 0xbf58476d1ce4e5b9ull, x ^= x >> 32;
    return 2.0 * double(x >> 11) / 9007199254740992.0 - 1.0;
  };
  double amp = 1;
  std::uint64_t octave = 0;
  for (int cell = largest; cell >= 1; cell /= 2, amp *= gain, ++octave)
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) {
        const double x = double(i) / cell, y = double(j) / cell;
        const std::int64_t x0 = std::int64_t(std::floor(x)), y0 = std::int64_t(std::floor(y));
        const double tx = x - double(x0), ty = y - double(y0);
        const double a = hash(octave, x0, y0), b = hash(octave, x0 + 1, y0);
        const double c = hash(octave, x0, y0 + 1), d = hash(octave, x0 + 1, y0 + 1);
        z[std::size_t(j) * w + i] += amp * ((a + (b - a) * tx) * (1 - ty) + (c + (d - c) * tx) * ty);
      }
  std::vector<double> diffs;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i + 1 < w; ++i)
      diffs.push_back(std::fabs(z[std::size_t(j) * w + i + 1] - z[std::size_t(j) * w + i]));
  std::nth_element(diffs.begin(), diffs.begin() + diffs.size() / 2, diffs.end());
  const double scale = std::tan(slope_deg * kPi / 180) / std::max(diffs[diffs.size() / 2], 1e-30);
  f.z.resize(z.size());
  for (std::size_t t = 0; t < z.size(); ++t) f.z[t] = float(z[t] * scale);
  return f;
}

// A step of height `step` (world units; texel size 1) along the line through the field's centre at
// `angle_deg` to the y axis: z = step where (x - cx) cos a + (y - cy) sin a >= 0, else 0 (angle 0: a wall
// along a column). `terraces` > 1: that many steps, `spacing` texels apart along the same normal.
inline HeightField step_field(int w, int h, double step, double angle_deg, int terraces = 1,
                              double spacing = 16) {
  HeightField f;
  f.width = w, f.height = h, f.wrap = Wrap::clamp, f.texel_size = 1.0;
  f.z.resize(std::size_t(w) * h);
  const double a = angle_deg * kPi / 180, ca = std::cos(a), sa = std::sin(a);
  const double cx = 0.5 * (w - 1) + 0.25, cy = 0.5 * (h - 1) + 0.125;  // no texel exactly on the step line
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double d = (i - cx) * ca + (j - cy) * sa;
      int n = 0;
      for (int t = 0; t < terraces; ++t) n += d >= (t - 0.5 * (terraces - 1)) * spacing ? 1 : 0;
      f.z[f.index(i, j)] = float(step * n);
    }
  return f;
}

// The exact horizons (sin of the elevation) of texel (i, j) for the K azimuths of the sweep (the
// directions plan_direction builds: the same unit vectors P1 looks along), by march_tri over every column,
// row and diagonal crossing: out[k]. -1 where nothing lies behind.
inline void exact_horizons(const HeightField& f, const std::vector<SweepDirection>& dirs, int i, int j,
                           float* out) {
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    const double e = march_tri(f, i, j, dirs[k].dx, dirs[k].dy, 7);
    out[k] = float(std::sin(e));
  }
}

// P1's ao term of one direction (Eq. 5 with the midpoint azimuthal rule, as compute_p1) at elevation e.
inline double ao_term(double e, double np, double nz) {
  const double th = std::min(kPi / 2 - e, kPi / 2 + std::atan2(np, nz));
  const double st = std::sin(th), ct = std::cos(th);
  return nz * st * st + np * (th - st * ct);
}

}  // namespace hfbake::truth
