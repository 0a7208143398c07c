#include "methods/nlp/horizon_march.hpp"

#include "field/triangulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hfbake::nlp {

MarchSetup make_march_setup(int W, int H, double texel_size, Wrap wrap, int k, int ov, int ou) {
  MarchSetup s;
  s.repeat = wrap == Wrap::repeat;
  s.width = W;
  s.height = H;
  s.texel_size = float(texel_size);
  const double dmax =
      std::max(1.0, s.repeat ? double(std::max(W, H)) : std::hypot(double(W - 1), double(H - 1)));
  s.steps = int(std::ceil(k * std::log2(dmax) - 1e-9)) + 1;
  const int lv = std::max(1, s.steps - k * ov), lu = std::max(1, s.steps - k * ou);
  for (int i = 0; i < s.steps; ++i) {
    s.dist.push_back(float(std::exp2(double(i) / k)));
    s.inv_dist.push_back(float(1 / (std::exp2(double(i) / k) * texel_size)));
    s.level.push_back(std::clamp(i - k * ov, 0, lv - 1));
    s.rlevel.push_back(std::clamp(i - k * ou, 0, lu - 1));
  }
  return s;
}

int height_levels(const MarchSetup& s) {
  return s.level.empty() ? 1 : s.level.back() + 1;
}
int radiance_levels(const MarchSetup& s) {
  return s.rlevel.empty() ? 1 : s.rlevel.back() + 1;
}

namespace {

// Bilinear read of a clamp-mode level with at least 2 x 2 nodes (coordinates clamped; no floor needed).
inline float sample_clamped(const PyramidLevel& lv, float x, float y) {
  float u = x * lv.inv_sx, v = y * lv.inv_sy;
  const float umax = float(lv.w - 1), vmax = float(lv.h - 1);
  u = u < 0 ? 0 : (u > umax ? umax : u);
  v = v < 0 ? 0 : (v > vmax ? vmax : v);
  int i0 = int(u), j0 = int(v);
  if (i0 > lv.w - 2) i0 = lv.w - 2;
  if (j0 > lv.h - 2) j0 = lv.h - 2;
  const float fu = u - float(i0), fv = v - float(j0);
  const float* r0 = lv.data.data() + std::size_t(j0) * lv.w + i0;
  const float* r1 = r0 + lv.w;
  const float a = r0[0] + (r0[1] - r0[0]) * fu;
  const float b = r1[0] + (r1[1] - r1[0]) * fu;
  return a + (b - a) * fv;
}

// The triangulated surface (field/triangulation.hpp, the reference's) over level 0, which is the field
// itself: its height at texel coordinates (x, y), clamped to the field or tiled.
float triangle_height(const PyramidLevel& lv, bool repeat, float x, float y) {
  if (repeat) {
    x -= std::floor(x / lv.w) * lv.w;
    y -= std::floor(y / lv.h) * lv.h;
  } else {
    x = std::clamp(x, 0.0f, float(lv.w - 1));
    y = std::clamp(y, 0.0f, float(lv.h - 1));
  }
  const int i = std::min(int(x), lv.w - 1), j = std::min(int(y), lv.h - 1);
  auto at = [&](int di, int dj) {
    int ii = i + di, jj = j + dj;
    if (repeat) {
      ii = ii == lv.w ? 0 : ii;
      jj = jj == lv.h ? 0 : jj;
    } else {
      ii = std::min(ii, lv.w - 1);
      jj = std::min(jj, lv.h - 1);
    }
    return lv.data[std::size_t(jj) * lv.w + ii];
  };
  return facet_height(x - float(i), y - float(j), at);
}

// MarchSetup::near_spacing: the knots on level 0 read the triangulated surface (bilinear heights bulge where
// a march runs along a facet edge, and near the receiver that bulge is a steep false occluder) and take the
// steepest slope of the samples between them and the knot before (at most near_spacing apart). omega holds
// slopes (before the arctangent), so the largest slope is the largest angle.
void near_maxima(const MarchSetup& s, const PyramidLevel& lv, bool repeat, float fi, float fj, float cx,
                 float cy, float recv0, int inner, float* omega) {
  float prev = 0;
  for (int k = 0; k < inner && s.level[k] == 0; prev = s.dist[k], ++k) {
    const float d = s.dist[k], gap = d - prev;
    float best = (triangle_height(lv, repeat, fi + d * cx, fj + d * cy) - recv0) / (d * s.texel_size);
    const int n = gap > s.near_spacing ? int(std::ceil(gap / s.near_spacing)) : 1;
    const float step = gap / float(n);
    for (int q = 1; q < n; ++q) {
      const float t = d - float(q) * step;
      best = std::max(best,
                      (triangle_height(lv, repeat, fi + t * cx, fj + t * cy) - recv0) / (t * s.texel_size));
    }
    omega[k] = best;
  }
}

}  // namespace

int march(const MarchSetup& s, const Pyramid& hp, int i, int j, float cx, float cy, const float* recv,
          float* omega, float* dist, int* lev) {
  float t_exit = std::numeric_limits<float>::infinity();
  if (!s.repeat) {
    const float eps = 1e-6f;
    if (cx > eps) t_exit = std::min(t_exit, (s.width - 1 - i) / cx);
    if (cx < -eps) t_exit = std::min(t_exit, -i / cx);
    if (cy > eps) t_exit = std::min(t_exit, (s.height - 1 - j) / cy);
    if (cy < -eps) t_exit = std::min(t_exit, -j / cy);
    if (t_exit < 1e-4f) return 0;
  }
  const float inv_ts = 1 / s.texel_size, fi = float(i), fj = float(j);
  // Knots 0..inner-1 lie inside the field; knot `inner` (if any) is the last, moved onto the border.
  int inner = 0;
  while (inner < s.steps && !(s.dist[inner] >= t_exit)) ++inner;
  const bool fast = !s.repeat && s.width >= 2 && s.height >= 2;
  if (fast) {
    const PyramidLevel* levels = hp.levels.data();
    for (int k = 0; k < inner; ++k) {
      const int l = s.level[k];
      const float d = s.dist[k];
      omega[k] = (sample_clamped(levels[l], fi + d * cx, fj + d * cy) - recv[l]) * s.inv_dist[k];
      dist[k] = d;
      lev[k] = k;
    }
    if (s.near_spacing > 0) near_maxima(s, levels[0], false, fi, fj, cx, cy, recv[0], inner, omega);
  } else {
    for (int k = 0; k < inner; ++k) {
      const int l = s.level[k];
      const float d = s.dist[k];
      omega[k] = (sample_level1(hp, hp.levels[l], fi + d * cx, fj + d * cy) - recv[l]) * s.inv_dist[k];
      dist[k] = d;
      lev[k] = k;
    }
    if (s.near_spacing > 0) near_maxima(s, hp.levels[0], s.repeat, fi, fj, cx, cy, recv[0], inner, omega);
  }
  int n = inner;
  if (inner < s.steps) {  // the border knot (clamp only: t_exit is infinite in repeat mode)
    const int l = s.level[inner];
    const float d = t_exit, inv = inv_ts / t_exit;
    const PyramidLevel& lv = hp.levels[l];
    const float x = fi + d * cx, y = fj + d * cy;
    const float h = fast ? sample_clamped(lv, x, y) : sample_level1(hp, lv, x, y);
    omega[n] = (h - recv[l]) * inv;
    dist[n] = d;
    lev[n] = inner;
    ++n;
  }
  for (int k = 0; k < n; ++k) omega[k] = fast_atan(omega[k]);
  return n;
}

}  // namespace hfbake::nlp
