// lsao's receiver-tangent strategy for a field seen from above (issue 19 item 3): P3's obscurance hull, one
// per tangent bin, queried with each texel's own tangent and summed along the hull's visible chain.
//
// P3's fixed tangent (sin t = -0.85, strategy 3) is a screen-space choice: an occluder counts only once it
// lifts that tangent past the horizontal, so the gentle occluders of terrain count for nothing. Here the
// tangent of a receiver towards direction D is its own (P3 strategy 1, digest §2: t = atan2(-n.D, n.z)),
// and each occluder is valued with the contract's cosine-weighted measure of the slice band it hides above
// that tangent (or the uniform one), for an in-slice normal perpendicular to t:
//     G_t(e) = 2 int_t^e sin(e' - t) cos e' de' = sin^2 e cos t - sin e cos e sin t - (e - t) sin t  (cosine)
//     G_t(e) = sin e - sin t                                                                     (uniform)
// for e > t, else 0; G_0(e) = sin^2 e is P3's W(sin e) with the tangent at the horizontal. A receiver's
// value in direction D scales the cosine measure by |(n.D, n.z)| (the normal's length in the slice), as
// hbao's slice integral does (slice_integral.hpp), so opposite directions cancel on a plane.
//
// The hull's pop rule depends on the tangent, so one hull is kept per tangent bin t_b (B bins evenly in
// [-kTangentBinLimit, kTangentBinLimit]); every line sample prunes each bin's hull with P3's rule for
// F_b = rho(|h|) G_{t_b}(e(h)) (O(1) amortised per bin). A receiver with tangent t reads the two bins whose
// tangents bracket t, each walked with its own exact F_t, and keeps the larger: exact at the bin tangents
// and continuous between them (the walk of a bin's hull finds that bin's largest occluder).
//
// Chain: the single largest occluder (P3 Eq. 1) under-occludes with a falloff, since the true obscurance
// sums every visible band, each at its own distance (hbao's slab estimator). The walk from the top of the
// stack to the largest occluder visits points of rising elevation (P3's pop rule), i.e. visible bands; the
// query sums their bands as hbao's slab estimator does (band_occlusion: the band between the chain's previous
// elevation and e_i, each ray weighted by rho at its own distance x_i / cos e to the slab at x_i), then follows the stack a bounded
// number of points further (kChainExtra) for higher bands beyond the largest occluder. Cost per query stays
// O(1) amortised and independent of the radius. With falloff none or step (inside the radius) the bands
// telescope to G_t of the horizon: the exact horizon-based obscurance of the line samples.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include "methods/ao/falloff.hpp"
#include "methods/ao/obscurance_hull.hpp"
#include "methods/ao/slice_integral.hpp"

namespace hfbake {

// The tangent bins: B tangents evenly spaced in [-limit, limit] (B = 1: the horizontal alone).
constexpr double kTangentBinLimit = 1.3;  // radians (74.5 degrees)
constexpr int kChainExtra = 4;            // stack points followed past the largest occluder
double tangent_bin_angle(int bin, int bins);

// The band measure G_t above one tangent t (file comment), and the per-occluder value rho(|h|) G_t(e(h)).
struct TangentMeasure {
  Falloff rho;
  bool cosine = true;
  double t = 0, sin_t = 0, cos_t = 1;
  SliceFrame frame;  // the unit in-slice normal perpendicular to t (for the chain's bands)

  TangentMeasure() = default;
  TangentMeasure(const Falloff& f, ObscuranceWeighting w, double tangent)
      : rho(f), cosine(w == ObscuranceWeighting::cosine), t(tangent), sin_t(std::sin(tangent)),
        cos_t(std::cos(tangent)), frame{-sin_t, cos_t, tangent} {}

  // G_t of elevation e (sin e, cos e given): 0 at or below t.
  double band(double e, double sin_e, double cos_e) const {
    if (!(e > t)) return 0.0;
    if (!cosine) return sin_e - sin_t;
    return std::max(0.0, sin_e * sin_e * cos_t - sin_e * cos_e * sin_t - (e - t) * sin_t);
  }
  // Occluder at vector (hs, hz) from the receiver, hs > 0: rho at the horizontal distance, as the chain's
  // slab bands and the window count it (P3 takes |h|; on steep ground that drops occluders the bands count).
  double operator()(double hs, double hz) const {
    const double d = std::sqrt(hs * hs + hz * hz);
    const double e = std::atan2(hz, hs);
    const double g = band(e, hz / d, hs / d);
    return g > 0 ? g * rho(hs) : 0.0;
  }
};

// The running band sum of a visible chain seen from one receiver, nearest point first: each point that rises
// above the chain adds the band between the chain's elevation and its own (starting at the tangent).
struct TangentChain {
  const TangentMeasure* f;
  double sum = 0;  // G_t units (before the slice-length factor)
  double e_max;    // highest elevation so far (starts at the tangent)
  explicit TangentChain(const TangentMeasure& m) : f(&m), e_max(m.t) {}
  void add(double hs, double hz);  // a point at (hs > 0, hz) from the receiver
};

// One tangent bin's hull on one line: P3's stack, pruned with that bin's measure. Reuse per thread.
class TangentHull {
 public:
  void reserve(std::size_t n) { stack_.reserve(n); }
  void clear() { stack_.clear(); }
  // P3 Alg. 1's pruning for receiver p (a line sample) with the bin's measure; returns the loop tests.
  std::size_t prune(SlicePoint p, const TangentMeasure& f);
  void push(SlicePoint p) { stack_.push_back(p); }
  std::size_t size() const { return stack_.size(); }
  // Walks the stack for receiver p with the chain's measure (its own tangent), without popping: from the top
  // to the largest occluder by P3's rule, then kChainExtra points on; adds the visited points to `chain`.
  // Returns the largest occluder (vector receiver -> occluder; s = -1: none).
  SlicePoint query(SlicePoint p, TangentChain& chain) const;

 private:
  std::vector<SlicePoint> stack_;
};

// The window (samples) of falloff f on a line of step `step`: 0 when the falloff never ends (none,
// exponential, rational: one hull per bin over the whole line, as P3).
int tangent_window(const Falloff& f, double step);

// Falloffs that end (step, linear, smooth): the window of W samples a receiver sees (hs <= W step <= R), cut
// in blocks of W samples. P3's pruning is only sound while every point it compares stays inside the window
// (a point popped for a farther, higher one is lost when that one leaves the window: at R = 8 texels this
// was most of the hull's error), so the bins' hulls restart at each block and hold only the current block;
// the previous block's part of the window, [n - W, block start), is this upper convex hull, built once per
// block from its right end leftwards with an undo log, and shrunk from its left end as the window moves on
// (each point inserted and undone once: O(1) amortised per sample, whatever the radius). From a receiver to
// the right of the block, the horizon over any suffix is the tangent point of its upper hull.
class WindowHull {
 public:
  void reserve(std::size_t n);
  // Builds the hull of the line's samples [begin, end) that are terrain (in [inside_begin, inside_end));
  // sample i at s = i * step, height z[i].
  void build(const float* z, int begin, int end, int inside_begin, int inside_end, double step);
  // Drops the samples before `first` (the window's start).
  void drop_before(int first);
  bool empty() const { return hull_.empty(); }
  // Walks from the block's nearest hull vertex to the tangent point of receiver p, adding each to `chain`.
  // Returns the last vertex visited (vector receiver -> vertex) or s = -1 when empty.
  SlicePoint query(SlicePoint p, TangentChain& chain) const;

 private:
  struct Vertex {
    SlicePoint p;
    int index;
  };
  std::vector<Vertex> hull_;    // right to left: hull_[0] the block's last terrain sample, back() the leftmost
  std::vector<Vertex> popped_;  // undo log: vertices each insertion removed
  std::vector<int> inserted_;   // per insertion (right to left): the sample index and how many it popped
  std::vector<int> pops_;
};

// Brute force over every earlier sample for receiver p, the samples in walk order: visible_only: the slab sum
// over every visible band (the chain the hull approximates); otherwise the single largest occluder over all
// samples. O(M) per receiver: tests and measurements.
double brute_tangent_chain(const SlicePoint* pts, std::size_t count, SlicePoint p, const TangentMeasure& f,
                           bool visible_only, SlicePoint* occluder = nullptr);

}  // namespace hfbake
