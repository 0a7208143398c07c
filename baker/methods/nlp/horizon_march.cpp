#include "methods/nlp/horizon_march.hpp"

#include <algorithm>
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
  const float inv_ts = 1 / s.texel_size;
  int n = 0;
  for (int k = 0; k < s.steps; ++k) {
    float d = s.dist[k];
    const bool last = d >= t_exit;
    if (last) d = t_exit;
    const int l = s.level[k];
    const float h = sample_level1(hp, hp.levels[l], i + d * cx, j + d * cy);
    omega[n] = fast_atan((h - recv[l]) * inv_ts / d);
    dist[n] = d;
    lev[n] = k;
    ++n;
    if (last) break;
  }
  return n;
}

}  // namespace hfbake::nlp
