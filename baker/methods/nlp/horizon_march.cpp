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

namespace {

// A level on the field's own grid: node (i, j) is texel (i, j).
bool field_grid(const PyramidLevel& lv, const MarchSetup& s) {
  return lv.w == s.width && lv.h == s.height && lv.inv_sx == 1 && lv.inv_sy == 1;
}

// One knot (or near sample) of receiver t the way march reads it: clamped bilinear (or the triangulated
// surface) at (xs[t] + d cx, j + d cy).
inline float read_one(const MarchSetup& s, const Pyramid& hp, const PyramidLevel& lv, bool fast, bool tri,
                      float x, float y) {
  if (tri) return triangle_height(lv, s.repeat, x, y);
  return fast ? sample_clamped(lv, x, y) : sample_level1(hp, lv, x, y);
}

// Heights of the whole row at offset d (cx, cy) from each receiver, into h[t]: on a field-grid level of a
// clamp field, receivers whose four texels lie inside read them with the row's shared fraction (bilinear or
// triangle weights); the rest (and other levels) as march.
void read_row(const MarchSetup& s, const Pyramid& hp, const PyramidLevel& lv, bool fast, bool tri,
              const int* xs, int cnt, bool contiguous, int j, float d, float cx, float cy, float* h) {
  const float fj = float(j);
  int lo = 0, hi = 0;  // [lo, hi): the shared-fraction run (contiguous rows); else per receiver
  const float dx = d * cx, dy = d * cy;
  const float ox = std::floor(dx), oy = std::floor(dy), fx = dx - ox, fy = dy - oy;
  const int jo = j + int(oy), io = int(ox);
  const bool grid = fast && field_grid(lv, s) && jo >= 0 && jo <= s.height - 2;
  if (grid) {
    const int W = s.width;
    const float* r0 = lv.data.data() + std::size_t(jo) * W;
    const float* r1 = r0 + W;
    const bool upper = tri && facet_of(fx, fy) == 1;
    auto value = [&](int i) {
      if (tri) {
        if (!upper) return r0[i] + (r0[i + 1] - r0[i]) * fx + (r1[i] - r0[i]) * fy;
        return r1[i + 1] + (r1[i] - r1[i + 1]) * (1 - fx) + (r0[i + 1] - r1[i + 1]) * (1 - fy);
      }
      const float a = r0[i] + (r0[i + 1] - r0[i]) * fx;
      const float b = r1[i] + (r1[i + 1] - r1[i]) * fx;
      return a + (b - a) * fy;
    };
    if (contiguous) {
      const int base = xs[0] + io;  // texel of receiver t: base + t
      lo = std::clamp(-base, 0, cnt);
      hi = std::clamp(W - 1 - base, lo, cnt);
      const int b = base;
      if (tri && !upper) {
        for (int t = lo; t < hi; ++t)
          h[t] = r0[b + t] + (r0[b + t + 1] - r0[b + t]) * fx + (r1[b + t] - r0[b + t]) * fy;
      } else if (tri) {
        for (int t = lo; t < hi; ++t)
          h[t] = r1[b + t + 1] + (r1[b + t] - r1[b + t + 1]) * (1 - fx) +
                 (r0[b + t + 1] - r1[b + t + 1]) * (1 - fy);
      } else {
        for (int t = lo; t < hi; ++t) {
          const float a = r0[b + t] + (r0[b + t + 1] - r0[b + t]) * fx;
          const float c = r1[b + t] + (r1[b + t + 1] - r1[b + t]) * fx;
          h[t] = a + (c - a) * fy;
        }
      }
    } else {
      for (int t = 0; t < cnt; ++t) {
        const int i = xs[t] + io;
        h[t] = i >= 0 && i <= W - 2 ? value(i) : read_one(s, hp, lv, fast, tri, float(xs[t]) + dx, fj + dy);
      }
      return;
    }
  }
  for (int t = 0; t < lo; ++t) h[t] = read_one(s, hp, lv, fast, tri, float(xs[t]) + dx, fj + dy);
  for (int t = std::max(hi, lo); t < cnt; ++t)
    h[t] = read_one(s, hp, lv, fast, tri, float(xs[t]) + dx, fj + dy);
}

}  // namespace

void march_row(const MarchSetup& s, const Pyramid& hp, const int* xs, int cnt, bool contiguous, int j,
               float cx, float cy, const float* recv, int rs, RowMarch& out) {
  const float inf = std::numeric_limits<float>::infinity();
  const float inv_ts = 1 / s.texel_size, fj = float(j);
  const bool fast = !s.repeat && s.width >= 2 && s.height >= 2;
  out.max_n = 0;
  for (int t = 0; t < cnt; ++t) {
    int n = s.steps;
    float t_exit = inf;
    if (!s.repeat) {
      const int i = xs[t];
      const float eps = 1e-6f;
      if (cx > eps) t_exit = std::min(t_exit, (s.width - 1 - i) / cx);
      if (cx < -eps) t_exit = std::min(t_exit, -i / cx);
      if (cy > eps) t_exit = std::min(t_exit, (s.height - 1 - j) / cy);
      if (cy < -eps) t_exit = std::min(t_exit, -j / cy);
      if (t_exit < 1e-4f) {
        out.n[t] = 0;
        out.exit[t] = inf;
        continue;
      }
      const int inner = int(std::lower_bound(s.dist.begin(), s.dist.end(), t_exit) - s.dist.begin());
      n = inner < s.steps ? inner + 1 : inner;
      if (inner == s.steps) t_exit = inf;
    }
    out.n[t] = n;
    out.exit[t] = t_exit;
    out.max_n = std::max(out.max_n, n);
  }
  float* tmp = out.tmp.data();
  float prev = 0;
  for (int k = 0; k < out.max_n; prev = s.dist[k], ++k) {
    const int l = s.level[k];
    const PyramidLevel& lv = hp.levels[l];
    const float d = s.dist[k];
    float* om = out.omega.data() + std::size_t(k) * out.stride;
    const float* rl = recv + std::size_t(l) * rs;
    const bool near = s.near_spacing > 0 && l == 0;
    read_row(s, hp, lv, fast, near, xs, cnt, contiguous, j, d, cx, cy, om);
    for (int t = 0; t < cnt; ++t) om[t] = (om[t] - rl[t]) * s.inv_dist[k];
    if (near) {  // MarchSetup::near_spacing: the steepest of the samples between the knot before and this one
      const float gap = d - prev;
      const int q_n = gap > s.near_spacing ? int(std::ceil(gap / s.near_spacing)) : 1;
      const float step = gap / float(q_n);
      for (int q = 1; q < q_n; ++q) {
        const float tq = d - float(q) * step, inv = 1 / (tq * s.texel_size);
        read_row(s, hp, lv, fast, true, xs, cnt, contiguous, j, tq, cx, cy, tmp);
        for (int t = 0; t < cnt; ++t) om[t] = std::max(om[t], (tmp[t] - rl[t]) * inv);
      }
    }
  }
  for (int t = 0; t < cnt; ++t) {  // the border knots
    if (!(out.exit[t] < inf)) continue;
    const int k = out.n[t] - 1, l = s.level[k];
    const float d = out.exit[t], x = float(xs[t]) + d * cx, y = fj + d * cy;
    const float h = fast ? sample_clamped(hp.levels[l], x, y) : sample_level1(hp, hp.levels[l], x, y);
    out.omega[std::size_t(k) * out.stride + t] = (h - recv[std::size_t(l) * rs + t]) * (inv_ts / d);
  }
}

void row_angles(RowMarch& r, int cnt) {
  for (int k = 0; k < r.max_n; ++k) {
    float* om = r.omega.data() + std::size_t(k) * r.stride;
    for (int t = 0; t < cnt; ++t) om[t] = fast_atan(om[t]);
  }
}

void row_knot_max(const RowMarch& r, int cnt, float* out) {
  float* __restrict o = out;
  const int* __restrict n = r.n.data();
  for (int t = 0; t < cnt; ++t) o[t] = -std::numeric_limits<float>::infinity();
  for (int k = 0; k < r.max_n; ++k) {
    const float* __restrict om = r.omega.data() + std::size_t(k) * r.stride;
    for (int t = 0; t < cnt; ++t) {
      const float v = om[t], cur = o[t];
      o[t] = ((k < n[t]) & (v > cur)) ? v : cur;
    }
  }
  for (int t = 0; t < cnt; ++t) out[t] = fast_atan(out[t]);
}

}  // namespace hfbake::nlp
