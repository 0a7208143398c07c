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
  const double len = std::hypot(slice.nt, slice.nz);
  frame = {slice.nt / len, slice.nz / len, slice.tangent};
}

void TangentChain::add(double hs, double hz, double x) {
  if (!(hz > slope_max * hs)) return;
  const double e = std::atan2(hz, hs);
  if (!(e > e_max)) return;  // rounding at the same elevation
  // The band's rays meet a vertical slab at horizontal distance x (hbao's slab estimator, exact for the
  // falloff); the cosine measure doubled.
  const double c = band_occlusion(rho, weighting, frame, e_max, e, x);
  sum += weighting == Weighting::cosine ? 2 * c : c;
  e_max = e;
  slope_max = hz / hs;
  top = {hs, hz};
}

namespace {

// b is higher than a seen from p (both behind p: positive horizontal distances).
bool higher(const ChainPoint& b, const ChainPoint& a, SlicePoint p) {
  return (a.z - p.z) * (p.s - b.s) < (b.z - p.z) * (p.s - a.s);
}

// Walks points[0], points[stride], ... (nearest first, `count` of them) for receiver p.
void walk(const ChainPoint* points, std::ptrdiff_t count, std::ptrdiff_t stride, SlicePoint p, double support,
          TangentChain& chain) {
  int since_rise = 0;
  for (std::ptrdiff_t k = 0; k < count && since_rise <= kChainExtra; ++k) {
    const ChainPoint& q = points[k * stride];
    const double hs = p.s - q.s;
    if (hs > support) break;
    const double e_before = chain.e_max;
    // The merged stretch [q.s, q.s_near] is counted at its middle.
    chain.add(hs, q.z - p.z, p.s - 0.5 * (q.s + q.s_near));
    since_rise = chain.e_max > e_before ? 0 : since_rise + 1;
  }
}

}  // namespace

std::size_t ChainHull::prune(SlicePoint p, const Falloff& rho, double tolerance) {
  std::size_t n = stack_.size(), tests = 0;
  while (n >= 2) {
    const ChainPoint& a = stack_[n - 1];
    ChainPoint& b = stack_[n - 2];
    ++tests;
    if (!higher(b, a, p) || rho(p.s - b.s) < rho(p.s - a.s_near) - tolerance) break;
    b.s_near = std::max(b.s_near, a.s_near);
    stack_.pop_back();
    --n;
  }
  return tests;
}

void ChainHull::query(SlicePoint p, double support, TangentChain& chain) const {
  if (stack_.empty()) return;
  walk(&stack_.back(), std::ptrdiff_t(stack_.size()), -1, p, support, chain);
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
    ChainPoint q{i * step, double(z[i]), i * step, i};
    // Extended on the left: the leftmost vertex a merges into q when it lies on or below the segment from q
    // to the vertex after it (so q or that vertex hides it from every receiver beyond the block) and rho at
    // q is within the tolerance of rho at a's nearest sample, seen from the nearest receiver.
    int popped = 0;
    while (hull_.size() >= 2) {
      const ChainPoint& a = hull_[hull_.size() - 1];
      const ChainPoint& c = hull_[hull_.size() - 2];
      const bool below = (a.s - q.s) * (c.z - q.z) - (a.z - q.z) * (c.s - q.s) >= 0;
      if (!below || rho(s_end - q.s) < rho(s_end - a.s_near) - tolerance) break;
      q.s_near = std::max(q.s_near, a.s_near);
      popped_.push_back(a);
      hull_.pop_back();
      ++popped;
    }
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
  walk(hull_.data(), std::ptrdiff_t(hull_.size()), 1, p, support, chain);
}

void brute_chain(const SlicePoint* pts, std::size_t count, SlicePoint p, TangentChain& chain) {
  for (std::size_t q = count; q-- > 0;) chain.add(p.s - pts[q].s, pts[q].z - p.z, p.s - pts[q].s);
}

}  // namespace hfbake
