#include "methods/ao/lsao_chain_hull.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace hfbake {

int chain_window(const Falloff& f, double step) {
  switch (f.kind) {
    case FalloffKind::step:
    case FalloffKind::linear:
    case FalloffKind::smooth:
      return std::max(1, int(std::min(1e9, std::floor(f.radius / step + 1e-9))));
    default:
      return 0;
  }
}

TangentChain::TangentChain(const Falloff& f, Weighting w, const SliceFrame& slice)
    : rho(f), weighting(w), e_max(slice.tangent), slope_max(-slice.nt / slice.nz) {
  length = std::hypot(slice.nt, slice.nz);
  frame = {slice.nt / length, slice.nz / length, slice.tangent};
  degree_ = slab_degree(f);
  c_max_ = frame.nz, s_max_ = -frame.nt;  // the tangent's elevation
}

namespace {

// band_occlusion for the chain: the closed forms of slice_integral for falloffs none, step, linear and
// smooth; for exponential and rational (no closed form) 2-point Gauss-Legendre on pieces of at most pi/8
// (band_occlusion uses 8 points a piece, which was 70 % of lsao's time with them; the chain's bands are
// narrow and the integrand smooth: within 2e-4 relative of the closed form on the wall, tests/ao).
double chain_band(const Falloff& rho, Weighting w, const SliceFrame& s, double a, double b, double x) {
  if (rho.kind != FalloffKind::exponential && rho.kind != FalloffKind::rational)
    return band_occlusion(rho, w, s, a, b, x);
  const double lo = std::max(a, s.tangent), hi = std::min(b, 0.5 * kPi);
  if (!(hi > lo)) return 0.0;
  const bool cosine = w == Weighting::cosine;
  auto g = [&](double e) {
    const double c = std::cos(e), wt = cosine ? std::max(0.0, s.nt * c + s.nz * std::sin(e)) * c : c;
    return c > 0 ? rho(x / c) * wt : 0.0;
  };
  const int pieces = std::max(1, int(std::ceil((hi - lo) / (kPi / 8))));
  const double len = (hi - lo) / pieces, half = 0.5 * len, node = half / std::sqrt(3.0);
  double sum = 0;
  for (int p = 0; p < pieces; ++p) {
    const double mid = lo + (p + 0.5) * len;
    sum += g(mid - node) + g(mid + node);
  }
  return sum * half;
}

}  // namespace

void TangentChain::rise(double hs, double hz, double x, SliceVec from) {
  const SliceVec at{hs, hz};
  if (degree_ >= 0) return add_closed(hs, hz, x, from, at);
  const double e = std::atan2(hz, hs);
  if (!(e > e_max)) return;  // rounding at the same elevation
  // The band's rays meet a vertical slab at horizontal distance x (hbao's slab estimator, exact for the
  // falloff), or the segment from the previous point; the cosine measure doubled.
  const bool exact = segments && (rho.kind == FalloffKind::none || rho.kind == FalloffKind::step);
  if (segments && !exact) {
    // The slab moved to where the band's middle ray meets the segment (within it).
    const double em = 0.5 * (std::max(e_max, frame.tangent) + e), ce = std::cos(em), se = std::sin(em);
    const double dh = at.h - from.h, dv = at.v - from.v, den = ce * dv - se * dh;
    const double t = den > 0 ? (from.h * dv - from.v * dh) / den * ce : at.h;
    x = std::clamp(t, from.h, at.h);
  }
  const double c = exact ? segment_band_occlusion(rho, weighting, frame, e_max, e, from, at)
                         : chain_band(rho, weighting, frame, e_max, e, x);
  sum += weighting == Weighting::cosine ? 2 * c : c;
  ++bands;
  if (want_direction) {
    const SliceVec b = exact ? segment_band_direction(rho, frame, e_max, e, from, at)
                             : band_direction(rho, frame, e_max, e, x);
    direction.h += b.h, direction.v += b.v;
  }
  e_max = e;
  slope_max = hz / hs;
}

// The closed forms of slice_integral.hpp (slab_primitives): the same integrals as band_occlusion,
// band_direction and (segments inside the radius) segment_band_occlusion, each band end evaluated once.
// Coalescing (segments, `coalesce` > 0): consecutive rising points whose bands would be weighted alike are
// held as one pending band from e_max up to the last of them, integrated once at the next band or finish().
namespace {

// The unit vector towards (h, v).
SliceVec unit(double h, double v) {
  const double r = std::sqrt(h * h + v * v);
  return {h / r, v / r};
}

// Where the band from elevation (ca, sa) (unit) up to point `at` meets the segment from `from` to `at`:
// the horizontal distance at which its middle ray (the sum of the ends' unit vectors; the distance does not
// depend on its length) crosses the segment, within it.
double middle_ray_distance(double ca, double sa, SliceVec at_unit, SliceVec from, SliceVec at) {
  const double ce = ca + at_unit.h, se = sa + at_unit.v;
  const double dh = at.h - from.h, dv = at.v - from.v, den = ce * dv - se * dh;
  const double t = den > 0 ? (from.h * dv - from.v * dh) / den * ce : at.h;
  return std::clamp(t, from.h, at.h);
}

}  // namespace

void TangentChain::resolve() {
  if (!lazy_) return;
  lazy_ = false;
  const SliceVec u = unit(pend_hs_, pend_hz_), b = unit(before_.h, before_.v);
  pend_c_ = u.h, pend_s_ = u.v;
  pend_x1_ = middle_ray_distance(b.h, b.v, u, pend_from_, {pend_hs_, pend_hz_});
}

void TangentChain::add_closed(double hs, double hz, double x, SliceVec from, SliceVec at) {
  const bool exact = segments && (rho.kind == FalloffKind::none || rho.kind == FalloffKind::step);
  if (pending_ && segments && !exact && coalesce > 0 && from.h >= pend_x0_) {
    // The band's distance lies in [from.h, hs], beyond pend_x0_: rho there is within `coalesce` of
    // rho(pend_x0_) when it is at hs (the test below, which add_closed's own then passes too).
    if (hs <= checked_ || rho_x0_ - rho(hs) <= coalesce) {
      checked_ = std::max(checked_, hs);
      slope_max = hz / hs;
      before_ = {pend_hs_, pend_hz_};
      pend_hs_ = hs, pend_hz_ = hz, pend_from_ = from;
      lazy_ = true;
      return;
    }
  }
  resolve();
  const double r = std::sqrt(hs * hs + hz * hz), c = hs / r, sn = hz / r;
  const bool radius = rho.kind != FalloffKind::none;
  if (exact && radius && !(from.h * from.h + from.v * from.v < rho.radius * rho.radius && r < rho.radius)) {
    // A segment that leaves the step's radius: its part inside (segment_band_occlusion's support).
    finish();
    const double e = std::atan2(hz, hs);
    if (!(e > e_max)) return;  // rounding at the same elevation
    sum += weighting == Weighting::cosine
               ? 2 * segment_band_occlusion(rho, weighting, frame, e_max, e, from, at)
               : segment_band_occlusion(rho, weighting, frame, e_max, e, from, at);
    if (want_direction) {
      const SliceVec b = segment_band_direction(rho, frame, e_max, e, from, at);
      direction.h += b.h, direction.v += b.v;
    }
    ++bands;
    commit(e, c, sn, nullptr);
    slope_max = hz / hs;
    return;
  }
  if (exact) {
    x = 0;  // inside the radius: rho = 1 along the segment, bands add exactly
  } else if (segments) {
    // The slab moved to where the band's middle ray meets the segment (within it).
    x = pending_ ? middle_ray_distance(pend_c_, pend_s_, {c, sn}, from, at)
                 : middle_ray_distance(c_max_, s_max_, {c, sn}, from, at);
  }
  slope_max = hz / hs;
  if (pending_ && coalesce > 0 && (exact || std::abs(rho(x) - rho(pend_x0_)) <= coalesce)) {
    pend_hs_ = hs, pend_hz_ = hz, pend_c_ = c, pend_s_ = sn, pend_x1_ = x;
    return;
  }
  finish();
  pending_ = true;
  pend_hs_ = hs, pend_hz_ = hz, pend_c_ = c, pend_s_ = sn, pend_x0_ = pend_x1_ = x;
  rho_x0_ = rho(x), checked_ = x;
  if (!(coalesce > 0)) finish();
}

void TangentChain::commit(double e, double c, double sn, const SlabPrimitives* at_e) {
  e_max = e;
  c_max_ = c, s_max_ = sn;
  if (at_e)
    at_max_ = *at_e;
  else
    have_max_ = false;
}

void TangentChain::finish() {
  if (!pending_) return;
  resolve();
  pending_ = false;
  const double e = std::atan2(pend_hz_, pend_hs_), c = pend_c_, sn = pend_s_;
  if (!(e > e_max)) return;  // rounding at the same elevation
  if (!have_max_) {
    at_max_ = slab_primitives(frame, weighting, e_max, s_max_, c_max_, degree_, want_direction);
    have_max_ = true;
  }
  const SlabPrimitives at_e = slab_primitives(frame, weighting, e, sn, c, degree_, want_direction);
  // A coalesced band: its rays meet the profile between its first and last points' distances.
  const double x = 0.5 * (pend_x0_ + pend_x1_);
  const bool radius = rho.kind != FalloffKind::none;
  double occ = 0;
  SliceVec dir;
  double coef[3];
  slab_coefficients(rho, x, coef);
  const double q = radius ? x / rho.radius : 0.0;
  if (q < 1) {
    // rho(x / cos e) > 0 only where cos e > q: the band clipped to [-acos q, acos q].
    const SlabPrimitives* lo = &at_max_;
    const SlabPrimitives* hi = &at_e;
    SlabPrimitives clip_lo, clip_hi;
    const bool lo_out = radius && e_max < 0 && c_max_ < q, hi_out = radius && e > 0 && c < q;
    const double ec = lo_out || hi_out ? std::acos(q) : 0.0;
    const double sc = lo_out || hi_out ? std::sqrt(std::max(0.0, 1 - q * q)) : 0.0;
    if (lo_out)
      clip_lo = slab_primitives(frame, weighting, -ec, -sc, q, degree_, want_direction), lo = &clip_lo;
    if (hi_out)
      clip_hi = slab_primitives(frame, weighting, ec, sc, q, degree_, want_direction), hi = &clip_hi;
    if ((hi_out ? ec : e) > (lo_out ? -ec : e_max)) {
      for (int k = 0; k <= degree_; ++k) occ += coef[k] * (hi->occ[k] - lo->occ[k]);
      if (want_direction)
        for (int k = 0; k <= degree_; ++k) {
          dir.h += coef[k] * (hi->h[k] - lo->h[k]);
          dir.v += coef[k] * (hi->v[k] - lo->v[k]);
        }
    }
  }
  sum += weighting == Weighting::cosine ? 2 * occ : occ;
  ++bands;
  if (want_direction) direction.h += dir.h, direction.v += dir.v;
  commit(e, c, sn, &at_e);
}

namespace {

// b is at least as high as a seen from p (both behind p: positive horizontal distances).
bool at_least_as_high(const ChainPoint& b, const ChainPoint& a, SlicePoint p) {
  return (a.z - p.z) * (p.s - b.s) <= (b.z - p.z) * (p.s - a.s);
}

// a merges into b (b farther): b stands for a's stretch too.
void merge(ChainPoint& b, const ChainPoint& a) {
  if (a.near_s > b.near_s) b.near_s = a.near_s, b.near_z = a.near_z;
  b.zmax = std::max(b.zmax, a.near_z);
}

// The block of a hull held as a stack whose positions 0 .. i are farthest first or nearest first: positions
// [i + 1 - block_span(i), i] (the ranges of a Fenwick tree; a block's summary depends only on the positions
// at or below its own, which pushes and pops above it leave as they are).
std::size_t block_span(std::size_t i) {
  return (i + 1) & ~i;
}

// Sets points[i].bmax from the point itself and the summaries of the blocks that tile the rest of its block.
void summarise_block(ChainPoint* points, std::size_t i) {
  double m = std::max(points[i].z, points[i].near_z);
  const std::ptrdiff_t first = std::ptrdiff_t(i + 1 - block_span(i));
  for (std::ptrdiff_t j = std::ptrdiff_t(i) - 1; j >= first; j -= std::ptrdiff_t(block_span(std::size_t(j))))
    m = std::max(m, points[j].bmax);
  points[i].bmax = m;
}

// Walks hull.point(0), hull.point(1), ... (nearest first, `count` of them) for receiver p; hull.zmax(k): the
// highest height of point k and everything after it; hull.block(k, &bmax): how many points from k on form a
// block (bmax: the highest of their heights and near ends), 1 when none larger starts at k.
// Points (and merged near ends) nearer than `near` are left out: the caller has marched them.
template <class Hull>
void walk(const Hull& hull, std::ptrdiff_t count, SlicePoint p, double support, double near,
          TangentChain& chain) {
  // Nothing from point k on is nearer than its near end nor higher than zmax: the walk ends when that cannot
  // rise (a point at distance d rises when it is higher than slope_max d: with the horizon still below the
  // horizontal, lower points farther on can). Once true it stays true farther on while nothing rises.
  auto ends = [&](std::ptrdiff_t k) {
    return chain.slope_max >= 0 && !(hull.zmax(k) - p.z > chain.slope_max * (p.s - hull.point(k).near_s));
  };
  // A point not rising changes only the segment's start (TangentChain::prev): its own position.
  auto passed = [&](std::ptrdiff_t k) { chain.prev = {p.s - hull.point(k).s, hull.point(k).z - p.z}; };
  for (std::ptrdiff_t k = 0; k < count;) {
    const ChainPoint& q = hull.point(k);
    ++chain.walked;
    if (ends(k)) break;
    const double nearest = p.s - q.near_s, hs = p.s - q.s;
    if (nearest > support) {
      // With segments the first point beyond the support ends the segment that crosses it.
      if (chain.segments && hs >= near) chain.add(nearest, q.near_z - p.z, nearest);
      break;
    }
    if (hs < near) {
      ++k;
      continue;
    }
    // The block from q on, all within the support, is passed over in one test when none of its points can
    // rise: below slope_max times its nearest distance (or, with the horizon below the horizontal, its
    // farthest). The same comparisons as the points' own (TangentChain::add), so the sum is the same.
    double bmax = 0;
    const std::ptrdiff_t len = hull.block(k, &bmax);
    if (len > 1) {
      const std::ptrdiff_t last = k + len - 1;
      const ChainPoint& far = hull.point(last);
      const double bound = chain.slope_max * (chain.slope_max >= 0 ? nearest : p.s - far.s);
      if (p.s - far.near_s <= support && !(bmax - p.z > bound)) {
        if (ends(last)) {
          // The walk ends inside the block: at its first point m where it ends (a binary search).
          std::ptrdiff_t lo = k, hi = last;  // ends(hi), not ends(lo)
          while (hi - lo > 1) {
            const std::ptrdiff_t mid = lo + (hi - lo) / 2;
            (ends(mid) ? hi : lo) = mid;
          }
          passed(hi - 1);
          break;
        }
        passed(last);
        k += len;
        continue;
      }
    }
    if (q.near_s > q.s && nearest >= near) {
      const double slope_before = chain.slope_max;
      chain.add(nearest, q.near_z - p.z, nearest);
      // A rising merged stretch is counted at its middle; otherwise the rays meet q's own face.
      chain.add(hs, q.z - p.z, chain.slope_max > slope_before ? 0.5 * (hs + nearest) : hs);
    } else {
      chain.add(hs, q.z - p.z, hs);
    }
    ++k;
  }
}

// The chain hull's stack walked from its top: walk position k is stack position n - 1 - k, whose block
// reaches farther (downwards).
struct StackFromTop {
  const ChainPoint* top;
  const ChainPoint& point(std::ptrdiff_t k) const { return top[-k]; }
  double zmax(std::ptrdiff_t k) const { return top[-k].zmax; }
  std::size_t size = 0;
  std::ptrdiff_t block(std::ptrdiff_t k, double* bmax) const {
    *bmax = top[-k].bmax;
    return std::ptrdiff_t(block_span(size - 1 - std::size_t(k)));
  }
};

// The window's hull walked from position 0 (nearest) up: the block starting at k is the one ending at
// k + 2^a - 1 with 2^(a + 1) dividing k (any a at k = 0), the largest that fits.
struct StackFromBottom {
  const ChainPoint* points;
  std::size_t size = 0;
  const ChainPoint& point(std::ptrdiff_t k) const { return points[k]; }
  double zmax(std::ptrdiff_t k) const { return points[k].zmax; }
  std::ptrdiff_t block(std::ptrdiff_t k, double* bmax) const {
    const std::size_t start = std::size_t(k), rest = size - start;
    std::size_t len = start == 0 ? std::bit_floor(rest) : (start & ~(start - 1)) / 2;
    while (len > rest) len /= 2;
    if (len == 0) return 1;
    *bmax = points[start + len - 1].bmax;
    return std::ptrdiff_t(len);
  }
};

}  // namespace

std::size_t ChainHull::prune(SlicePoint p, const Falloff& rho, double tolerance) {
  const std::size_t before = stack_.size();
  std::size_t n = before, tests = 0;
  while (n >= 2) {
    const ChainPoint& a = stack_[n - 1];
    ChainPoint& b = stack_[n - 2];
    ++tests;
    if (!at_least_as_high(b, a, p) || rho(p.s - b.s) < rho(p.s - a.near_s) - tolerance) break;
    merge(b, a);
    stack_.pop_back();
    --n;
  }
  if (n < before) summarise_block(stack_.data(), n - 1);  // the top took the merged points' near end
  return tests;
}

void ChainHull::push(SlicePoint p) {
  const double below = stack_.empty() ? p.z : stack_.back().zmax;
  stack_.push_back({p.s, p.z, p.s, p.z, std::max(below, p.z), 0});
  summarise_block(stack_.data(), stack_.size() - 1);
}

void ChainHull::query(SlicePoint p, double support, TangentChain& chain, double near) const {
  if (stack_.empty()) return;
  walk(StackFromTop{&stack_.back(), stack_.size()}, std::ptrdiff_t(stack_.size()), p, support, near, chain);
}

void WindowHull::reserve(std::size_t n) {
  hull_.reserve(n);
  prefix_.reserve(n);
  popped_.reserve(n);
  pops_.reserve(n);
}

void WindowHull::clear() {
  hull_.clear();
  popped_.clear();
  pops_.clear();
}

void WindowHull::build(const ChainPoint* points, std::size_t count, double s_end, const Falloff& rho,
                       double tolerance) {
  clear();
  // zmax of a vertex: the highest of the block's points at or beyond its near end (prefix_), which bounds it,
  // its near end and every vertex farther on, whatever drop_before later removes or restores.
  prefix_.resize(count);
  double highest = -INFINITY;
  for (std::size_t k = 0; k < count; ++k) prefix_[k] = highest = std::max(highest, points[k].z);
  for (std::size_t k = count; k-- > 0;) {
    const double si = points[k].s, zi = points[k].z;
    ChainPoint q{si, zi, si, zi, prefix_[k], points[k].index};
    // Extended on the left: the leftmost vertex a merges into q when it lies on or below the segment from q
    // to the vertex after it (so q or that vertex hides it from every receiver beyond the block) and rho at
    // q is within the tolerance of rho at a's near end, seen from the nearest receiver.
    int popped = 0;
    while (hull_.size() >= 2) {
      const ChainPoint& a = hull_[hull_.size() - 1];
      const ChainPoint& c = hull_[hull_.size() - 2];
      const bool below = (a.s - q.s) * (c.z - q.z) - (a.z - q.z) * (c.s - q.s) >= 0;
      if (!below || rho(s_end - q.s) < rho(s_end - a.near_s) - tolerance) break;
      merge(q, a);
      q.zmax = std::max(q.zmax, a.zmax);  // a's near end is q's now
      popped_.push_back(a);
      hull_.pop_back();
      ++popped;
    }
    hull_.push_back(q);
    summarise_block(hull_.data(), hull_.size() - 1);
    pops_.push_back(popped);
  }
}

void WindowHull::drop_before(int first) {
  while (!hull_.empty() && hull_.back().index < first) {
    hull_.pop_back();  // the last insertion is the leftmost vertex
    for (int k = pops_.back(); k > 0; --k) {
      hull_.push_back(popped_.back());
      popped_.pop_back();
    }
    pops_.pop_back();
  }
}

void WindowHull::query(SlicePoint p, double support, TangentChain& chain, double near) const {
  if (hull_.empty()) return;
  walk(StackFromBottom{hull_.data(), hull_.size()}, std::ptrdiff_t(hull_.size()), p, support, near, chain);
}

void brute_chain(const SlicePoint* pts, std::size_t count, SlicePoint p, TangentChain& chain, double near) {
  for (std::size_t q = count; q-- > 0;)
    if (p.s - pts[q].s >= near) chain.add(p.s - pts[q].s, pts[q].z - p.z, p.s - pts[q].s);
}

}  // namespace hfbake
