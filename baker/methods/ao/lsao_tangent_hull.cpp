#include "methods/ao/lsao_tangent_hull.hpp"

#include <algorithm>

namespace hfbake {

double tangent_bin_angle(int bin, int bins) {
  if (bins <= 1) return 0.0;
  return -kTangentBinLimit + 2.0 * kTangentBinLimit * double(bin) / double(bins - 1);
}

std::size_t TangentHull::prune(SlicePoint p, const TangentMeasure& f) {
  std::size_t n = stack_.size(), tests = 0;
  if (n < 2) return 0;
  double h1s = p.s - stack_[n - 1].s, h1z = stack_[n - 1].z - p.z;
  double o1 = f(h1s, h1z);
  while (n >= 2) {
    const SlicePoint b = stack_[n - 2];
    const double h2s = p.s - b.s, h2z = b.z - p.z;
    const double o2 = f(h2s, h2z);
    ++tests;
    // P3's rule: the second casts more AND is higher (slopes compare elevations: hs > 0).
    if (!(o1 < o2 && h1z * h2s < h2z * h1s)) break;
    stack_.pop_back();
    --n;
    h1s = h2s, h1z = h2z, o1 = o2;
  }
  return tests;
}

void TangentChain::add(double hs, double hz) {
  const double e = std::atan2(hz, hs);
  if (!(e > e_max)) return;
  // The band's rays meet a vertical slab at horizontal distance hs (hbao's slab estimator, exact for the
  // falloff): the cosine measure doubled, as G_t is.
  const double c =
      band_occlusion(f->rho, f->cosine ? Weighting::cosine : Weighting::uniform, f->frame, e_max, e, hs);
  sum += f->cosine ? 2 * c : c;
  e_max = e;
}

SlicePoint TangentHull::query(SlicePoint p, TangentChain& chain) const {
  std::size_t n = stack_.size();
  if (n == 0) return {-1, 0};
  const TangentMeasure& f = *chain.f;
  double h1s = p.s - stack_[n - 1].s, h1z = stack_[n - 1].z - p.z;
  double o1 = f(h1s, h1z);
  chain.add(h1s, h1z);
  while (n >= 2) {
    const SlicePoint b = stack_[n - 2];
    const double h2s = p.s - b.s, h2z = b.z - p.z;
    const double o2 = f(h2s, h2z);
    if (!(o1 < o2 && h1z * h2s < h2z * h1s)) break;
    --n;
    h1s = h2s, h1z = h2z, o1 = o2;
    chain.add(h1s, h1z);
  }
  const SlicePoint occluder{h1s, h1z};
  // Higher bands beyond the largest occluder, a bounded number of stack points on (none beyond the
  // falloff's support: stop).
  const double support = f.rho.support(1e-4);
  for (int m = 0; m < kChainExtra && n >= 2; ++m) {
    --n;
    const double hs = p.s - stack_[n - 1].s, hz = stack_[n - 1].z - p.z;
    if (hs > support) break;
    chain.add(hs, hz);
  }
  return occluder;
}

int tangent_window(const Falloff& f, double step) {
  switch (f.kind) {
    case FalloffKind::step:
    case FalloffKind::linear:
    case FalloffKind::smooth:
      return std::max(1, int(std::min(1e9, std::floor(f.radius / step + 1e-9))));
    default:
      return 0;
  }
}

void WindowHull::reserve(std::size_t n) {
  hull_.reserve(n);
  popped_.reserve(n);
  inserted_.reserve(n);
  pops_.reserve(n);
}

void WindowHull::build(const float* z, int begin, int end, int inside_begin, int inside_end, double step) {
  hull_.clear();
  popped_.clear();
  inserted_.clear();
  pops_.clear();
  for (int i = std::min(end, inside_end); i-- > std::max(begin, inside_begin);) {
    const SlicePoint q{i * step, double(z[i])};
    // Upper hull, extended on the left: drop the leftmost vertex while it lies on or below the segment
    // from q to the vertex after it.
    int popped = 0;
    while (hull_.size() >= 2) {
      const SlicePoint a = hull_[hull_.size() - 1].p, b = hull_[hull_.size() - 2].p;
      // a is below (or on) segment q-b: cross((a - q), (b - q)) >= 0.
      if ((a.s - q.s) * (b.z - q.z) - (a.z - q.z) * (b.s - q.s) < 0) break;
      popped_.push_back(hull_.back());
      hull_.pop_back();
      ++popped;
    }
    hull_.push_back({q, i});
    inserted_.push_back(i);
    pops_.push_back(popped);
  }
}

void WindowHull::drop_before(int first) {
  while (!inserted_.empty() && inserted_.back() < first) {
    hull_.pop_back();  // the last insertion is the leftmost vertex
    for (int k = pops_.back(); k > 0; --k) {
      hull_.push_back(popped_.back());
      popped_.pop_back();
    }
    inserted_.pop_back();
    pops_.pop_back();
  }
}

SlicePoint WindowHull::query(SlicePoint p, TangentChain& chain) const {
  if (hull_.empty()) return {-1, 0};
  double hs = p.s - hull_[0].p.s, hz = hull_[0].p.z - p.z;
  chain.add(hs, hz);
  for (std::size_t k = 1; k < hull_.size(); ++k) {
    const double s2 = p.s - hull_[k].p.s, z2 = hull_[k].p.z - p.z;
    if (!(hz * s2 < z2 * hs)) break;  // the next vertex is no higher: the tangent point is passed
    hs = s2, hz = z2;
    chain.add(hs, hz);
  }
  return {hs, hz};
}

double brute_tangent_chain(const SlicePoint* pts, std::size_t count, SlicePoint p, const TangentMeasure& f,
                           bool visible_only, SlicePoint* occluder) {
  TangentChain chain(f);
  double best = 0;
  for (std::size_t q = count; q-- > 0;) {
    const double hs = p.s - pts[q].s, hz = pts[q].z - p.z;
    if (visible_only) {
      chain.add(hs, hz);
    } else {
      const double v = f(hs, hz);
      if (v > best) {
        best = v;
        if (occluder) *occluder = {hs, hz};
      }
    }
  }
  return visible_only ? chain.sum : best;
}

}  // namespace hfbake
