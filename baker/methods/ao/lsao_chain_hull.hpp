// lsao's receiver-tangent strategy for a field seen from above: per line a hull of the
// visible chain's points, walked from each texel with its own tangent, the chain's bands summed as hbao's
// slab estimator sums them.
//
// Why: P3's fixed tangent (sin t = -0.85, strategy 3) is a screen-space choice: an occluder counts only once
// it lifts that tangent past the horizontal, so the gentle occluders of terrain count for nothing (gentle
// craters, smooth R = 32: 98 % of the occlusion missing). Here the tangent of a texel towards direction D is
// its own (P3 strategy 1: t = atan2(-n.D, n.z)); the obscurance of the slice is the contract's
// cosine-weighted (or uniform) measure of the bands between that tangent and the horizon, each band weighted
// by rho at the distance where its rays meet the terrain (band_occlusion: a vertical slab at the point's
// horizontal distance, hbao's estimator), scaled by the normal's length in the slice. A single largest
// occluder (P3 Eq. 1) under-occludes with a falloff, since the bands nearer than it carry more weight.
//
// The hull (ChainHull) is tangent-free: the sweep's line samples prune it as P3's Alg. 1 does, with a pop
// rule that keeps what the chain needs: the top a is merged into the point b below it when b is higher seen
// from the sample (a cannot be the horizon of a later receiver beyond b's line) and rho at b differs from rho
// at the nearest point a stands for by at most `tolerance` (the merged bands are then counted at the middle
// of the distances they stand for). With falloff none or a step (inside the radius) this is the convex hull
// of P1 and the sum telescopes to the exact horizon obscurance of the line samples; with a smooth falloff the
// hull keeps about 1 / tolerance points per falloff range whatever the radius. With a near field (lsao's
// surface triangles) a point is pushed only once it lies the near radius behind the receivers, after a prune
// from there (lsao.cpp): judged from the adjacent sample, the surface's small kinks, which no receiver
// farther on sees, would decide them, and the hull would grow with the radius. A query walks from the top
// outwards, adding each point that rises above the chain (a merged point: its near end at its own distance,
// then the point itself, counted at the middle of the stretch when the near end rose), and stops where no
// point farther on can rise (zmax) or beyond the falloff's support.
//
// Falloffs that end (step, linear, smooth): a receiver sees a window of W samples (hs <= W step <= R).
// Pruning is only sound while the points it compares stay inside the window (a point merged into a farther
// one is lost when that one leaves it: at R = 8 texels that was most of the error), so the hull restarts at
// each block of W samples and holds only the current block; the window's part in the previous block is a
// WindowHull: the same rule built once per block from its right end leftwards with an undo log, and shrunk
// from its left end as the window moves on. Each point is pushed and popped (inserted and undone) once: O(1)
// amortised per sample and independent of the radius.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "methods/ao/falloff.hpp"
#include "methods/ao/obscurance_hull.hpp"
#include "methods/ao/slice_integral.hpp"

namespace hfbake {

// The window (samples) of falloff f on a line of step `step`: 0 when the falloff never ends (none,
// exponential, rational: one hull over the whole line, as P3).
int chain_window(const Falloff& f, double step);

// The running band sum of the visible chain seen from one receiver, nearest point first.
struct TangentChain {
  Falloff rho;
  Weighting weighting = Weighting::cosine;
  SliceFrame frame;   // the unit in-slice normal perpendicular to the receiver's tangent
  double length = 1;  // the receiver's normal's length in the slice, |(n.D, n.z)|
  double sum = 0;  // the occluded measure (cosine: doubled, so a horizon e over a level texel gives sin^2 e)
  double e_max;    // highest elevation so far (starts at the tangent)
  double slope_max;             // tan e_max: rising points are found without a trigonometric call
  bool want_direction = false;  // also sum the bands' rho-weighted cosine direction (band_direction)
  SliceVec direction;           // that sum, for the unit in-slice normal (bent normals)

  // `slice`: the receiver's normal in the slice (n.D, n.z), any positive length.
  // Segments (when set): a rising point's band meets the straight piece of profile from the point added
  // before it (the receiver first) instead of a vertical slab at x. Falloffs none and step:
  // segment_band_occlusion's closed form, exact when the points are the profile's consecutive vertices (as
  // hbao's segment estimator); other falloffs (whose segment integral needs Gauss-Legendre): the slab's
  // closed form at the horizontal distance where the band's middle ray meets the segment.
  bool segments = false;
  SliceVec prev;  // the point added last, relative to the receiver
  // Work counters (LsaoStats): the walks' steps over the hulls (a skipped block one step), bands added.
  unsigned walked = 0, bands = 0;

  TangentChain(const Falloff& f, Weighting w, const SliceFrame& slice);
  // A point at (hs > 0, hz) from the receiver standing for the profile's stretch at horizontal distances
  // around x: adds the band from the chain's elevation up to its own, if it rises above it.
  void add(double hs, double hz, double x) {
    const SliceVec from = prev;
    prev = {hs, hz};
    if (hz > slope_max * hs) rise(hs, hz, x, from);
  }
  // Coalescing (segments only; 0: off): a rising point whose band's rho is within `coalesce` of the pending
  // band's first is added to it (falloffs none and step inside the radius: always, the bands then add
  // exactly). finish() integrates what is pending: call it before reading sum and direction.
  double coalesce = 0;
  void finish();

 private:
  // Falloffs with closed forms (slab_degree >= 0): the bands are adjacent, so each band's lower end is the
  // last one's upper end, e_max, whose cosine, sine and antiderivatives (slab_primitives) are kept.
  int degree_ = -1;
  double c_max_ = 1, s_max_ = 0;
  bool have_max_ = false;
  SlabPrimitives at_max_;
  // The pending band's top point (relative to the receiver, its cosine and sine) and the distances of its
  // first and last points' bands.
  bool pending_ = false;
  double pend_hs_ = 0, pend_hz_ = 0, pend_c_ = 1, pend_s_ = 0, pend_x0_ = 0, pend_x1_ = 0;
  // A pending band's later points whose band ends all lie where rho is within `coalesce` of rho(pend_x0_)
  // (rho is monotone, so whatever distance their middle ray meets) are held without their unit vectors and
  // distances: `lazy_` until resolve() finds the top's from the top, the point before it (before_) and the
  // segment's start (pend_from_), as add_closed would have. rho_x0_: rho(pend_x0_); checked_: the farthest
  // distance whose rho was found within `coalesce` of it.
  bool lazy_ = false;
  double rho_x0_ = 0, checked_ = 0;
  SliceVec before_, pend_from_;
  void rise(double hs, double hz, double x, SliceVec from);
  void add_closed(double hs, double hz, double x, SliceVec from, SliceVec at);
  void resolve();
  void commit(double e, double c, double sn, const SlabPrimitives* at_e);
};

// A hull point: its position; the nearest sample merged into it (near_s >= s; itself when none): the near end
// of the stretch of profile it stands for; and zmax, the highest height of it, its near end and every point
// farther on in its hull (what lets a walk stop once nothing farther can rise above the chain).
struct ChainPoint {
  double s = 0, z = 0;
  double near_s = 0, near_z = 0;
  double zmax = 0;
  int index = 0;  // WindowHull: the sample index
  // The highest of z and near_z over the point's block of its hull: the stack positions
  // [i + 1 - lowbit(i + 1), i] of its position i (a Fenwick tree's ranges, so a query passes over a block
  // that cannot rise in one test: O(log) blocks cover the rest of a walk).
  double bmax = 0;
};

// One line's hull. Reuse one per thread (clear() keeps the capacity).
class ChainHull {
 public:
  void reserve(std::size_t n) { stack_.reserve(n); }
  void clear() { stack_.clear(); }
  // Prunes the top for receiver p (a line sample); returns the loop tests.
  std::size_t prune(SlicePoint p, const Falloff& rho, double tolerance);
  void push(SlicePoint p);
  std::size_t size() const { return stack_.size(); }
  // Adds the chain of receiver p (not necessarily a sample), without popping; support: the falloff's. Points
  // nearer than `near` (world units along the line) are left out (lsao's near field marched them).
  void query(SlicePoint p, double support, TangentChain& chain, double near = 0) const;

 private:
  std::vector<ChainPoint> stack_;
};

// The previous block's part of the window (file comment).
class WindowHull {
 public:
  void reserve(std::size_t n);
  void clear();
  // Builds the hull of the block's terrain points[0..count) (walk order: s increasing; index: the sample
  // whose group the point belongs to, for drop_before); merges judged from the nearest receiver at s_end.
  void build(const ChainPoint* points, std::size_t count, double s_end, const Falloff& rho, double tolerance);
  void drop_before(int first);  // undoes the samples before the window's start
  void query(SlicePoint p, double support, TangentChain& chain, double near = 0) const;

 private:
  std::vector<ChainPoint> hull_;    // right to left: hull_[0] the block's last terrain sample
  std::vector<ChainPoint> popped_;  // undo log: the vertices each insertion removed, in order
  std::vector<int> pops_;           // per insertion (right to left): how many it removed
  std::vector<double> prefix_;      // build: the highest of points[0..k]
};

// Brute force for receiver p over every earlier sample pts[0..count) (in walk order): the band sum over
// every visible sample, each at its own distance (what the hull's chain approximates). O(M): tests and
// measurements. Samples nearer than `near` are left out (as ChainHull::query).
void brute_chain(const SlicePoint* pts, std::size_t count, SlicePoint p, TangentChain& chain,
                 double near = 0);

}  // namespace hfbake
