// Multiresolution pyramids of NS09 §5.2-5.3 (after Snyder & Nowrouzezahrai 2008): the height pyramid f_l
// and the radiance pyramid of each bounce, k levels per octave.
//
// Level l holds the field filtered with a 2D separable cubic B-spline of scale s_l = sqrt(4^(l/k) - 1)
// texels: with the field itself counted as a unit-spacing B-spline, level l has the resolution of a B-spline
// synthesised from samples 2^(l/k) texels apart (NS09: "reduces resolution by a factor of 2^(1/k) per
// level"), and level 0 is the field itself. Rather than a full-resolution stack per level (NS09 §9, 4 x more
// memory per octave), each level is stored on its own grid with spacing g_l = the largest power of two <= s_l
// / 2 (at least 1 texel), and read bilinearly between grid nodes; about 11 x field memory for k = 4, whatever
// the level count (a full-resolution stack costs n_v x). Clamp mode renormalises the kernel inside the field;
// repeat mode filters periodically.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "field/height_field.hpp"

namespace hfbake::nlp {

struct PyramidLevel {
  int w = 0, h = 0;                 // grid nodes
  float inv_sx = 1, inv_sy = 1;     // grid nodes per texel (texel coordinate x -> node coordinate x * inv_sx)
  double blur = 0;                  // kernel scale s_l in texels
  std::vector<float> data;          // row-major, `channels` interleaved (empty when the pyramid is half)
  std::vector<std::uint16_t> half;  // Pyramid::half_scale > 0: the same as binary16 of value / half_scale
};

struct Pyramid {
  int channels = 1;
  int field_w = 0, field_h = 0;
  bool repeat = false;
  int levels_per_octave = 4;
  std::vector<PyramidLevel> levels;
  // > 0: the levels are held as binary16 (PyramidLevel::half) of value / half_scale, a power of two chosen
  // from the largest value so nothing overflows: half the memory, relative rounding <= 2^-11.
  float half_scale = 0;
  // half_scale > 0: binary16 -> float for all 65536 values (half_to_float's table), read inline by
  // sample_level.
  const float* half_table = nullptr;

  std::size_t bytes() const;
};

// binary16 -> float (exact), and float -> binary16 rounded to nearest even (overflow saturates to the largest
// finite value).
float half_to_float(std::uint16_t h);
// The table half_to_float reads (65536 floats, built once).
const float* half_table();
std::uint16_t float_to_half(float f);

double pyramid_blur(int level, int levels_per_octave);

// data: field_w x field_h texels, `channels` interleaved. level_count >= 1. half: hold the levels as
// binary16 (Pyramid::half_scale; each level filtered in float, then rounded once).
Pyramid build_pyramid(const float* data, int channels, int field_w, int field_h, Wrap wrap,
                      int levels_per_octave, int level_count, bool half = false);

// Bytes build_pyramid allocates for these arguments (its levels), without building it: for estimates.
std::size_t pyramid_bytes(int channels, int field_w, int field_h, Wrap wrap, int levels_per_octave,
                          int level_count, bool half = false);

// Bilinear read of level `lv` at texel coordinates (x, y) (x = i at texel centers), `channels` values to out.
// Clamp: coordinates are clamped to the field. Repeat: the level tiles.
inline void sample_level(const Pyramid& p, const PyramidLevel& lv, float x, float y, float* out) {
  float u = x * lv.inv_sx, v = y * lv.inv_sy;
  int i0, j0, i1, j1;
  float fu, fv;
  if (p.repeat) {
    u -= std::floor(u / lv.w) * lv.w;
    v -= std::floor(v / lv.h) * lv.h;
    const float fi = std::floor(u), fj = std::floor(v);
    fu = u - fi, fv = v - fj;
    i0 = int(fi), j0 = int(fj);
    if (i0 >= lv.w) i0 -= lv.w;
    if (j0 >= lv.h) j0 -= lv.h;
    i1 = i0 + 1 == lv.w ? 0 : i0 + 1;
    j1 = j0 + 1 == lv.h ? 0 : j0 + 1;
  } else {
    u = u < 0 ? 0 : (u > lv.w - 1 ? float(lv.w - 1) : u);
    v = v < 0 ? 0 : (v > lv.h - 1 ? float(lv.h - 1) : v);
    const float fi = std::floor(u), fj = std::floor(v);
    i0 = int(fi), j0 = int(fj);
    fu = u - fi, fv = v - fj;
    i1 = i0 + 1 < lv.w ? i0 + 1 : i0;
    j1 = j0 + 1 < lv.h ? j0 + 1 : j0;
  }
  const int c = p.channels;
  if (p.half_scale > 0) {
    const float* lut = p.half_table;
    const std::uint16_t* r0 = lv.half.data() + std::size_t(j0) * lv.w * c;
    const std::uint16_t* r1 = lv.half.data() + std::size_t(j1) * lv.w * c;
    for (int k = 0; k < c; ++k) {
      const float a00 = lut[r0[i0 * c + k]], a10 = lut[r0[i1 * c + k]];
      const float a01 = lut[r1[i0 * c + k]], a11 = lut[r1[i1 * c + k]];
      const float a = a00 + (a10 - a00) * fu, b = a01 + (a11 - a01) * fu;
      out[k] = (a + (b - a) * fv) * p.half_scale;
    }
    return;
  }
  const float* r0 = lv.data.data() + std::size_t(j0) * lv.w * c;
  const float* r1 = lv.data.data() + std::size_t(j1) * lv.w * c;
  for (int k = 0; k < c; ++k) {
    const float a = r0[i0 * c + k] + (r0[i1 * c + k] - r0[i0 * c + k]) * fu;
    const float b = r1[i0 * c + k] + (r1[i1 * c + k] - r1[i0 * c + k]) * fu;
    out[k] = a + (b - a) * fv;
  }
}

inline float sample_level1(const Pyramid& p, const PyramidLevel& lv, float x, float y) {
  float v;
  sample_level(p, lv, x, y, &v);
  return v;
}

}  // namespace hfbake::nlp
