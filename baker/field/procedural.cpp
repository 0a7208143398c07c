// Built-in height fields. Every kind is a pure function of (spec, texel coordinates): deterministic for
// any thread count and machine (integer hashing, no global RNG state). Shapes are defined in texel units
// and scaled by texel_size, so a field means the same thing at any world scale.
//
//   fractal  periodic fBm (value noise with quintic interpolation, octaves of doubling frequency and
//            halving amplitude: a 1/f^2 power spectrum like midpoint displacement), tiles seamlessly.
//            feature_size: largest wavelength (default width / 2), amplitude: height range scale
//            (default width / 8).
//   bricks   running-bond brick wall: bricks of feature_size x feature_size / 2 (default width / 8)
//            with per-brick random height in [0.75, 1] * amplitude (default feature_size / 4), 45-degree
//            bevels, and mortar joints of width feature_size / 16 at height 0.
//   sines    sine grid h = amplitude * sin(2 pi x / P) * sin(2 pi y / P), P = feature_size (default
//            width / 8), amplitude default P / 4.
//   blocks   axis-aligned boxes of random size in [0.5, 1.5] * feature_size (default width / 12) and
//            random height in [0.2, 1] * amplitude (default feature_size), on flat ground, one per cell
//            of a feature_size * 2 grid (seeded placement inside the cell).
//   flat     h = 0.
//   slope    a plane rising with angle_deg towards the azimuth aspect_deg + 180 (it faces aspect_deg).
//   trench   a V-trench along the y axis through the field's center column, walls at angle_deg.
//   pit      a cylindrical pit of radius `radius` and depth `depth` centred in the field.
//   cone     a cone with its apex at the field's center, flanks falling at angle_deg.
#include "field/procedural.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace hfbake {
namespace {

std::uint64_t mix(std::uint64_t x) {  // splitmix64 finaliser
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Uniform in [0, 1) from (seed, a, b, c).
double hash01(std::uint64_t seed, std::int64_t a, std::int64_t b, std::int64_t c = 0) {
  std::uint64_t h = mix(seed ^ mix(std::uint64_t(a) ^ mix(std::uint64_t(b) ^ mix(std::uint64_t(c)))));
  return double(h >> 11) * (1.0 / 9007199254740992.0);
}

double quintic(double t) {
  return t * t * t * (t * (t * 6 - 15) + 10);
}

// Periodic value noise with `cells` lattice cells across the unit square, u, v in [0, 1).
// 64-bit cell counts: a long thin field doubles its long side's count past int's range (size [2, 100000]).
double value_noise(std::uint64_t seed, int octave, std::int64_t cells_x, std::int64_t cells_y, double u,
                   double v) {
  const double x = u * double(cells_x), y = v * double(cells_y);
  const double fx = std::floor(x), fy = std::floor(y);
  const std::int64_t x0 = std::int64_t(fx), y0 = std::int64_t(fy);
  const double tx = quintic(x - fx), ty = quintic(y - fy);
  auto lattice = [&](std::int64_t xi, std::int64_t yi) {
    xi = ((xi % cells_x) + cells_x) % cells_x;
    yi = ((yi % cells_y) + cells_y) % cells_y;
    return 2.0 * hash01(seed, xi, yi, octave) - 1.0;
  };
  const double a = lattice(x0, y0), b = lattice(x0 + 1, y0);
  const double c = lattice(x0, y0 + 1), d = lattice(x0 + 1, y0 + 1);
  return (a + (b - a) * tx) * (1 - ty) + (c + (d - c) * tx) * ty;
}

double fractal(const ProceduralSpec& s, double feature, double amp, int i, int j) {
  const double u = double(i) / s.width, v = double(j) / s.height;
  std::int64_t cx = std::max<std::int64_t>(1, std::llround(s.width / feature));
  std::int64_t cy = std::max<std::int64_t>(1, std::llround(s.height / feature));
  double h = 0, a = amp;
  const std::int64_t max_cells = std::max(s.width, s.height);
  for (int octave = 0; octave < 16 && std::min(cx, cy) <= max_cells; ++octave) {
    h += a * value_noise(s.seed, octave, cx, cy, u, v);
    a *= 0.5;
    cx *= 2;
    cy *= 2;
  }
  return h;
}

double bricks(const ProceduralSpec& s, double feature, double amp, int i, int j) {
  const double bw = feature, bh = feature / 2, mortar = feature / 16;
  const double y = j + 0.5;
  const std::int64_t row = std::int64_t(std::floor(y / bh));
  const double x = i + 0.5 + ((row & 1) ? bw / 2 : 0.0);
  const std::int64_t col = std::int64_t(std::floor(x / bw));
  const double lx = x - col * bw, ly = y - row * bh;
  // Distance into the brick from its nearest edge, minus the half mortar joint.
  const double edge = std::min(std::min(lx, bw - lx), std::min(ly, bh - ly)) - mortar / 2;
  if (edge <= 0) return 0.0;
  const double top = amp * (0.75 + 0.25 * hash01(s.seed, col, row));
  return std::min(top, edge);  // 45-degree bevel up to the brick's top
}

double sines(double feature, double amp, int i, int j) {
  const double k = 2 * kPi / feature;
  return amp * std::sin(k * i) * std::sin(k * j);
}

double blocks(const ProceduralSpec& s, double feature, double amp, int i, int j) {
  const double cell = 2 * feature;
  const std::int64_t ci = std::int64_t(std::floor(i / cell)), cj = std::int64_t(std::floor(j / cell));
  double h = 0;
  // A block may extend into neighbouring cells: look at the 3x3 neighbourhood.
  for (std::int64_t dj = -1; dj <= 1; ++dj) {
    for (std::int64_t di = -1; di <= 1; ++di) {
      const std::int64_t bi = ci + di, bj = cj + dj;
      const double w = feature * (0.5 + hash01(s.seed, bi, bj, 1));
      const double d = feature * (0.5 + hash01(s.seed, bi, bj, 2));
      const double x0 = bi * cell + hash01(s.seed, bi, bj, 3) * (cell - 0.5 * w);
      const double y0 = bj * cell + hash01(s.seed, bi, bj, 4) * (cell - 0.5 * d);
      if (i >= x0 && i < x0 + w && j >= y0 && j < y0 + d)
        h = std::max(h, amp * (0.2 + 0.8 * hash01(s.seed, bi, bj, 5)));
    }
  }
  return h;
}

}  // namespace

bool parse_procedural_kind(const std::string& name, ProceduralKind& kind) {
  for (int k = 0; k <= int(ProceduralKind::cone); ++k) {
    if (name == procedural_kind_name(ProceduralKind(k))) {
      kind = ProceduralKind(k);
      return true;
    }
  }
  return false;
}

const char* procedural_kind_name(ProceduralKind kind) {
  switch (kind) {
    case ProceduralKind::fractal:
      return "fractal";
    case ProceduralKind::bricks:
      return "bricks";
    case ProceduralKind::sines:
      return "sines";
    case ProceduralKind::blocks:
      return "blocks";
    case ProceduralKind::flat:
      return "flat";
    case ProceduralKind::slope:
      return "slope";
    case ProceduralKind::trench:
      return "trench";
    case ProceduralKind::pit:
      return "pit";
    case ProceduralKind::cone:
      return "cone";
  }
  return "?";
}

HeightField make_procedural(const ProceduralSpec& s, double texel_size, Wrap wrap) {
  HeightField f;
  f.width = s.width;
  f.height = s.height;
  f.texel_size = texel_size;
  f.wrap = wrap;
  f.z.resize(f.texel_count());
  const double size = std::min(s.width, s.height);
  const double deg = kPi / 180.0;
  const double cx = 0.5 * (s.width - 1), cy = 0.5 * (s.height - 1);

  double feature = s.feature_size, amp = s.amplitude;
  switch (s.kind) {
    case ProceduralKind::fractal:
      if (feature <= 0) feature = size / 2;
      if (amp <= 0) amp = size / 8;
      break;
    case ProceduralKind::bricks:
      if (feature <= 0) feature = size / 8;
      if (amp <= 0) amp = feature / 4;
      break;
    case ProceduralKind::sines:
      if (feature <= 0) feature = size / 8;
      if (amp <= 0) amp = feature / 4;
      break;
    case ProceduralKind::blocks:
      if (feature <= 0) feature = size / 12;
      if (amp <= 0) amp = feature;
      break;
    default:
      break;
  }
  const double radius = s.radius > 0 ? s.radius : size / 4;
  const double depth = s.depth > 0 ? s.depth : radius;
  const double tan_a = std::tan(s.angle_deg * deg);
  const double ax = std::cos(s.aspect_deg * deg), ay = std::sin(s.aspect_deg * deg);

  // Each texel is a pure function of (spec, i, j): rows in parallel, the same heights for any thread count.
  tbb::parallel_for(0, s.height, [&](int j) {
    for (int i = 0; i < s.width; ++i) {
      double h = 0;  // in texel units
      switch (s.kind) {
        case ProceduralKind::fractal:
          h = fractal(s, feature, amp, i, j);
          break;
        case ProceduralKind::bricks:
          h = bricks(s, feature, amp, i, j);
          break;
        case ProceduralKind::sines:
          h = sines(feature, amp, i, j);
          break;
        case ProceduralKind::blocks:
          h = blocks(s, feature, amp, i, j);
          break;
        case ProceduralKind::flat:
          h = 0;
          break;
        case ProceduralKind::slope:
          h = -tan_a * ((i - cx) * ax + (j - cy) * ay);
          break;
        case ProceduralKind::trench:
          h = tan_a * std::abs(i - cx);
          break;
        case ProceduralKind::pit:
          h = std::hypot(i - cx, j - cy) < radius ? -depth : 0.0;
          break;
        case ProceduralKind::cone:
          h = -tan_a * std::hypot(i - cx, j - cy);
          break;
      }
      f.z[f.index(i, j)] = float(h * texel_size);
    }
  });
  return f;
}

}  // namespace hfbake
