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
//   terraces smooth hills (three octaves of the fractal's noise, feature_size default width / 2, amplitude
//            default width / 16) quantised into flat terraces: z = step * floor(hills / step), vertical
//            steps of `step` texels (default amplitude / 3) between neighbouring texels.
//   craters  bowls with raised rims on flat ground, one per cell of a 3 * feature_size grid (feature_size
//            default width / 10): radius R in [0.5, 1.5] * feature_size, depth d in [0.5, 1] * amplitude
//            (default 0.4 * feature_size); inside z = d ((r/R)^2 - 1) + d / 4, outside the rim
//            d / 4 * (1 - (r/R - 1) / 0.6)^2 out to 1.6 R. Overlapping craters add.
//   ridges   ridged multifractal: sum over octaves of amplitude 2^-o (1 - |noise_o|)^2 (the fractal's
//            periodic value noise), sharp crests and rounded valleys; feature_size and amplitude as fractal.
//   rough    fBm steep at the texel scale, like a rough DSM: bilinear lattice noise with cells from 64
//            texels down to 1, each octave 0.7 times the last, scaled so that the median forward
//            difference |z(i+1, j) - z(i, j)| is tan(angle_deg) (default 70 degrees). The scale is measured
//            on the noise's fixed 256x256 window at the origin, so it is the same for every field size.
#include "field/procedural.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

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

// One periodic lattice value in [-1, 1): octave `octave`'s value at lattice point (xi, yi), the lattice
// repeating every cells_x x cells_y points.
double lattice_value(std::uint64_t seed, int octave, std::int64_t xi, std::int64_t yi, std::int64_t cells_x,
                     std::int64_t cells_y) {
  xi = ((xi % cells_x) + cells_x) % cells_x;
  yi = ((yi % cells_y) + cells_y) % cells_y;
  return 2.0 * hash01(seed, xi, yi, octave) - 1.0;
}

// Adds a * shape(n) to out[i] for i in [0, width): n is the bilinear blend, with weights tx(i) and ty, of the
// four lattice values around texel i of the row: columns x0(i) and x0(i) + 1 of lattice rows y0 and y0 + 1,
// where column(i) = {x0(i), tx(i)} and x0 never falls along a row. at(xi, dy) is the value at column xi of
// row y0 + dy; each is read once per row (the texel-by-texel definition reads four per texel; tests/field
// compares the bits).
template <class Column, class At, class Shape>
void add_lattice_row(int width, double a, double ty, Column column, At at, Shape shape, double* out) {
  std::int64_t cell = std::numeric_limits<std::int64_t>::min();
  double c00 = 0, c10 = 0, c01 = 0, c11 = 0;
  for (int i = 0; i < width; ++i) {
    const auto [x0, tx] = column(i);
    if (x0 != cell) {
      if (x0 == cell + 1) {  // the next cell along the row: its left corners are the last one's right ones
        c00 = c10;
        c01 = c11;
      } else {
        c00 = at(x0, 0);
        c01 = at(x0, 1);
      }
      c10 = at(x0 + 1, 0);
      c11 = at(x0 + 1, 1);
      cell = x0;
    }
    out[i] += a * shape((c00 + (c10 - c00) * tx) * (1 - ty) + (c01 + (c11 - c01) * tx) * ty);
  }
}

double identity_shape(double n) {
  return n;
}

double ridge_shape(double n) {
  return (1 - std::abs(n)) * (1 - std::abs(n));
}

// One row j of octaves of periodic value noise (quintic-weighted bilinear blend of the lattice values,
// `cells` lattice cells across the unit square; 64-bit counts: a long thin field doubles its long side's
// count past int's range, size [2, 100000]), from `feature` texels down to one texel (at most `octaves`):
// each octave adds amplitude * shape(noise) and the amplitude halves. out[i] for i in [0, width): each
// texel's octaves are summed in order, as a texel-by-texel evaluation would (tests/field compares the
// bits); the lattice values are hashed once per row and octave, not four times per texel.
template <class Shape>
void octave_sum_row(const ProceduralSpec& s, double feature, double amp, int j, int octaves, Shape shape,
                    double* out) {
  std::fill(out, out + s.width, 0.0);
  const double v = double(j) / s.height;
  std::int64_t cx = std::max<std::int64_t>(1, std::llround(s.width / feature));
  std::int64_t cy = std::max<std::int64_t>(1, std::llround(s.height / feature));
  double a = amp;
  const std::int64_t max_cells = std::max(s.width, s.height);
  for (int octave = 0; octave < octaves && std::min(cx, cy) <= max_cells; ++octave) {
    const double y = v * double(cy), fy = std::floor(y);
    const std::int64_t y0 = std::int64_t(fy);
    const double ty = quintic(y - fy);
    const auto column = [&](int i) {
      const double x = (double(i) / s.width) * double(cx), fx = std::floor(x);
      return std::pair{std::int64_t(fx), quintic(x - fx)};
    };
    const auto at = [&](std::int64_t xi, int dy) {
      return lattice_value(s.seed, octave, xi, y0 + dy, cx, cy);
    };
    add_lattice_row(s.width, a, ty, column, at, shape, out);
    a *= 0.5;
    cx *= 2;
    cy *= 2;
  }
}

double craters(const ProceduralSpec& s, double feature, double amp, int i, int j) {
  const double cell = 3 * feature;
  const std::int64_t ci = std::int64_t(std::floor(i / cell)), cj = std::int64_t(std::floor(j / cell));
  double h = 0;
  // A crater reaches at most 1.6 * 1.5 * feature < one cell from its centre: the 3x3 cells around suffice.
  for (std::int64_t dj = -1; dj <= 1; ++dj) {
    for (std::int64_t di = -1; di <= 1; ++di) {
      const std::int64_t bi = ci + di, bj = cj + dj;
      const double r0 = feature * (0.5 + hash01(s.seed, bi, bj, 1));
      const double d = amp * (0.5 + 0.5 * hash01(s.seed, bi, bj, 2));
      const double x0 = (double(bi) + hash01(s.seed, bi, bj, 3)) * cell;
      const double y0 = (double(bj) + hash01(s.seed, bi, bj, 4)) * cell;
      const double t = std::hypot(i - x0, j - y0) / r0;
      if (t < 1) {
        h += d * (t * t - 1) + d / 4;
      } else if (t < 1.6) {
        const double fall = 1 - (t - 1) / 0.6;
        h += d / 4 * fall * fall;
      }
    }
  }
  return h;
}

// One row j of rough's noise: octaves of bilinear lattice noise in [-1, 1) (not periodic) with cells of
// 64 texels down to 1, each octave 0.7 times the last. out[i] for i in [0, width), each texel's octaves
// summed in order (tests/field compares the bits with the texel-by-texel definition); the lattice values
// are hashed once per row and octave.
void rough_noise_row(std::uint64_t seed, int j, int width, double* out) {
  std::fill(out, out + width, 0.0);
  double a = 1;
  int octave = 0;
  for (int cell = 64; cell >= 1; cell /= 2, a *= 0.7, ++octave) {
    const double y = double(j) / cell;
    const std::int64_t y0 = std::int64_t(std::floor(y));
    const double ty = y - double(y0);
    const auto column = [&](int i) {
      const double x = double(i) / cell;
      const std::int64_t x0 = std::int64_t(std::floor(x));
      return std::pair{x0, x - double(x0)};
    };
    const auto at = [&](std::int64_t xi, int dy) {
      return 2.0 * hash01(seed, xi, y0 + dy, 100 + octave) - 1.0;
    };
    add_lattice_row(width, a, ty, column, at, identity_shape, out);
  }
}

// The factor that makes the median forward difference of rough_noise tan(angle_deg), from its fixed
// 256x256 window at the origin (the same for every field size and thread count).
double rough_scale(std::uint64_t seed, double angle_deg) {
  constexpr int n = 256;
  std::vector<double> z(std::size_t(n) * n);
  for (int j = 0; j < n; ++j) rough_noise_row(seed, j, n, &z[std::size_t(j) * n]);
  std::vector<double> diffs;
  diffs.reserve(std::size_t(n) * (n - 1));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i + 1 < n; ++i)
      diffs.push_back(std::abs(z[std::size_t(j) * n + i + 1] - z[std::size_t(j) * n + i]));
  std::nth_element(diffs.begin(), diffs.begin() + diffs.size() / 2, diffs.end());
  return std::tan(angle_deg * kPi / 180) / std::max(diffs[diffs.size() / 2], 1e-30);
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
  for (int k = 0; k <= int(kLastProceduralKind); ++k) {
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
    case ProceduralKind::terraces:
      return "terraces";
    case ProceduralKind::craters:
      return "craters";
    case ProceduralKind::ridges:
      return "ridges";
    case ProceduralKind::rough:
      return "rough";
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
    case ProceduralKind::terraces:
      if (feature <= 0) feature = size / 2;
      if (amp <= 0) amp = size / 16;
      break;
    case ProceduralKind::ridges:
      if (feature <= 0) feature = size / 2;
      if (amp <= 0) amp = size / 8;
      break;
    case ProceduralKind::craters:
      if (feature <= 0) feature = size / 10;
      if (amp <= 0) amp = 0.4 * feature;
      break;
    default:
      break;
  }
  const double radius = s.radius > 0 ? s.radius : size / 4;
  const double depth = s.depth > 0 ? s.depth : radius;
  const double angle_deg =
      std::isnan(s.angle_deg) ? (s.kind == ProceduralKind::rough ? 70.0 : 30.0) : s.angle_deg;
  const double tan_a = std::tan(angle_deg * deg);
  const double step = s.step > 0 ? s.step : amp / 3;
  const double rough = s.kind == ProceduralKind::rough ? rough_scale(s.seed, angle_deg) : 0.0;
  const double ax = std::cos(s.aspect_deg * deg), ay = std::sin(s.aspect_deg * deg);

  // Each texel is a pure function of (spec, i, j): rows in parallel, the same heights for any thread count.
  // The kinds made a row at a time: their noise, before the kind's own scale or steps (the others: nothing).
  const auto noise_row = [&](int j, double* out) {
    if (s.kind == ProceduralKind::fractal) octave_sum_row(s, feature, amp, j, 16, identity_shape, out);
    if (s.kind == ProceduralKind::terraces) octave_sum_row(s, feature, amp, j, 3, identity_shape, out);
    if (s.kind == ProceduralKind::ridges) octave_sum_row(s, feature, amp, j, 16, ridge_shape, out);
    if (s.kind == ProceduralKind::rough) rough_noise_row(s.seed, j, s.width, out);
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, s.height), [&](const tbb::blocked_range<int>& rows) {
    std::vector<double> row(std::size_t(s.width));  // once per range of rows, not per row
    for (int j = rows.begin(); j != rows.end(); ++j) {
      noise_row(j, row.data());
      for (int i = 0; i < s.width; ++i) {
        double h = 0;  // in texel units
        switch (s.kind) {
          case ProceduralKind::fractal:
            h = row[std::size_t(i)];
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
          case ProceduralKind::terraces:
            h = step * std::floor(row[std::size_t(i)] / step);
            break;
          case ProceduralKind::craters:
            h = craters(s, feature, amp, i, j);
            break;
          case ProceduralKind::ridges:
            h = row[std::size_t(i)];
            break;
          case ProceduralKind::rough:
            h = rough * row[std::size_t(i)];
            break;
        }
        f.z[f.index(i, j)] = float(h * texel_size);
      }
    }
  });
  return f;
}

}  // namespace hfbake
