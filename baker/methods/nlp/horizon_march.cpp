#include "methods/nlp/horizon_march.hpp"

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

// MarchSetup::near_spacing: the knots on level 0 take the steepest slope of the samples between them and the
// knot before (at most near_spacing apart). omega holds slopes (before the arctangent), so the largest slope
// is the largest angle.
template <class Level0>
void near_maxima(const MarchSetup& s, Level0 height, float fi, float fj, float cx, float cy, float recv0,
                 int inner, float* omega) {
  float prev = 0;
  for (int k = 0; k < inner && s.level[k] == 0; prev = s.dist[k], ++k) {
    const float gap = s.dist[k] - prev;
    if (!(gap > s.near_spacing)) continue;
    const int n = int(std::ceil(gap / s.near_spacing));
    const float step = gap / float(n);
    float best = omega[k];
    for (int q = 1; q < n; ++q) {
      const float t = s.dist[k] - float(q) * step;
      best = std::max(best, (height(fi + t * cx, fj + t * cy) - recv0) / (t * s.texel_size));
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
    if (s.near_spacing > 0)
      near_maxima(
          s, [&](float x, float y) { return sample_clamped(levels[0], x, y); }, fi, fj, cx, cy, recv[0],
          inner, omega);
  } else {
    for (int k = 0; k < inner; ++k) {
      const int l = s.level[k];
      const float d = s.dist[k];
      omega[k] = (sample_level1(hp, hp.levels[l], fi + d * cx, fj + d * cy) - recv[l]) * s.inv_dist[k];
      dist[k] = d;
      lev[k] = k;
    }
    if (s.near_spacing > 0)
      near_maxima(
          s, [&](float x, float y) { return sample_level1(hp, hp.levels[0], x, y); }, fi, fj, cx, cy, recv[0],
          inner, omega);
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
