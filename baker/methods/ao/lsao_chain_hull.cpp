#include "methods/ao/lsao_chain_hull.hpp"

#include <algorithm>
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

void TangentChain::add(double hs, double hz, double x) {
  if (!(hz > slope_max * hs)) return;
  const double e = std::atan2(hz, hs);
  if (!(e > e_max)) return;  // rounding at the same elevation
  // The band's rays meet a vertical slab at horizontal distance x (hbao's slab estimator, exact for the
  // falloff); the cosine measure doubled.
  const double c = chain_band(rho, weighting, frame, e_max, e, x);
  sum += weighting == Weighting::cosine ? 2 * c : c;
  if (want_direction) {
    const SliceVec b = band_direction(rho, frame, e_max, e, x);
    direction.h += b.h, direction.v += b.v;
  }
  e_max = e;
  slope_max = hz / hs;
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

// Walks points[0], points[stride], ... (nearest first, `count` of them) for receiver p; zmax_of(k): the
// highest height of point k and everything after it.
template <class ZMax>
void walk(const ChainPoint* points, std::ptrdiff_t count, std::ptrdiff_t stride, SlicePoint p, double support,
          TangentChain& chain, const ZMax& zmax_of) {
  for (std::ptrdiff_t k = 0; k < count; ++k) {
    const ChainPoint& q = points[k * stride];
    // Nothing from here on is nearer than q's near end nor higher than zmax: stop when that cannot rise.
    const double nearest = p.s - q.near_s;
    if (nearest > support || !(zmax_of(k) - p.z > chain.slope_max * nearest)) break;
    const double hs = p.s - q.s;
    if (q.near_s > q.s) {
      const double e_before = chain.e_max;
      chain.add(nearest, q.near_z - p.z, nearest);
      // A rising merged stretch is counted at its middle; otherwise the rays meet q's own face.
      chain.add(hs, q.z - p.z, chain.e_max > e_before ? 0.5 * (hs + nearest) : hs);
    } else {
      chain.add(hs, q.z - p.z, hs);
    }
  }
}

}  // namespace

std::size_t ChainHull::prune(SlicePoint p, const Falloff& rho, double tolerance) {
  std::size_t n = stack_.size(), tests = 0;
  while (n >= 2) {
    const ChainPoint& a = stack_[n - 1];
    ChainPoint& b = stack_[n - 2];
    ++tests;
    if (!at_least_as_high(b, a, p) || rho(p.s - b.s) < rho(p.s - a.near_s) - tolerance) break;
    merge(b, a);
    stack_.pop_back();
    --n;
  }
  return tests;
}

void ChainHull::query(SlicePoint p, double support, TangentChain& chain) const {
  if (stack_.empty()) return;
  const ChainPoint* top = &stack_.back();
  walk(top, std::ptrdiff_t(stack_.size()), -1, p, support, chain,
       [&](std::ptrdiff_t k) { return top[-k].zmax; });
}

void WindowHull::reserve(std::size_t n) {
  hull_.reserve(n);
  popped_.reserve(n);
  pops_.reserve(n);
}

void WindowHull::clear() {
  hull_.clear();
  popped_.clear();
  pops_.clear();
}

void WindowHull::build(const float* z, int begin, int end, int inside_begin, int inside_end, double step,
                       const Falloff& rho, double tolerance) {
  clear();
  const double s_end = end * step;
  for (int i = std::min(end, inside_end); i-- > std::max(begin, inside_begin);) {
    const double zi = double(z[i]);
    ChainPoint q{i * step, zi, i * step, zi, zi, i};
    // zmax: the running maximum over the insertions (the back vertex is always the latest insertion).
    const double before = hull_.empty() ? zi : hull_.back().zmax;
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
      popped_.push_back(a);
      hull_.pop_back();
      ++popped;
    }
    q.zmax = std::max(q.zmax, before);
    hull_.push_back(q);
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

void WindowHull::query(SlicePoint p, double support, TangentChain& chain) const {
  if (hull_.empty()) return;
  // The last insertion's zmax covers every vertex left.
  const double zmax = hull_.back().zmax;
  walk(hull_.data(), std::ptrdiff_t(hull_.size()), 1, p, support, chain,
       [&](std::ptrdiff_t) { return zmax; });
}

void brute_chain(const SlicePoint* pts, std::size_t count, SlicePoint p, TangentChain& chain) {
  for (std::size_t q = count; q-- > 0;) chain.add(p.s - pts[q].s, pts[q].z - p.z, p.s - pts[q].s);
}

}  // namespace hfbake
