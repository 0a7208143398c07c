#include "methods/nlp/pyramid.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace hfbake::nlp {

namespace {

double bspline3(double u) {
  u = std::abs(u);
  if (u < 1) return 2.0 / 3.0 - u * u + 0.5 * u * u * u;
  if (u < 2) return (2 - u) * (2 - u) * (2 - u) / 6;
  return 0;
}

// Grid for one axis: node count and texels per node.
void axis_grid(int n, bool repeat, double g, int& nodes, double& spacing) {
  if (repeat) {
    nodes = std::max(1, int(std::lround(n / g)));
    spacing = double(n) / nodes;
  } else {
    nodes = n <= 1 ? 1 : int(std::ceil((n - 1) / g)) + 1;
    spacing = nodes <= 1 ? 1.0 : double(n - 1) / (nodes - 1);
  }
}

// Filter weights for node positions X = a * spacing: taps[a] lists (texel, weight), weights sum to 1.
struct Taps {
  std::vector<int> start;  // offset into idx/w per node (size nodes + 1)
  std::vector<int> idx;
  std::vector<float> w;
};

Taps make_taps(int n, bool repeat, int nodes, double spacing, double s) {
  Taps t;
  t.start.push_back(0);
  for (int a = 0; a < nodes; ++a) {
    const double x = a * spacing;
    if (s <= 0) {
      int i = int(std::lround(x));
      if (repeat) i = ((i % n) + n) % n;
      t.idx.push_back(std::clamp(i, 0, n - 1));
      t.w.push_back(1);
    } else {
      const int lo = int(std::ceil(x - 2 * s)), hi = int(std::floor(x + 2 * s));
      double sum = 0;
      const std::size_t first = t.w.size();
      for (int i = lo; i <= hi; ++i) {
        if (!repeat && (i < 0 || i >= n)) continue;
        const double w = bspline3((x - i) / s);
        if (w <= 0) continue;
        t.idx.push_back(repeat ? ((i % n) + n) % n : i);
        t.w.push_back(float(w));
        sum += w;
      }
      if (sum <= 0) {  // kernel narrower than the texel spacing: nearest texel
        int i = int(std::lround(x));
        if (repeat) i = ((i % n) + n) % n;
        t.idx.push_back(std::clamp(i, 0, n - 1));
        t.w.push_back(1);
        sum = 1;
      }
      for (std::size_t k = first; k < t.w.size(); ++k) t.w[k] = float(t.w[k] / sum);
    }
    t.start.push_back(int(t.w.size()));
  }
  return t;
}

}  // namespace

double pyramid_blur(int level, int k) {
  return std::sqrt(std::max(0.0, std::pow(4.0, double(level) / k) - 1));
}

std::size_t Pyramid::bytes() const {
  std::size_t b = 0;
  for (const PyramidLevel& l : levels) b += l.data.size() * sizeof(float) + l.half.size() * 2;
  return b;
}

namespace {

std::vector<float> make_half_table() {
  std::vector<float> t(65536);
  for (std::uint32_t h = 0; h < 65536; ++h) {
    const std::uint32_t sign = (h & 0x8000u) << 16, e = (h >> 10) & 0x1f, m = h & 0x3ff;
    float v;
    if (e == 0)
      v = std::ldexp(float(m), -24);  // subnormal (and zero)
    else if (e == 31)
      v = m ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
    else
      v = std::ldexp(float(m | 0x400u), int(e) - 25);
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    bits |= sign;
    std::memcpy(&v, &bits, 4);
    t[h] = v;
  }
  return t;
}

}  // namespace

const float* half_table() {
  static const std::vector<float> table = make_half_table();
  return table.data();
}

float half_to_float(std::uint16_t h) {
  return half_table()[h];
}

std::uint16_t float_to_half(float f) {
  // IEEE 754 binary32 to binary16, rounding to nearest even, saturated first so nothing becomes infinite
  // (written out rather than _Float16, which clang before 15 does not support on x86).
  constexpr float kMax = 65504.0f;
  f = std::clamp(f, -kMax, kMax);
  std::uint32_t x;
  std::memcpy(&x, &f, 4);
  const std::uint16_t sign = std::uint16_t((x >> 16) & 0x8000u);
  x &= 0x7fffffffu;
  if (x > 0x7f800000u) return std::uint16_t(sign | 0x7e00u);  // NaN
  if (x >= 0x38800000u) {                                     // >= 2^-14: a normal half
    std::uint32_t h = (x - 0x38000000u) >> 13;                // exponent rebiased, 10 mantissa bits
    const std::uint32_t rest = x & 0x1fffu;
    if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;  // a carry moves into the exponent
    return std::uint16_t(sign | h);
  }
  if (x <= 0x33000000u) return sign;  // at most 2^-25: zero (2^-25 ties to even)
  // A subnormal half: the value in units of 2^-24 is m 2^(e - 126), m the 24-bit significand.
  const std::uint32_t e = x >> 23, m = (x & 0x7fffffu) | 0x800000u;
  const std::uint32_t shift = 126u - e;  // 14 .. 23
  std::uint32_t h = m >> shift;
  const std::uint32_t rest = m & ((1u << shift) - 1u), half = 1u << (shift - 1u);
  if (rest > half || (rest == half && (h & 1u))) ++h;
  return std::uint16_t(sign | h);
}

namespace {

// Level l's blur and grid (the one rule build_pyramid and pyramid_bytes share).
void level_grid(int l, int k, int W, int H, bool repeat, double& s, int& w, int& h, double& sx, double& sy) {
  s = l == 0 ? 0.0 : pyramid_blur(l, k);
  double g = 1;
  while (g * 2 <= s / 2) g *= 2;
  axis_grid(W, repeat, g, w, sx);
  axis_grid(H, repeat, g, h, sy);
}

}  // namespace

std::size_t pyramid_bytes(int channels, int W, int H, Wrap wrap, int k, int level_count, bool half) {
  std::size_t b = 0;
  for (int l = 0; l < std::max(1, level_count); ++l) {
    double s, sx, sy;
    int w, h;
    level_grid(l, k, W, H, wrap == Wrap::repeat, s, w, h, sx, sy);
    b += std::size_t(w) * std::size_t(h) * std::size_t(channels) * (half ? 2 : sizeof(float));
  }
  return b;
}

Pyramid build_pyramid(const float* data, int channels, int W, int H, Wrap wrap, int k, int level_count,
                      bool half) {
  Pyramid p;
  p.channels = channels;
  p.field_w = W;
  p.field_h = H;
  p.repeat = wrap == Wrap::repeat;
  p.levels_per_octave = k;
  p.levels.resize(std::max(1, level_count));
  const int c = channels;
  const std::size_t n_in = std::size_t(W) * std::size_t(H) * std::size_t(c);
  if (half) {
    // A power of two at least the largest |value| / 32768: every filtered value (a convex combination)
    // stays below half's largest finite 65504, and scaling by it is exact.
    float peak = 0;
    for (std::size_t t = 0; t < n_in; ++t)
      if (std::isfinite(data[t])) peak = std::max(peak, std::fabs(data[t]));
    p.half_scale = peak > 0 ? std::ldexp(1.0f, std::ilogb(peak) + 1 - 15) : 1.0f;
    p.half_table = half_table();
  }
  // Rounds a finished level to binary16 and frees its floats.
  auto to_half = [&](PyramidLevel& lv, const float* values) {
    lv.half.resize(std::size_t(lv.w) * lv.h * c);
    const float inv = 1.0f / p.half_scale;
    tbb::parallel_for(std::size_t(0), lv.half.size(),
                      [&](std::size_t t) { lv.half[t] = float_to_half(values[t] * inv); });
    std::vector<float>().swap(lv.data);
  };
  for (int l = 0; l < int(p.levels.size()); ++l) {
    PyramidLevel& lv = p.levels[l];
    double s, sx, sy;
    level_grid(l, k, W, H, p.repeat, s, lv.w, lv.h, sx, sy);
    lv.inv_sx = float(1 / sx);
    lv.inv_sy = float(1 / sy);
    lv.blur = s;
    if (s <= 0 && lv.w == W && lv.h == H) {
      if (half) {
        to_half(lv, data);
      } else {
        lv.data.assign(data, data + n_in);
      }
      continue;
    }
    lv.data.assign(std::size_t(lv.w) * lv.h * c, 0.0f);
    const Taps tx = make_taps(W, p.repeat, lv.w, sx, s), ty = make_taps(H, p.repeat, lv.h, sy, s);
    // Horizontal pass: every field row to lv.w nodes.
    std::vector<float> tmp(std::size_t(lv.w) * H * c, 0.0f);
    tbb::parallel_for(0, H, [&](int j) {
      const float* row = data + std::size_t(j) * W * c;
      float* out = tmp.data() + std::size_t(j) * lv.w * c;
      for (int a = 0; a < lv.w; ++a)
        for (int t = tx.start[a]; t < tx.start[a + 1]; ++t)
          for (int ch = 0; ch < c; ++ch) out[a * c + ch] += tx.w[t] * row[std::size_t(tx.idx[t]) * c + ch];
    });
    // Vertical pass.
    tbb::parallel_for(0, lv.h, [&](int b) {
      float* out = lv.data.data() + std::size_t(b) * lv.w * c;
      for (int t = ty.start[b]; t < ty.start[b + 1]; ++t) {
        const float* in = tmp.data() + std::size_t(ty.idx[t]) * lv.w * c;
        const float w = ty.w[t];
        for (int a = 0; a < lv.w * c; ++a) out[a] += w * in[a];
      }
    });
    if (half) to_half(lv, lv.data.data());
  }
  return p;
}

}  // namespace hfbake::nlp
