#include "methods/p1/lane_horizons.hpp"

#include <emmintrin.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "core/instruction_set.hpp"
#include "methods/p1/horizon_sweep.hpp"

namespace hfbake::p1 {

namespace {

inline float fmax_(float a, float b) {
  return a > b ? a : b;
}

// Eight lanes as two SSE2 registers (every x86-64 has them); lane_kernel.inc pairs them up to kLanes.
struct Sse2 {
  static constexpr int kWidth = 8;
  struct F {
    __m128 lo, hi;
  };
  struct I {
    __m128i lo, hi;
  };
  using M = F;
  static F load(const float* p) { return {_mm_loadu_ps(p), _mm_loadu_ps(p + 4)}; }
  static void store(float* p, F a) { _mm_storeu_ps(p, a.lo), _mm_storeu_ps(p + 4, a.hi); }
  static void storei(std::int32_t* p, I a) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(p), a.lo);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(p + 4), a.hi);
  }
  static F set1(float x) { return {_mm_set1_ps(x), _mm_set1_ps(x)}; }
  static I seti(std::int32_t x) { return {_mm_set1_epi32(x), _mm_set1_epi32(x)}; }
  static F add(F a, F b) { return {_mm_add_ps(a.lo, b.lo), _mm_add_ps(a.hi, b.hi)}; }
  static F sub(F a, F b) { return {_mm_sub_ps(a.lo, b.lo), _mm_sub_ps(a.hi, b.hi)}; }
  static F mul(F a, F b) { return {_mm_mul_ps(a.lo, b.lo), _mm_mul_ps(a.hi, b.hi)}; }
  static F max(F a, F b) { return {_mm_max_ps(a.lo, b.lo), _mm_max_ps(a.hi, b.hi)}; }
  static F gt(F a, F b) { return {_mm_cmpgt_ps(a.lo, b.lo), _mm_cmpgt_ps(a.hi, b.hi)}; }
  static F sel(F m, F a, F b) {
    return {_mm_or_ps(_mm_and_ps(m.lo, a.lo), _mm_andnot_ps(m.lo, b.lo)),
            _mm_or_ps(_mm_and_ps(m.hi, a.hi), _mm_andnot_ps(m.hi, b.hi))};
  }
  static I seli(F m, I a, I b) {
    const __m128i lo = _mm_castps_si128(m.lo), hi = _mm_castps_si128(m.hi);
    return {_mm_or_si128(_mm_and_si128(lo, a.lo), _mm_andnot_si128(lo, b.lo)),
            _mm_or_si128(_mm_and_si128(hi, a.hi), _mm_andnot_si128(hi, b.hi))};
  }
  static bool any(F m) { return _mm_movemask_ps(_mm_or_ps(m.lo, m.hi)) != 0; }
  static F or_(F a, F b) { return {_mm_or_ps(a.lo, b.lo), _mm_or_ps(a.hi, b.hi)}; }
};

#include "methods/p1/lane_kernel.inc"

}  // namespace

namespace {

// Where f lies in its tiling (tiled_shape): texel (i0, j0) of it is f's (0, 0); and the tiling's shape.
void tiled_frame(int width, int height, bool xm, int periods, int* i0, int* j0, int* tw, int* th) {
  const long major = xm ? width : height, minor = xm ? height : width;
  // Across the major axis: a ray's drift over its span ((periods + 1) major periods, |g| <= 1) and the
  // texels its crossings read either side of its line (at most 2 kLaneWindow, LaneDirection::build).
  const long across = (long(periods) + 1) * major + 2 * kLaneWindow + 2;
  const long along = long(periods) * major;
  const long tmaj = 2 * along + major, tmin = 2 * across + minor;
  if (tmaj > 1L << 30 || tmin > 1L << 30)
    throw std::length_error("lane search: a repeat field's tiling is too large");
  *i0 = int(xm ? along : across), *j0 = int(xm ? across : along);
  *tw = int(xm ? tmaj : tmin), *th = int(xm ? tmin : tmaj);
}

}  // namespace

double tiled_texels(int width, int height, bool xm, int periods) {
  int i0, j0, tw, th;
  tiled_frame(width, height, xm, periods, &i0, &j0, &tw, &th);
  return double(tw) * double(th);
}

bool lane_tiles(int width, int height, Wrap wrap, int periods) {
  if (wrap == Wrap::clamp) return true;
  return std::max(tiled_texels(width, height, true, periods), tiled_texels(width, height, false, periods)) <=
         kTiledTexels;
}

double lane_layout_bytes(int width, int height, Wrap wrap, int periods) {
  if (wrap == Wrap::clamp)  // heights and window maxima, padded on the minor axis
    return 2.0 * 4.0 * double(std::max(width, height)) * double(std::min(width, height) + 2 * kLanePad);
  return 8.0 *
         std::max(tiled_texels(width, height, true, periods), tiled_texels(width, height, false, periods));
}

HeightField tiled_shape(const HeightField& f, bool xm, int periods) {
  int i0, j0, tw, th;
  tiled_frame(f.width, f.height, xm, periods, &i0, &j0, &tw, &th);
  HeightField t;
  static_cast<FieldShape&>(t) = f;
  t.width = tw, t.height = th, t.wrap = Wrap::clamp;
  return t;
}

namespace {

// Builds L from the heights of a width x height field whose texels [ib, ie) of row j rows(j, ib, ie, out)
// writes to out (LaneLayout::build: a field's own; build_tiled: a repeat field's tiling, never held whole).
template <class Rows>
void build_rows(LaneLayout& L, int width, int height, bool xm, const Rows& rows) {
  L.x_major = xm;
  L.nmajor = xm ? width : height;
  L.nminor = xm ? height : width;
  L.recv_u0 = 0, L.recv_u1 = L.nmajor, L.recv_v0 = 0, L.recv_v1 = L.nminor;
  L.out_i0 = 0, L.out_j0 = 0, L.out_width = width;
  const std::ptrdiff_t stride = L.stride = L.nminor + 2 * kLanePad;
  const int nmajor = L.nmajor, nminor = L.nminor;
  L.size = std::size_t(nmajor) * std::size_t(stride);
  // A layout built again (the other axis of the same field, LaneReuse) writes into the buffers it holds
  // when they are large enough: fresh pages cost a fault each on a VM (core/page_buffer.hpp). Else they
  // are freed before the larger ones are taken.
  if (L.capacity < L.size) {
    L.z.reset(), L.window.reset(), L.capacity = 0;
    L.z = make_page_buffer<float>(L.size);
    L.window = make_page_buffer<float>(L.size);
    L.capacity = L.size;
  }
  L.tilt0 = 0, L.tilt_major = 0, L.tilt_minor = 0;
  float* z = L.z.get();
  // The layout's rows (major indices) in parallel, a run of them at a time: for x_major, each field row's
  // piece across the run read once and spread over the run's rows.
  tbb::parallel_for(tbb::blocked_range<int>(0, nmajor, 64), [&](const tbb::blocked_range<int>& run) {
    for (int u = run.begin(); u < run.end(); ++u) {
      float* row = z + std::ptrdiff_t(u) * stride;
      std::fill(row, row + kLanePad, kOffField);
      std::fill(row + kLanePad + nminor, row + stride, kOffField);
      if (!xm) rows(u, 0, width, row + kLanePad);
    }
    if (xm) {
      constexpr int kPiece = 64;  // a blocked_range's run may exceed its grain size
      float piece[kPiece];
      for (int u0 = run.begin(); u0 < run.end(); u0 += kPiece) {
        const int u1 = std::min(run.end(), u0 + kPiece);
        for (int j = 0; j < height; ++j) {
          rows(j, u0, u1, piece);
          for (int u = u0; u < u1; ++u)
            z[std::size_t(u) * std::size_t(stride) + kLanePad + j] = piece[u - u0];
        }
      }
    }
  });
  // The heights less an offset, the middle of their range, where every difference is exact (a float z
  // minus a float near it): a crossing's rise (va - z0) + (vb - va) w takes the same values, bit for bit,
  // from either, while the bounds' roundings (the margins below and in lane_kernel.inc) scale with the
  // largest |z| held, the relief instead of the altitude (a plateau 8000 m up searched as fast as one at
  // sea level). Where some difference would round (heights spanning several binades), no offset.
  {
    // Each row's range in parallel, then the rows' in order.
    std::vector<float> row_lo(static_cast<std::size_t>(nmajor)), row_hi(static_cast<std::size_t>(nmajor));
    tbb::parallel_for(0, nmajor, [&](int u) {
      const float* row = z + std::ptrdiff_t(u) * stride + kLanePad;
      float a = std::numeric_limits<float>::infinity(), b = -a;
      for (int v = 0; v < nminor; ++v) a = std::min(a, row[v]), b = std::max(b, row[v]);
      row_lo[std::size_t(u)] = a, row_hi[std::size_t(u)] = b;
    });
    const float lo = *std::min_element(row_lo.begin(), row_lo.end());
    const float hi = *std::max_element(row_hi.begin(), row_hi.end());
    const float off = std::isfinite(lo) && std::isfinite(hi) ? float(0.5 * (double(lo) + double(hi))) : 0.0f;
    std::atomic<bool> exact{off != 0};
    if (exact)
      tbb::parallel_for(0, nmajor, [&](int u) {
        const float* row = z + std::ptrdiff_t(u) * stride + kLanePad;
        for (int v = 0; v < nminor && exact.load(std::memory_order_relaxed); ++v)
          if (double(row[v] - off) != double(row[v]) - double(off)) exact = false;
      });
    if (exact)
      tbb::parallel_for(0, nmajor, [&](int u) {
        float* row = z + std::ptrdiff_t(u) * stride + kLanePad;
        for (int v = 0; v < nminor; ++v) row[v] -= off;
      });
  }
  // The field's least-squares plane, tilt0 + tilt_major * u + tilt_minor * v at major index u, minor index
  // v (on a whole grid the two slopes are independent sums), and its largest |z|: each row's sums in
  // parallel (read back from the layout), added in row order (the same bits for any thread count).
  L.zabs = 0;
  {
    const double mi = 0.5 * double(width - 1), mj = 0.5 * double(height - 1);
    std::vector<double> row_z(static_cast<std::size_t>(height)), row_iz(static_cast<std::size_t>(height));
    std::vector<float> row_abs(static_cast<std::size_t>(height));
    tbb::parallel_for(0, height, [&](int j) {
      // Texel (i, j) of the field: z[u * stride + kLanePad + v] with (u, v) = (i, j) if x_major, else (j, i).
      const float* at = z + kLanePad + (xm ? std::ptrdiff_t(j) : std::ptrdiff_t(j) * stride);
      const std::ptrdiff_t step = xm ? stride : 1;
      double rz = 0, riz = 0;
      float a = 0;
      for (int i = 0; i < width; ++i) {
        const float v = at[std::ptrdiff_t(i) * step];
        rz += double(v), riz += (double(i) - mi) * double(v);
        a = fmax_(a, std::fabs(v));
      }
      row_z[std::size_t(j)] = rz, row_iz[std::size_t(j)] = riz, row_abs[std::size_t(j)] = a;
    });
    double sz = 0, siz = 0, sjz = 0;
    for (int j = 0; j < height; ++j) {
      const double rz = row_z[std::size_t(j)];
      sz += rz, siz += row_iz[std::size_t(j)], sjz += (double(j) - mj) * rz;
      L.zabs = fmax_(L.zabs, row_abs[std::size_t(j)]);
    }
    const double n = double(width) * double(height);
    // sum over the grid of (i - mi)^2 is height * w (w^2 - 1) / 12, and of (j - mj)^2 width * h (h^2 - 1)
    // / 12.
    const double w = double(width), h = double(height);
    const double a = width > 1 ? siz / (h * w * (w * w - 1) / 12) : 0.0;
    const double b = height > 1 ? sjz / (w * h * (h * h - 1) / 12) : 0.0;
    const double c = sz / n - a * mi - b * mj;
    if (std::isfinite(a) && std::isfinite(b) && std::isfinite(c)) {
      L.tilt0 = c;
      L.tilt_major = xm ? a : b;
      L.tilt_minor = xm ? b : a;
    }
  }
  // window[at] = the highest of z less the plane over [at, at + kLaneWindow) within the major index's row
  // (kOffField past its end), raised by more than a crossing's rounding and the plane's: a crossing's height,
  // (1 - w) z[a] + w z[b] evaluated in floats, can exceed both heights by a few units in the last place of
  // the field's largest |z|. So every bound is at least every slope it bounds as the search evaluates them,
  // and the search's slope is the largest of all its crossings' (however the texels are grouped and the
  // blocks ordered).
  double pabs = 0;  // the plane's largest |value| on the field (at a corner)
  for (const double u : {0.0, double(nmajor - 1)})
    for (const double v : {0.0, double(nminor - 1)})
      pabs = std::max(pabs, std::fabs(L.tilt0 + L.tilt_major * u + L.tilt_minor * v));
  L.plane_abs = float(pabs);
  const float margin = (L.zabs + L.plane_abs) * 0x1p-20f;
  tbb::parallel_for(tbb::blocked_range<int>(0, nmajor, 64), [&](const tbb::blocked_range<int>& run) {
    std::vector<float> level(static_cast<std::size_t>(stride));  // a row of z less the plane
    for (int u = run.begin(); u < run.end(); ++u) {
      const float* r = z + std::ptrdiff_t(u) * stride;
      float* w = L.window.get() + std::ptrdiff_t(u) * stride;
      const double pu = L.tilt0 + L.tilt_major * double(u);
      for (std::ptrdiff_t i = 0; i < stride; ++i)
        level[std::size_t(i)] =
            r[i] == kOffField ? kOffField : r[i] - float(pu + L.tilt_minor * double(i - kLanePad));
      for (std::ptrdiff_t i = 0; i < stride; ++i) {
        float m = kOffField;
        for (std::ptrdiff_t t = i; t < std::min<std::ptrdiff_t>(stride, i + kLaneWindow); ++t)
          m = fmax_(m, level[std::size_t(t)]);
        w[i] = m == kOffField ? kOffField : m + margin;
      }
    }
  });
}

}  // namespace

void LaneLayout::build(const HeightField& f, bool xm) {
  build_rows(*this, f.width, f.height, xm, [&](int j, int ib, int ie, float* out) {
    std::copy(f.z.data() + f.index(ib, j), f.z.data() + f.index(ie, j), out);
  });
}

void LaneLayout::build_tiled(const HeightField& f, bool xm, int periods) {
  int i0, j0, tw, th;
  tiled_frame(f.width, f.height, xm, periods, &i0, &j0, &tw, &th);
  const int W = f.width, H = f.height;
  // Texels [ib, ie) of the tiling's row j: runs of f's row (j - j0) mod H from column (ib - i0) mod W.
  build_rows(*this, tw, th, xm, [&](int j, int ib, int ie, float* out) {
    const float* row = f.z.data() + f.index(0, (((j - j0) % H) + H) % H);
    int i = ib, src = (((ib - i0) % W) + W) % W;
    while (i < ie) {
      const int n = std::min(ie - i, W - src);
      std::copy(row + src, row + src + n, out + (i - ib));
      i += n, src = 0;
    }
  });
  recv_u0 = xm ? i0 : j0, recv_u1 = recv_u0 + (xm ? f.width : f.height);
  recv_v0 = xm ? j0 : i0, recv_v1 = recv_v0 + (xm ? f.height : f.width);
  out_i0 = i0, out_j0 = j0, out_width = f.width;
}

namespace {
double run_of(const LaneDirection& d) {
  if (d.crossings.empty()) return 0.0;
  return 1.0 / (double(d.crossings.back().inv_s) * double(d.major.back()));
}
}  // namespace

void LaneDirection::build(const HeightField& f, const LaneLayout& L, double dx, double dy, double curvature) {
  x_major = L.x_major;
  const double dmaj = x_major ? dx : dy, dmin = x_major ? dy : dx;
  su = dmaj >= 0 ? 1 : -1;
  g = dmin / dmaj;
  const double radius = std::hypot(double(f.width), double(f.height)) + 2;
  const std::vector<NearCrossing> cs = near_field_stencil(dx, dy, radius, f.texel_size);
  crossings.clear();
  crossings.reserve(cs.size());
  major.clear();
  curved = curvature != 0;
  end_below = curvature >= 0;
  e_lo = 0, e_hi = 0;
  // Each crossing's nearest and farthest column read (major distances in texels: a crossing a hair past a
  // column reads the next one, with a weight of that hair).
  std::vector<int> near_col, far_col;
  near_col.reserve(cs.size()), far_col.reserve(cs.size());
  for (const NearCrossing& c : cs) {
    const int amaj = x_major ? c.ai : c.aj, amin = x_major ? c.aj : c.ai;
    const int bmaj = x_major ? c.bi : c.bj, bmin = x_major ? c.bj : c.bi;
    crossings.push_back({std::ptrdiff_t(amaj) * L.stride + amin, std::ptrdiff_t(bmaj) * L.stride + bmin, c.w,
                         c.inv_s, float(curvature / double(c.inv_s))});
    for (const double e : {double(amin) - g * double(amaj), double(bmin) - g * double(bmaj)}) {
      e_lo = std::min(e_lo, e);
      e_hi = std::max(e_hi, e);
    }
    near_col.push_back(std::min(std::abs(amaj), std::abs(bmaj)));
    far_col.push_back(std::max(std::abs(amaj), std::abs(bmaj)));
    major.push_back(std::fabs(x_major ? c.x : c.y));
  }
  // The strips' bounds cover a column's texels with two windows (lane_kernel.inc): the rays' crossings
  // read within e_hi - e_lo + 2 texels across their lines (about 2 + 2 |g|), never more than 2 kLaneWindow.
  if (e_hi - e_lo > 2 * kLaneWindow - 2.01)
    throw std::logic_error("lane search: a direction's crossings read too far from its rays");
  reach_lo.resize(std::size_t(L.nmajor)), reach_hi.resize(std::size_t(L.nmajor));
  for (int u = 0; u < L.nmajor; ++u) {
    const double P = g * u, fl = std::floor(P), phi = P - fl;
    reach_lo[std::size_t(u)] = std::int32_t(fl + std::ceil(phi + e_lo - 1e-6));
    reach_hi[std::size_t(u)] = std::int32_t(fl + std::ceil(phi + e_hi + 1 + 1e-6) - 1);
  }
  // first_at[n]: the first crossing reading no column nearer than n (the crossings of walk columns n ..
  // read columns n and beyond); first_at[nmajor + 2 + n] (the second half): the first reading a column
  // beyond n, i.e. the end of the crossings a texel with n columns ahead on the field may read (the layout
  // has no padding along its major axis). The crossings are ordered by distance, so both columns only grow.
  const int nn = L.nmajor + 2;
  first_at.assign(std::size_t(2 * nn), std::int32_t(crossings.size()));
  std::size_t c = 0;
  for (int n = 0; n < nn; ++n) {
    while (c < near_col.size() && near_col[c] < n) ++c;
    first_at[n] = std::int32_t(c);
  }
  c = 0;
  for (int n = 0; n < nn; ++n) {
    while (c < far_col.size() && far_col[c] <= n) ++c;
    first_at[nn + n] = std::int32_t(c);
  }
  run = run_of(*this);
}

SweepDirection lane_plan(const HeightField& f, const SweepSpec& spec, int k) {
  SweepDirection sd = plan_direction(f, spec, k);
  if (!f.square_texels()) {
    double tx = sd.dx / f.dx(), ty = sd.dy / f.dy();
    const double n = std::hypot(tx, ty);
    tx /= n, ty /= n;
    sd.dx = std::fabs(tx) < 1e-12 ? 0.0 : tx, sd.dy = std::fabs(ty) < 1e-12 ? 0.0 : ty;
  }
  return sd;
}

void build_lane_direction(LaneDirection& d, const HeightField& f, const LaneLayout& layout,
                          const SweepDirection& sd, double curvature) {
  if (f.square_texels()) return d.build(f, layout, sd.dx, sd.dy, curvature);
  HeightField unit;  // the field's shape with unit texels
  unit.width = f.width, unit.height = f.height, unit.wrap = f.wrap, unit.texel_size = 1;
  d.build(unit, layout, sd.dx, sd.dy, 0.0);
  const double scale = std::hypot(sd.dx * f.dx(), sd.dy * f.dy());
  for (LaneCrossing& c : d.crossings) {
    c.inv_s = float(double(c.inv_s) / scale);
    c.drop = float(curvature / double(c.inv_s));
  }
  d.curved = curvature != 0;
  d.end_below = curvature >= 0;
  d.run = run_of(d);
}

int lane_strip_count(const LaneLayout& L, const LaneDirection& d) {
  const double span = double(L.nminor - 1) + std::fabs(d.g) * double(L.nmajor - 1);
  return int(std::floor(span / kLanes)) + 2;
}

void lane_strip_range(const LaneLayout& L, const LaneDirection& d, int* s0, int* s1) {
  // Texel (u, v) lies in strip floor((v - ceil(origin + g u)) / kLanes) (lane_kernel.inc): monotone in u
  // and in v, so the corners of the searched texels bound their strips.
  const double origin = lane_intercept_origin(L, d);
  long lo = std::numeric_limits<long>::max(), hi = std::numeric_limits<long>::min();
  for (const int u : {L.recv_u0, L.recv_u1 - 1})
    for (const int v : {L.recv_v0, L.recv_v1 - 1}) {
      const long base = long(std::ceil(origin + d.g * u));
      const long s = long(std::floor(double(long(v) - base) / kLanes));
      lo = std::min(lo, s), hi = std::max(hi, s);
    }
  const int count = lane_strip_count(L, d);
  *s0 = int(std::clamp<long>(lo - 1, 0, count));
  *s1 = int(std::clamp<long>(hi + 2, *s0, count));
}

static_assert(std::extent_v<decltype(LaneScratch::level_at)> == kLevels + 1);

void LaneScratch::size_for(int n) {
  if (nmajor == n) return;
  nmajor = n;
  const int nq = block_count(n);
  block.assign(std::size_t(nq + 1) * kRow, kOffField);
  suffix.assign(std::size_t(nq + 1) * kRow, kOffField);
  raw_suffix.assign(std::size_t(nq + 1) * kRow, kOffField);
  int at = 0;
  for (int v = 0, span = 4; v < kLevels; ++v, span *= 4) level_at[v] = at, at += nq / span + 2;
  level_at[kLevels] = at;
  coarse.assign(std::size_t(at) * kRow, kOffField);
  mark.assign(std::size_t(nq + 1), -1);
  trend.assign(std::size_t(n), 0.0f);
}

void lane_search(const LaneLayout& layout, const LaneDirection& d, int s0, int s1, float tolerance,
                 LaneScratch& scratch, float* slope, std::int32_t* which, LaneStats* stats, LaneIsa isa) {
  scratch.size_for(layout.nmajor);
  if (isa == LaneIsa::best) isa = lane_isa();
  if (isa == LaneIsa::avx512)
    lane_search_avx512(layout, d, s0, s1, tolerance, scratch, slope, which, stats);
  else if (isa == LaneIsa::avx2)
    lane_search_avx2(layout, d, s0, s1, tolerance, scratch, slope, which, stats);
  else
    lane_search_any<Sse2>(layout, d, s0, s1, tolerance, scratch, slope, which, stats);
}

bool lane_isa_available(LaneIsa isa) {
  static const bool avx2 = __builtin_cpu_supports("avx2"), avx512 = __builtin_cpu_supports("avx512f");
  return isa == LaneIsa::sse2 || (isa == LaneIsa::avx2 && avx2) || (isa == LaneIsa::avx512 && avx512);
}

LaneIsa lane_isa() {
  static const LaneIsa isa = [] {
    const InstructionSet cap = instruction_set_cap();
    if (cap >= InstructionSet::avx512 && lane_isa_available(LaneIsa::avx512)) return LaneIsa::avx512;
    if (cap >= InstructionSet::avx2 && lane_isa_available(LaneIsa::avx2)) return LaneIsa::avx2;
    return LaneIsa::sse2;
  }();
  return isa;
}
}  // namespace hfbake::p1
