#include "methods/ao/lsao_tangent_hull.hpp"

#include <algorithm>
#include <cstdlib>

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

namespace {

// The running band sum of a visible chain seen from one receiver.
struct ChainSum {
  const TangentMeasure* f;
  double sum = 0;
  double e_max;  // highest elevation so far (starts at the tangent)
  explicit ChainSum(const TangentMeasure& m) : f(&m), e_max(m.t) {}
  // A visible point at (hs, hz) from the receiver: adds its band if it rises above the chain.
  void add(double hs, double hz) {
    const double e = std::atan2(hz, hs);
    if (!(e > e_max)) return;
    // The band's rays meet a vertical slab at horizontal distance hs (hbao's slab estimator, exact for the
    // falloff): the cosine measure doubled, as G_t is.
    const double c = band_occlusion(f->rho, f->cosine ? Weighting::cosine : Weighting::uniform, f->frame, e_max,
                                    e, hs);
    sum += f->cosine ? 2 * c : c;
    e_max = e;
  }
};

}  // namespace

TangentHull::Chain TangentHull::query(SlicePoint p, const TangentMeasure& f) const {
  Chain c;
  c.occluder = {-1, 0};
  std::size_t n = stack_.size();
  if (n == 0) return c;
  ChainSum chain(f);
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
  c.occluder = {h1s, h1z};
  // Higher bands beyond the largest occluder, a bounded number of stack points on (none within the
  // falloff's support: stop).
  const double support = f.rho.support(1e-4);
  static const int extra = getenv("LSAO_EXTRA") ? atoi(getenv("LSAO_EXTRA")) : kChainExtra;
  for (int m = 0; m < extra && n >= 2; ++m) {
    --n;
    const double hs = p.s - stack_[n - 1].s, hz = stack_[n - 1].z - p.z;
    if (hs > support) break;
    chain.add(hs, hz);
  }
  c.sum = chain.sum;
  return c;
}

double brute_tangent_chain(const SlicePoint* pts, std::size_t count, SlicePoint p, const TangentMeasure& f,
                           bool visible_only, SlicePoint* occluder) {
  ChainSum chain(f);
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
