#include "methods/p1/far_horizons.hpp"

#include "field/edge_crossings.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace hfbake::p1 {
namespace {

constexpr double kMinGap = 1e-7;  // steps: the least gap between two entries of a LinePattern

int wrap_index(long long a, int n) {
  a %= n;
  return int(a < 0 ? a + n : a);
}

}  // namespace

void LinePattern::build(const HeightField& f, const SweepDirection& d) {
  k = d.k, u_start = d.u_start, count = d.count;
  pos.clear(), major_a.clear(), major_b.clear(), d_a.clear(), d_b.clear(), w.clear(), minor.clear();
  first.assign(std::size_t(d.count) + 1, 0);
  strip_d.assign(std::size_t(d.count), 0);
  const bool rep = d.repeat;
  const int nmaj = d.n_major, nmin = d.n_minor;
  const std::int64_t major_stride = d.x_major ? 1 : f.width;
  auto moff = [&](int u) { return std::int64_t(rep ? wrap_index(u, nmaj) : u) * major_stride; };
  auto dmin = [&](int v) { return std::int32_t(rep ? wrap_index(v, nmin) : v); };
  auto push = [&](double p, int ua, int va, int ub, int vb, double wb, double m) {
    pos.push_back(p);
    major_a.push_back(moff(ua)), major_b.push_back(moff(ub));
    const std::int32_t da = dmin(va);
    d_a.push_back(da), d_b.push_back(rep && vb == va + 1 ? da + 1 : dmin(vb));
    w.push_back(float(wb));
    minor.push_back(m);
  };
  for (int n = 0; n < d.count; ++n) {
    first[n] = std::int32_t(pos.size());
    const int u = d.u(n);
    const double x = double(u) * d.slope;  // minor coordinate of line 0 (line l: l + x), as sample_line
    const int jb = floor_int(x);
    const double t = x - jb;
    push(n, u, jb, u, jb + 1, t, x);
    strip_d[n] = t > 0 ? jb : jb - 1;
    if (n + 1 >= d.count) break;
    const int u1 = d.u(n + 1);
    const double x1 = double(u1) * d.slope;
    // The step's crossings with the triangulation's edges (field/edge_crossings.hpp, in field coordinates):
    // the minor axis' integers (at most one, |slope| <= 1) and the diagonals u + v = integer (at most two);
    // the major axis' integers are the samples themselves.
    EdgeCrossing c[kMaxEdgeCrossings];
    const int m = d.x_major ? edge_crossings(u, x, u1, x1, c) : edge_crossings(x, u, x1, u1, c);
    // Positions increase by at least kMinGap (the hull's precondition, with room for rounding): a crossing
    // nearer a sample (u * slope an integer up to rounding) or another crossing is that point already, to
    // kMinGap times the surface's slope, and is left out. Two vertices 1e-15 apart, float heights one ulp
    // apart, made the hull non-concave and its binary search miss the steepest vertex.
    for (int i = 0; i < m; ++i) {
      const double p = n + c[i].t;
      if (!(p > pos.back() + kMinGap && p < double(n + 1) - kMinGap)) continue;
      const LineEdge g = line_edge(c[i], u + d.su * c[i].t);
      push(p, g.ua, g.va, g.ub, g.vb, g.w, g.v);
    }
  }
  first[d.count] = std::int32_t(pos.size());
}

std::size_t LinePattern::bytes() const {
  return pos.capacity() *
             (sizeof(double) * 2 + sizeof(std::int64_t) * 2 + sizeof(std::int32_t) * 2 + sizeof(float)) +
         (first.capacity() + strip_d.capacity()) * sizeof(std::int32_t);
}

std::size_t FarHorizonWorker::scratch_bytes(int count) {
  // At most 4 entries a step (a sample, a row, two diagonals): two patterns, three profiles, the hull.
  const std::size_t entries = 4 * std::size_t(count);
  const std::size_t pattern = entries * (2 * 8 + 2 * 8 + 2 * 4 + 4) + 2 * 4 * std::size_t(count);
  return 2 * pattern + entries * (3 * 4 + 8 + 4) + std::size_t(count) * (4 + 4);
}

const LinePattern& FarHorizonWorker::pattern(const SweepDirection& d) {
  for (LinePattern& p : patterns_)
    if (p.k == d.k && p.u_start == d.u_start && p.count == d.count) return p;
  LinePattern& p = patterns_[next_slot_];
  next_slot_ ^= 1;
  p.build(*field, d);
  p.near = beat_near ? near_stencil(*field, d, far_radius / field->texel_size) : NearStencil{};
  return p;
}

void FarHorizonWorker::profile(const LinePattern& pat, const SweepDirection& d, int line,
                               std::vector<float>& out) const {
  const std::size_t E = pat.pos.size();
  out.resize(E);
  const float* Z = field->z.data();
  const int nv = d.n_minor;
  const std::ptrdiff_t ms = d.x_major ? field->width : 1;
  if (d.repeat) {
    for (std::size_t e = 0; e < E; ++e) {
      int ra = line + pat.d_a[e], rb = line + pat.d_b[e];
      ra -= ra >= nv ? nv : 0;
      rb -= rb >= nv ? nv : 0;
      const float za = Z[pat.major_a[e] + ra * ms], zb = Z[pat.major_b[e] + rb * ms];
      out[e] = (za - z_ref_) + (zb - za) * pat.w[e];
    }
    return;
  }
  const float none = -std::numeric_limits<float>::infinity();
  const double top = nv - 1 + 1e-9;
  for (std::size_t e = 0; e < E; ++e) {
    const double v = line + pat.minor[e];
    if (v < -1e-9 || v > top) {
      out[e] = none;
      continue;
    }
    const int ra = std::clamp(line + pat.d_a[e], 0, nv - 1), rb = std::clamp(line + pat.d_b[e], 0, nv - 1);
    const float za = Z[pat.major_a[e] + ra * ms], zb = Z[pat.major_b[e] + rb * ms];
    out[e] = (za - z_ref_) + (zb - za) * pat.w[e];
  }
}

void FarHorizonWorker::operator()(const SweepLine& line, float* out) {
  if (!have_z_ref_) {
    const auto [lo, hi] = std::minmax_element(field->z.begin(), field->z.end());
    z_ref_ = lo == field->z.end() ? 0.0f : float(0.5 * (double(*lo) + double(*hi)));
    have_z_ref_ = true;
  }
  // The border rule is a template argument: the search's height reads (Zr) and range tests are the
  // innermost code, and a runtime test in each cost ~1 % of p1's instructions.
  if (line.dir->repeat)
    search<true>(line, out);
  else
    search<false>(line, out);
}

template <bool rep>
void FarHorizonWorker::search(const SweepLine& line, float* out) {
  const SweepDirection& d = *line.dir;
  const HeightField& f = *field;
  const float inf = std::numeric_limits<float>::infinity();
  const int R0 = line.first_receiver, count = line.count;
  for (int n = R0; n < count; ++n) out[2 * (n - R0)] = 0.0f, out[2 * (n - R0) + 1] = inf;
  const LinePattern& pat = pattern(d);
  const int l = line.line, nv = d.n_minor, nu = d.n_major;
  const int lprev = rep ? (l == 0 ? nv - 1 : l - 1) : l - 1;
  if (last_k_ == d.k && last_line_ == lprev && last_u_start_ == d.u_start)
    std::swap(prev_, cur_);  // the last call's line l is this one's line l - 1
  else
    profile(pat, d, lprev, prev_);
  profile(pat, d, l, cur_);
  last_k_ = d.k, last_line_ = l, last_u_start_ = d.u_start;

  const float* Z = f.z.data();
  const std::ptrdiff_t ms = d.x_major ? f.width : 1;
  const std::int64_t major_stride = d.x_major ? 1 : f.width;
  auto row_of = [&](long long r) { return rep ? wrap_index(r, nv) : int(r); };
  // The strip's texel at each sample (NaN where it is off a clamp field) and its minor coordinate.
  texel_z_.resize(std::size_t(count));
  texel_r_.resize(std::size_t(count));
  for (int n = 0; n < count; ++n) {
    const int u = d.u(n);
    // The same texel as strip_line (the gather's rule), also where u * slope rounds to an integer. The
    // rule is monotone in r but rounding can skip l (r - u * slope rounds up to l from below): then no
    // texel at this column reads strip l, and the skipped texel, on line l, is in cur_ already.
    int r = l + pat.strip_d[n];
    int s = strip_line(d, u, r);
    while (s > l) s = strip_line(d, u, --r);
    while (s < l) s = strip_line(d, u, ++r);
    texel_r_[n] = r;
    texel_z_[n] = s == l && (rep || (r >= 0 && r < nv))
                      ? Z[pat.major_a[pat.first[n]] + std::ptrdiff_t(row_of(r)) * ms] - z_ref_
                      : std::numeric_limits<float>::quiet_NaN();
  }
  const std::size_t E = pat.pos.size();
  const bool on_line = d.slope == 0 || d.slope == 1 || d.slope == -1;  // every texel on line l - 1
  const float* hb = prev_.data();
  if (!on_line) {
    bound_.resize(E);
    for (std::size_t e = 0; e < E; ++e) bound_[e] = std::max(prev_[e], cur_[e]);
    for (int n = 0; n < count; ++n)
      if (texel_z_[n] == texel_z_[n]) bound_[pat.first[n]] = std::max(bound_[pat.first[n]], texel_z_[n]);
    hb = bound_.data();
  }
  // Skip bounds: per band c (columns c to c + 1), the highest entry of the strip's bound in it, both
  // columns included. The surface of the strip in the band is below the bound's linear interpolation
  // between its entries (see the header), so the band's points on any texel's ray lie below its largest
  // entry; a block of kBlock bands below its bands' largest. `slack` covers the lerps' float rounding (a
  // ray's crossing can coincide with an entry computed with other weights).
  if (!on_line) {
    band_max_.resize(std::size_t(count));
    float scale = 0;
    for (std::size_t e = 0; e < E; ++e)
      if (hb[e] > -inf) scale = std::max(scale, std::fabs(hb[e]));
    const float slack = scale * 1e-6f;
    for (int c = 0; c + 1 < count; ++c) {
      float m = hb[pat.first[c]];
      for (int e = pat.first[c] + 1; e <= pat.first[c + 1]; ++e) m = std::max(m, hb[e]);
      band_max_[c] = m + slack;
    }
    band_max_[count - 1] = -inf;
    block_max_.assign(std::size_t(count / kBlock + 1), -inf);
    for (int c = 0; c + 1 < count; ++c) {
      float& b = block_max_[std::size_t(c / kBlock)];
      b = std::max(b, band_max_[c]);
    }
  }
  hull_.reset(int(E));
  const double step = line.step;
  const double reach = std::max(far_radius / step, 1.0);  // steps; the near field covers the rest
  const double dvp = d.su * d.slope;                      // a ray's minor coordinate per step
  const double dws = d.su + dvp;                          // ... and its u + v per step
  const double inv_dvp = dvp != 0 ? 1 / dvp : 0, inv_dws = dws != 0 ? 1 / dws : 0;
  const double tol = tolerance;
  std::size_t fed = 0;
  int hint = -1;   // the band of the last texel's far caster: the next texel's is usually in or near it
  int q_prev = 0;  // the last texel's hull vertex: the next one's is usually a few vertices away

  for (int n = R0; n < count; ++n) {
    const double cut = n - reach;
    // The points up to the first column at or after the cut: the kinks' heights are linear between two
    // columns (or a column and a line's crossing), so the hull bounds the strip up to the cut only with
    // the column beyond it.
    // Entries at positions <= ceil(cut - 1e-9) + 1e-9: up to that column's sample (its crossings lie more
    // than kMinGap beyond it), found from the pattern's index instead of comparing positions.
    const int cc = -floor_int(-(cut - 1e-9));
    const std::size_t feed_end = cc < 0 ? 0 : cc >= count ? E : std::size_t(pat.first[cc]) + 1;
    for (; fed < feed_end; ++fed)
      if (hb[fed] > -inf) hull_.add(pat.pos[fed], hb[fed]);
    const float zt = texel_z_[n];
    if (hull_.size() == 0 || !(zt == zt)) continue;
    float* o = out + 2 * std::size_t(n - R0);
    const int q = hull_.query_index_near(n, zt, q_prev);
    q_prev = q;
    if (on_line) {  // T's ray is line l - 1: its hull's caster is exact
      o[0] = float(double(hull_.height(q)) - zt), o[1] = float((n - hull_.position(q)) * step);
      continue;
    }
    ++texels;
    // T's ray: minor coordinate r + dvp (p - n), major u(p) = u_start + su p.
    const int r = texel_r_[n];
    bool any = false, found = false;
    double bdz = 0, brun = 1;
    if (beat_near) {  // the best point starts as the near field's, lowered by more than atan's error
      const int iu = rep ? wrap_index(d.u(n), nu) : d.u(n), ir = row_of(r);
      const int ti = d.x_major ? iu : ir, tj = d.x_major ? ir : iu;
      const float m = near_slope_at(f, pat.near, ti, tj);
      if (m > -1e29f) any = true, bdz = double(m) - 1e-6 * (1 + double(m) * m), brun = 1;
    }
    auto u_at = [&](double p) { return d.u_start + d.su * p; };
    auto Zr = [&](long long uu, long long vv) {
      if constexpr (rep)
        return Z[std::int64_t(wrap_index(uu, nu)) * major_stride + std::ptrdiff_t(wrap_index(vv, nv)) * ms] -
               z_ref_;
      vv = vv < 0 ? 0 : (vv >= nv ? nv - 1 : vv);
      return Z[uu * major_stride + vv * ms] - z_ref_;
    };
    // Where T's ray is on the field (clamp), and the far field's end.
    double lo = 0, hi = cut;
    if (!rep) {
      const double pa = n + (0 - r) / dvp, pb = n + (nv - 1 - r) / dvp;
      lo = std::max(lo, std::min(pa, pb) - 1e-9), hi = std::min(hi, std::max(pa, pb) + 1e-9);
    }
    const double vtop = nv - 1 + 1e-9;
    // A point at position p, `rise` above T: the rise as (a - zt) + (b - a) t, rounded as a rise is, not as
    // the heights are (a DEM 8000 m up rounds a + (b - a) t to 0.5 mm).
    auto take = [&](double p, float rise) {
      const double dz = double(rise), run = (n - p) * step;
      if (!any || dz * brun > bdz * run) bdz = dz, brun = run, any = found = true;
    };
    // Column c's point of T's ray, v = r + dvp (c - n) its minor coordinate, fv = floor(v).
    auto column_at = [&](int c, double v, int fv) {
      if (c < 0 || c >= n) return;
      if (!rep && (v < -1e-9 || v > vtop)) return;
      const int uu = d.u(c);
      const float a = Zr(uu, fv), b = Zr(uu, fv + 1);
      take(c, (a - zt) + (b - a) * float(v - fv));
    };
    auto column = [&](int c) {
      const double v = r + dvp * (c - n);
      column_at(c, v, floor_int(v));
    };
    // The crossings strictly between columns c and c + 1 (with_column: and column c's point). One floor:
    // every crossing inside the band lies between texel columns u(c) and u(c) + su, so its edge's lower
    // major coordinate is fu below, and a diagonal's row is kd - fu - 1.
    auto band = [&](int c, bool with_column) {
      ++bands;
      const double va = r + dvp * (c - n), vb = va + dvp;
      const int fa = floor_int(va), ca = va > fa ? fa + 1 : fa;  // floor and ceiling of va
      if (with_column) column_at(c, va, fa);
      const int fu = d.su > 0 ? d.u(c) : d.u(c) - 1;
      const int kr = dvp > 0 ? fa + 1 : ca - 1;
      if ((dvp > 0 ? kr < vb : kr > vb) && (rep || (kr >= 0 && kr < nv))) {
        const double p = n + (kr - r) * inv_dvp, uc = u_at(p);
        if (p > c && p < c + 1) {
          const float a = Zr(fu, kr), b = Zr(fu + 1, kr);
          take(p, (a - zt) + (b - a) * float(uc - fu));
        }
      }
      const double wa = d.u(c) + va, wb = wa + dws;
      for (int kd = dws > 0 ? d.u(c) + fa + 1 : d.u(c) + ca - 1; dws > 0 ? kd < wb : kd > wb;
           kd += dws > 0 ? 1 : -1) {
        const double p = c + (kd - wa) * inv_dws, uc = u_at(p), vc = kd - uc;
        if (!rep && (vc < -1e-9 || vc > vtop)) continue;
        if (!(p > c && p < c + 1)) continue;
        const int fv = kd - fu - 1;
        const float a = Zr(fu + 1, fv), b = Zr(fu, fv + 1);
        take(p, (a - zt) + (b - a) * float(vc - fv));
      }
    };
    // The hull's value at x (between its vertices j and j + 1, or vertex j itself).
    auto hull_at = [&](int j, double x) {
      const double p0 = hull_.position(j), h0 = hull_.height(j);
      if (x <= p0 || j + 1 >= hull_.size()) return h0;
      const double p1 = hull_.position(j + 1), h1 = hull_.height(j + 1);
      return h0 + (h1 - h0) * (x - p0) / (p1 - p0);
    };
    // The bound at x is no steeper than the best point plus the tolerance (bdz + tol * brun over brun).
    auto beaten = [&](double x, double hx) {
      return any && (hx - zt) * brun <= (bdz + tol * brun) * ((n - x) * step);
    };
    // Nothing in positions [x0, x1] (clipped to the far field) that is at most h high beats the best by
    // more than the tolerance.
    auto lower = [&](double x0, double x1, float h) {
      if (!any) return false;
      const double x = h >= zt ? std::min(x1, hi) : std::max(x0, lo);
      return (double(h) - zt) * brun <= (bdz + tol * brun) * ((n - x) * step);
    };
    auto band_lower = [&](int c) { return lower(c, c + 1, band_max_[c]); };
    auto block_lower = [&](int k) { return lower(k * kBlock, (k + 1) * kBlock, block_max_[k]); };
    if (lo > hi) continue;
    const double pq = hull_.position(q);
    if (beaten(pq, hull_.height(q))) continue;  // the bound's peak is below the near field's point
    // The neighbour's caster band first (when it lies wholly in this texel's far field): a best point
    // near the final one from the start prunes most of the walk's bands. Evaluating a band twice is
    // harmless (take keeps the first of equal points).
    if (hint >= lo && hint + 1 <= hi && !band_lower(hint)) band(hint, true), column(hint + 1);
    const int c0 = std::clamp(floor_int(pq), floor_int(lo), floor_int(hi));
    int a = c0, b = c0;
    if (pq > c0 && c0 < hi) {
      if (!band_lower(c0)) band(c0, true), column(c0 + 1);
      b = c0 + 1;
    } else {
      column(c0);
    }
    // Left: the bound is unimodal with its peak at pq, so for a <= pq it bounds every point before a.
    const double left_end = std::max(lo, hull_.position(0));
    for (int j = q; a > left_end;) {
      if (a <= pq) {
        while (j > 0 && hull_.position(j) > a) --j;
        if (beaten(a, hull_at(j, a))) break;
      }
      const int k = (a - 1) / kBlock;
      if (block_lower(k)) {
        a = k * kBlock;
        continue;
      }
      if (!band_lower(a - 1)) band(a - 1, true);
      --a;
    }
    const double right_end = std::min(hi, hull_.position(hull_.size() - 1));
    for (int j = q; b < right_end;) {
      if (b >= pq) {
        while (j + 1 < hull_.size() && hull_.position(j + 1) <= b) ++j;
        if (beaten(b, hull_at(j, b))) break;
      }
      const int k = b / kBlock;
      if (block_lower(k)) {
        b = (k + 1) * kBlock;
        continue;
      }
      if (!band_lower(b)) band(b, false), column(b + 1);
      ++b;
    }
    if (found) o[0] = float(bdz), o[1] = float(brun), hint = floor_int(n - brun / step);
  }
}

}  // namespace hfbake::p1
