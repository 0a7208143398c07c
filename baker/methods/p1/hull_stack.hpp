// P1 Algorithm 1: the convex-hull stack of one sweep line. Samples are added in walk order; each new
// sample's horizon (the steepest elevation to any earlier sample, no distance limit) is cast by the hull
// point just below it on the stack after popping every point that the new sample makes non-convex.
// Exactly one push per sample and fewer pops: O(1) amortised per sample.
//
// Points are (s, z): s the sample's position along the line in steps (distance = (s_new - s) * step), z its
// height.
// The pop test compares the slopes from the new point to the top two points by cross-multiplication in
// double (no division): pop the top while the point under it is at least as steep, so on ties the farther
// point casts the horizon. The stack is an upper convex hull of the points added so far.
#pragma once

#include <vector>

namespace hfbake::p1 {

// What casts a point's horizon: nothing (any = false, nothing behind the point), or the hull point dz above
// it (world units) and dist behind it (position units: steps).
template <class Pos>
struct BasicHorizonCaster {
  bool any = false;
  double dz = 0;
  Pos dist = 0;
};

// Pos = int: samples at integer indices along the line (one per column); Pos = double: arbitrary increasing
// positions, for lines sampled between columns too (HorizonLineWorker with triangle crossings).
template <class Pos>
class BasicHullStack {
 public:
  using Caster = BasicHorizonCaster<Pos>;

  // Empties the stack and makes room for `capacity` points (allocates only when it grows).
  void reset(int capacity) {
    if (int(s_.size()) < capacity) {
      s_.resize(capacity);
      z_.resize(capacity);
    }
    size_ = 0;
  }
  int size() const { return size_; }

  // Adds point (s, z), s greater than every earlier s, and returns what casts its horizon.
  Caster add(Pos s, float z) {
    Caster c;
    int top = size_ - 1;
    if (top >= 0) {
      double dz1 = double(z_[top]) - z;
      double ds1 = double(s - s_[top]);
      while (top >= 1) {
        const double dz2 = double(z_[top - 1]) - z, ds2 = double(s - s_[top - 1]);
        if (dz2 * ds1 >= dz1 * ds2) {  // the point below is at least as steep: the top is not on the hull
          dz1 = dz2;
          ds1 = ds2;
          --top;
        } else {
          break;
        }
      }
      c.any = true;
      c.dz = dz1;
      c.dist = s - s_[top];
    }
    size_ = top + 1;
    s_[size_] = s;
    z_[size_] = z;
    ++size_;
    return c;
  }

  // The horizon caster of a point (s, z) beyond every point on the stack, without adding it (receivers
  // that are not terrain, or receivers ahead of a lagging hull). The slopes from such a point to the
  // hull's vertices rise then fall, so the steepest is found by binary search.
  Caster query(Pos s, float z) const {
    Caster c;
    if (size_ == 0) return c;
    const int lo = query_index(s, z);
    c.any = true;
    c.dz = double(z_[lo]) - z;
    c.dist = s - s_[lo];
    return c;
  }

  // The stack index of query(s, z)'s caster (the stack must not be empty); the stack's points from the
  // bottom (farthest) up are position(0), height(0) .. position(size() - 1), height(size() - 1).
  int query_index(Pos s, float z) const { return first_steeper(s, z, 0, size_ - 1); }
  // query_index(s, z) found by galloping from `hint` (any index; the last query's for a neighbouring point,
  // whose caster is usually a few vertices away): the same index, in O(log d) probes for a distance d
  // instead of O(log size()). The predicate "vertex m at least as steep as m + 1" is false then true along
  // the stack, so any search for its first true index gives the binary search's answer.
  int query_index_near(Pos s, float z, int hint) const {
    const int last = size_ - 1;
    auto steeper = [&](int m) { return steeper_than_next(s, z, m); };
    const int h = hint < 0 ? 0 : (hint > last ? last : hint);
    int lo = 0, hi = last;          // the answer is in [lo, hi]
    if (h == last || steeper(h)) {  // at or before h: probe h - 1, h - 2, h - 4, ...
      hi = h;
      for (int step = 1; h - step >= 0; step *= 2) {
        if (!steeper(h - step)) {
          lo = h - step + 1;
          break;
        }
        hi = h - step;
      }
    } else {  // after h: probe h + 1, h + 2, h + 4, ... (the predicate holds at `last`)
      lo = h + 1;
      for (int step = 1; h + step < last; step *= 2) {
        if (steeper(h + step)) {
          hi = h + step;
          break;
        }
        lo = h + step + 1;
      }
    }
    return first_steeper(s, z, lo, hi);
  }
  Pos position(int i) const { return s_[i]; }
  float height(int i) const { return z_[i]; }

 private:
  // Seen from (s, z), vertex m (< size() - 1) is at least as steep as vertex m + 1 (cross-multiplied in
  // double): false then true along the stack, whose vertices' slopes from such a point rise then fall.
  bool steeper_than_next(Pos s, float z, int m) const {
    const double dza = double(z_[m]) - z, dsa = double(s - s_[m]);
    const double dzb = double(z_[m + 1]) - z, dsb = double(s - s_[m + 1]);
    return dza * dsb >= dzb * dsa;
  }
  // The first index t in [lo, hi] with steeper_than_next(t) (hi when none before it), by bisection: the
  // caster's vertex when the answer is known to lie in [lo, hi].
  int first_steeper(Pos s, float z, int lo, int hi) const {
    while (lo < hi) {
      const int m = (lo + hi) / 2;
      if (steeper_than_next(s, z, m))  // the maximum is at or before m
        hi = m;
      else
        lo = m + 1;
    }
    return lo;
  }
  std::vector<Pos> s_;
  std::vector<float> z_;
  int size_ = 0;
};

using HorizonCaster = BasicHorizonCaster<int>;
using HullStack = BasicHullStack<int>;
using HorizonCasterF = BasicHorizonCaster<double>;
using HullStackF = BasicHullStack<double>;

}  // namespace hfbake::p1
