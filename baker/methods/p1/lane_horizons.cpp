#include "methods/p1/lane_horizons.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdlib>

#include <emmintrin.h>
#include <limits>

#include "methods/p1/horizon_sweep.hpp"

namespace hfbake::p1 {

namespace {

constexpr int kBlock = 4;       // walk columns a block test covers
constexpr int kLevels = 3;      // coarser tests: 4, 16 and 64 blocks
constexpr int kLaneRow = 9;     // unit strips a strip's bounds cover (its eight lanes, one either way)
constexpr int kRow = 12;        // floats per bound row (kLaneRow, padded for unaligned 8-wide loads)

inline float fmax_(float a, float b) { return a > b ? a : b; }

// Eight lanes as two SSE2 registers (every x86-64 has them); each lane's arithmetic is IEEE single
// precision, so a wider instruction set would give the same bits.
struct v8f {
  __m128 lo, hi;
};
struct v8i {
  __m128i lo, hi;
};
inline v8f load8(const float* p) { return {_mm_loadu_ps(p), _mm_loadu_ps(p + 4)}; }
inline v8f splat(float x) { return {_mm_set1_ps(x), _mm_set1_ps(x)}; }
inline bool any_gt(v8f a, v8f b) {
  return _mm_movemask_ps(_mm_or_ps(_mm_cmpgt_ps(a.lo, b.lo), _mm_cmpgt_ps(a.hi, b.hi))) != 0;
}

}  // namespace

void LaneLayout::build(const HeightField& f, bool xm) {
  x_major = xm;
  nmajor = xm ? f.width : f.height;
  nminor = xm ? f.height : f.width;
  stride = nminor + 2 * kLanePad;
  z.assign(std::size_t(nmajor) * std::size_t(stride), kOffField);
  for (int j = 0; j < f.height; ++j) {
    const float* row = f.z.data() + std::size_t(j) * std::size_t(f.width);
    if (xm)
      for (int i = 0; i < f.width; ++i) z[std::size_t(i) * std::size_t(stride) + kLanePad + j] = row[i];
    else
      std::copy(row, row + f.width, z.begin() + std::ptrdiff_t(j) * stride + kLanePad);
  }
  // window[at] = max z[at .. at + kLaneWindow - 1] within the major index's row (kOffField past its end).
  window.assign(z.size(), kOffField);
  for (int u = 0; u < nmajor; ++u) {
    const float* r = z.data() + std::ptrdiff_t(u) * stride;
    float* w = window.data() + std::ptrdiff_t(u) * stride;
    for (std::ptrdiff_t i = 0; i < stride; ++i) {
      float m = kOffField;
      for (std::ptrdiff_t t = i; t < std::min<std::ptrdiff_t>(stride, i + kLaneWindow); ++t) m = fmax_(m, r[t]);
      w[i] = m;
    }
  }
}

void LaneDirection::build(const HeightField& f, const LaneLayout& L, double dx, double dy) {
  x_major = L.x_major;
  const double dmaj = x_major ? dx : dy, dmin = x_major ? dy : dx;
  su = dmaj >= 0 ? 1 : -1;
  g = dmin / dmaj;
  const double radius = std::hypot(double(f.width), double(f.height)) + 2;
  const std::vector<NearCrossing> cs = near_field_stencil(dx, dy, radius, f.texel_size);
  crossings.clear();
  crossings.reserve(cs.size());
  major.clear();
  std::vector<double> n_c;
  n_c.reserve(cs.size());
  for (const NearCrossing& c : cs) {
    const int amaj = x_major ? c.ai : c.aj, amin = x_major ? c.aj : c.ai;
    const int bmaj = x_major ? c.bi : c.bj, bmin = x_major ? c.bj : c.bi;
    crossings.push_back({std::int32_t(std::ptrdiff_t(amaj) * L.stride + amin),
                         std::int32_t(std::ptrdiff_t(bmaj) * L.stride + bmin), c.w, c.inv_s});
    n_c.push_back(std::fabs(double(x_major ? c.x : c.y)));
    major.push_back(float(n_c.back()));
  }
  // first_at[n]: the first crossing at major distance >= n; first_at[nmajor + 2 + n] (the second half):
  // the first beyond n (distance > n), i.e. the end of the crossings on the field up to n.
  const int nn = L.nmajor + 2;
  first_at.assign(std::size_t(2 * nn), std::int32_t(crossings.size()));
  std::size_t c = 0;
  for (int n = 0; n < nn; ++n) {
    while (c < n_c.size() && n_c[c] < n - 1e-4) ++c;
    first_at[n] = std::int32_t(c);
  }
  c = 0;
  for (int n = 0; n < nn; ++n) {
    while (c < n_c.size() && n_c[c] <= n + 1e-4) ++c;
    first_at[nn + n] = std::int32_t(c);
  }
}

namespace {

double c_min_of(const LaneLayout& L, const LaneDirection& d) {
  return std::min(0.0, -d.g * double(L.nmajor - 1));
}

}  // namespace

int lane_strip_count(const LaneLayout& L, const LaneDirection& d) {
  const double span = double(L.nminor - 1) + std::fabs(d.g) * double(L.nmajor - 1);
  return int(std::floor(span / kLanes)) + 2;
}

void lane_search(const HeightField& f, const LaneLayout& L, const LaneDirection& d, int s0, int s1,
                 float tolerance, LaneScratch& S, float* slope_out, std::int32_t* which_out,
                 LaneStats* stats) {
  const int nmaj = L.nmajor, nmin = L.nminor;
  const int nq = nmaj / kBlock + 2;  // blocks (walk order)
  S.block.assign(std::size_t(nq + 1) * kRow, kOffField);
  // Level v holds the bounds of 4^(v+1) blocks from block 4^(v+1) Q, at [level_at[v] + Q].
  int level_at[kLevels + 1];
  {
    int at = 0;
    for (int v = 0, span = 4; v < kLevels; ++v, span *= 4) level_at[v] = at, at += nq / span + 2;
    level_at[kLevels] = at;
    S.coarse.assign(std::size_t(at) * kRow, kOffField);
  }
  S.suffix.assign(std::size_t(nq + 1) * kRow, kOffField);
  const double c_min = c_min_of(L, d);
  const LaneCrossing* cr = d.crossings.data();
  const int nn = nmaj + 2;
  const std::int32_t* first_at = d.first_at.data();
  const std::int32_t* end_at = d.first_at.data() + nn;
  const float inf = std::numeric_limits<float>::infinity();
  auto u_of = [&](int r) { return d.su > 0 ? r : nmaj - 1 - r; };
  const double gr = d.g * d.su;  // minor change per column along the ray
  LaneStats st;
  float* UB = S.block.data();
  float* UC = S.coarse.data();
  float* US = S.suffix.data();

  for (int s = s0; s < s1; ++s) {
    // The strip's bounds, per unit strip j = 0 .. 8 of intercepts [k0 + j, k0 + j + 1) (a ray there uses
    // texels of its column within LaneLayout::window's reach): UB[q][j] the highest over walk columns
    // 4q .. 4q + 4 (every crossing at walk positions [4q, 4q + 4)), UC over 64 columns from 64Q, US from
    // column 4q to the end.
    const double k0 = std::floor(c_min + double(kLanes) * s);
    for (int q = 0; q < nq; ++q) {
      __m128 lo = _mm_set1_ps(kOffField), hi = lo;
      float last = kOffField;
      for (int r = kBlock * q; r <= kBlock * q + kBlock && r < nmaj; ++r) {
        const int u = u_of(r);
        const long start = long(std::floor(k0 + d.g * u)) - 2;
        // Windows entirely off the field bound nothing a ray on it uses (and stay inside the padding).
        if (start + kLaneRow + kLaneWindow - 2 < 0 || start > nmin - 1) continue;
        const float* w = L.window.data() + std::ptrdiff_t(u) * L.stride + kLanePad + start;
        lo = _mm_max_ps(lo, _mm_loadu_ps(w)), hi = _mm_max_ps(hi, _mm_loadu_ps(w + 4));
        last = fmax_(last, w[8]);
      }
      float* row = UB + std::size_t(q) * kRow;
      _mm_storeu_ps(row, lo), _mm_storeu_ps(row + 4, hi), row[8] = last;
    }
    for (int j = 0; j < kRow; ++j) {
      float run = kOffField;
      for (int q = nq - 1; q >= 0; --q) US[std::size_t(q) * kRow + j] = run = fmax_(run, UB[std::size_t(q) * kRow + j]);
      for (int v = 0, span = 4; v < kLevels; ++v, span *= 4) {
        const float* below = v == 0 ? UB : UC + std::size_t(level_at[v - 1]) * kRow;
        const int below_n = v == 0 ? nq : level_at[v] - level_at[v - 1];
        for (int Q = 0; Q < level_at[v + 1] - level_at[v]; ++Q) {
          float m = kOffField;
          for (int q = 4 * Q; q < std::min(below_n, 4 * Q + 4); ++q) m = fmax_(m, below[std::size_t(q) * kRow + j]);
          UC[std::size_t(level_at[v] + Q) * kRow + j] = m;
        }
      }
    }

    // The previous group's casters (walk blocks), tried first: the caster of a texel is most often the
    // caster of its neighbour one column behind, and a good best slope early prunes the most.
    int hint[kLanes];
    for (int l = 0; l < kLanes; ++l) hint[l] = -1;
    static const bool no_search = std::getenv("LANE_NOSEARCH") != nullptr;
    for (int r_u = 0; r_u < (no_search ? 0 : nmaj); ++r_u) {
      const int u = u_of(r_u);
      // The strip's texels in column u: the eight whose intercepts v - g u lie in [c_min + 8 s, + 8).
      const long v0 = long(std::ceil(c_min + d.g * u)) + long(kLanes) * s;
      if (v0 + kLanes <= 0 || v0 >= nmin) continue;
      const int lane_lo = int(std::max<long>(0, -v0));                   // lanes [lane_lo, lane_hi) are
      const int lane_hi = int(std::min<long>(kLanes, long(nmin) - v0));  // on the field
      // Lane l's unit strip is k0 + o + l.
      const int o = int(std::floor(double(v0) - d.g * u) - k0) > 0 ? 1 : 0;
      const int nmax = nmaj - 1 - r_u;  // columns ahead on the field
      long n_end = nmax;
      if (gr > 0) n_end = std::min<long>(n_end, long(std::floor(double(nmin - 1 - v0 - lane_lo) / gr)) + 2);
      if (gr < 0) n_end = std::min<long>(n_end, long(std::floor(double(v0 + lane_hi - 1) / -gr)) + 2);
      const int c_end = end_at[n_end];
      const float* zb = L.z.data() + std::ptrdiff_t(u) * L.stride + kLanePad + v0;
      const v8f z0 = load8(zb);
      alignas(16) float init[kLanes];
      for (int l = 0; l < kLanes; ++l) init[l] = l >= lane_lo && l < lane_hi ? -inf : inf;
      v8f best = load8(init);
      v8i arg = {_mm_set1_epi32(-1), _mm_set1_epi32(-1)};
      const __m128 tol = _mm_set1_ps(tolerance), zero = _mm_setzero_ps();
      // Could any lane's ray beat its best slope (plus the tolerance) at a point no higher than its
      // bound (row + o + lane) among crossings cn .. cf (nearest, farthest)?
      int last_lanes = 0;
      auto beats = [&](const float* row, int cn, int cf) {
        ++st.tests;
        const __m128 inv_n = _mm_set1_ps(cr[cn].inv_s), inv_f = _mm_set1_ps(cr[cf].inv_s);
        auto half = [&](const float* bz, __m128 z, __m128 b) {
          const __m128 num = _mm_sub_ps(_mm_loadu_ps(bz), z);
          const __m128 pos = _mm_cmpgt_ps(num, zero);
          const __m128 inv = _mm_or_ps(_mm_and_ps(pos, inv_n), _mm_andnot_ps(pos, inv_f));
          return _mm_cmpgt_ps(_mm_mul_ps(num, inv), _mm_add_ps(b, tol));
        };
        const int mk = _mm_movemask_ps(half(row + o, z0.lo, best.lo)) | (_mm_movemask_ps(half(row + o + 4, z0.hi, best.hi)) << 4);
        last_lanes = __builtin_popcount(mk);
        return mk != 0;
      };
      auto evaluate = [&](int c0, int c1) {
        ++st.blocks;
        st.crossings += std::uint64_t(c1 - c0);
        for (int c = c0; c < c1; ++c) {
          const float* pa = zb + cr[c].a;
          const float* pb = zb + cr[c].b;
          const __m128 w = _mm_set1_ps(cr[c].w), inv = _mm_set1_ps(cr[c].inv_s);
          const __m128i ci = _mm_set1_epi32(c);
          auto half = [&](const float* a, const float* b, __m128 z, __m128& bst, __m128i& ag) {
            const __m128 va = _mm_loadu_ps(a), vb = _mm_loadu_ps(b);
            const __m128 m = _mm_mul_ps(_mm_sub_ps(_mm_add_ps(va, _mm_mul_ps(_mm_sub_ps(vb, va), w)), z), inv);
            const __m128 gt = _mm_cmpgt_ps(m, bst);
            bst = _mm_max_ps(m, bst);
            const __m128i g = _mm_castps_si128(gt);
            ag = _mm_or_si128(_mm_and_si128(g, ci), _mm_andnot_si128(g, ag));
          };
          half(pa, pb, z0.lo, best.lo, arg.lo);
          half(pa + 4, pb + 4, z0.hi, best.hi, arg.hi);
        }
      };
      ++st.groups;
      // The near blocks: every crossing up to the end of the walk block after the texel's own.
      const int q_first = r_u / kBlock + 2;
      {
        const int c1 = std::min<int>(first_at[std::min<long>(kBlock * q_first - r_u, n_end + 1)], c_end);
        if (c1 > 0) evaluate(0, c1);
      }
      int tried[kLanes], n_tried = 0;
      for (int l = 0; l < kLanes; ++l) {
        const int q = hint[l];
        if (q < q_first) continue;
        bool seen = false;
        for (int t = 0; t < n_tried; ++t) seen |= tried[t] == q;
        if (seen) continue;
        tried[n_tried++] = q;
        const long n0 = long(kBlock) * q - r_u;
        if (n0 > n_end) continue;
        const int c0 = first_at[n0];
        if (c0 >= c_end) continue;
        const int c1 = std::min<int>(first_at[std::min<long>(n0 + kBlock, n_end + 1)], c_end);
        if (beats(UB + std::size_t(q) * kRow, c0, c1 - 1)) evaluate(c0, c1);
      }
      for (int q = q_first;;) {
        const long n0 = long(kBlock) * q - r_u;
        if (n0 > n_end) break;
        const int c0 = first_at[n0];
        if (c0 >= c_end) break;
        const float* ub = UB + std::size_t(q) * kRow;
        if (!beats(US + std::size_t(q) * kRow, c0, c_end - 1)) break;
        // The coarsest aligned span whose bound no lane can beat is skipped whole.
        int skip = 0;
        for (int v = kLevels - 1, span = 4 * 4 * 4; v >= 0 && skip == 0; --v, span /= 4) {
          if (q % span != 0) continue;
          const int cc = std::min<int>(first_at[std::min<long>(n0 + long(kBlock) * span, n_end + 1)], c_end);
          if (!beats(UC + std::size_t(level_at[v] + q / span) * kRow, c0, cc - 1)) skip = span;
        }
        if (skip) {
          q += skip;
          continue;
        }
        const int c1 = std::min<int>(first_at[std::min<long>(n0 + kBlock, n_end + 1)], c_end);
        bool done = false;
        for (int t = 0; t < n_tried; ++t) done |= tried[t] == q;
        if (!done && beats(ub, c0, c1 - 1)) {
          ++st.by_block[std::min<long>(q - q_first, 32)];
          st.lanes += std::uint64_t(last_lanes);
          evaluate(c0, c1);
        }
        ++q;
      }
      alignas(16) float bo[kLanes];
      alignas(16) std::int32_t ao[kLanes];
      _mm_store_ps(bo, best.lo), _mm_store_ps(bo + 4, best.hi);
      _mm_store_si128(reinterpret_cast<__m128i*>(ao), arg.lo);
      _mm_store_si128(reinterpret_cast<__m128i*>(ao + 4), arg.hi);
      for (int l = 0; l < kLanes; ++l)
        hint[l] = ao[l] >= 0 ? int((r_u + long(d.major[std::size_t(ao[l])])) / kBlock) : -1;
      for (int l = lane_lo; l < lane_hi; ++l) {
        const int i = L.x_major ? u : int(v0) + l, j = L.x_major ? int(v0) + l : u;
        const std::size_t at = f.index(i, j);
        slope_out[at] = bo[l];
        which_out[at] = ao[l];
      }
    }
  }
  if (stats) {
    for (int i = 0; i < 33; ++i) stats->by_block[i] += st.by_block[i];
    stats->groups += st.groups, stats->blocks += st.blocks, stats->crossings += st.crossings;
    stats->lanes += st.lanes, stats->tests += st.tests;
  }
}

}  // namespace hfbake::p1
