// P1 Algorithm 1: the convex-hull stack of one sweep line. Samples are added in walk order; each new
// sample's horizon (the steepest elevation to any earlier sample, no distance limit) is cast by the hull
// point just below it on the stack after popping every point that the new sample makes non-convex.
// Exactly one push per sample and fewer pops: O(1) amortised per sample.
//
// Points are (n, z): n the sample's index along the line (distance = (n_new - n) * step), z its height.
// The pop test compares the slopes from the new point to the top two points by cross-multiplication in
// double (no division): pop the top while the point under it is at least as steep, so on ties the farther
// point casts the horizon. The stack is an upper convex hull of the points added so far.
#pragma once

#include <vector>

namespace hfbake::p1 {

struct HorizonCaster {
  int n = -1;     // index of the casting sample, -1: none (nothing behind the sample)
  double dz = 0;  // its height above the receiver (world units)
  int dn = 0;     // its distance in steps (> 0 when n >= 0)
};

class HullStack {
 public:
  // Empties the stack and makes room for `capacity` points (allocates only when it grows).
  void reset(int capacity) {
    if (int(n_.size()) < capacity) {
      n_.resize(capacity);
      z_.resize(capacity);
    }
    size_ = 0;
  }
  int size() const { return size_; }

  // Adds sample (n, z), n greater than every earlier n, and returns what casts its horizon.
  HorizonCaster add(int n, float z) {
    HorizonCaster c;
    int top = size_ - 1;
    if (top >= 0) {
      double dz1 = double(z_[top]) - z;
      double dn1 = double(n - n_[top]);
      while (top >= 1) {
        const double dz2 = double(z_[top - 1]) - z, dn2 = double(n - n_[top - 1]);
        if (dz2 * dn1 >= dz1 * dn2) {  // the point below is at least as steep: the top is not on the hull
          dz1 = dz2;
          dn1 = dn2;
          --top;
        } else {
          break;
        }
      }
      c.n = n_[top];
      c.dz = dz1;
      c.dn = int(dn1);
    }
    size_ = top + 1;
    n_[size_] = n;
    z_[size_] = z;
    ++size_;
    return c;
  }

  // The horizon caster of a point (n, z) beyond every point on the stack, without adding it (receivers
  // that are not terrain). The slopes from such a point to the hull's vertices rise then fall, so the
  // steepest is found by binary search.
  HorizonCaster query(int n, float z) const {
    HorizonCaster c;
    if (size_ == 0) return c;
    // First index t such that vertex t + 1 is not steeper than vertex t (seen from (n, z)).
    int lo = 0, hi = size_ - 1;
    while (lo < hi) {
      const int m = (lo + hi) / 2;
      const double dza = double(z_[m]) - z, dna = double(n - n_[m]);
      const double dzb = double(z_[m + 1]) - z, dnb = double(n - n_[m + 1]);
      if (dza * dnb >= dzb * dna)  // vertex m at least as steep as m + 1: the maximum is at or before m
        hi = m;
      else
        lo = m + 1;
    }
    c.n = n_[lo];
    c.dz = double(z_[lo]) - z;
    c.dn = n - n_[lo];
    return c;
  }

 private:
  std::vector<int> n_;
  std::vector<float> z_;
  int size_ = 0;
};

// The same hull over points at arbitrary increasing positions (double), for lines sampled between columns
// too (HorizonLineWorker with triangle crossings). ds: distance to the caster in position units (0: none).
struct HorizonCasterF {
  bool any = false;
  double dz = 0, ds = 0;
};

class HullStackF {
 public:
  void reset(int capacity) {
    if (int(s_.size()) < capacity) {
      s_.resize(capacity);
      z_.resize(capacity);
    }
    size_ = 0;
  }
  int size() const { return size_; }
  void add(double s, float z) {  // s greater than every earlier s; pops the points the new one hides
    int top = size_ - 1;
    if (top >= 1) {
      double dz1 = double(z_[top]) - z, ds1 = s - s_[top];
      while (top >= 1) {
        const double dz2 = double(z_[top - 1]) - z, ds2 = s - s_[top - 1];
        if (dz2 * ds1 >= dz1 * ds2) {
          dz1 = dz2, ds1 = ds2;
          --top;
        } else {
          break;
        }
      }
    }
    size_ = top + 1;
    s_[size_] = s;
    z_[size_] = z;
    ++size_;
  }
  // The steepest point seen from (s, z), s beyond every point on the stack (binary search, as HullStack).
  HorizonCasterF query(double s, float z) const {
    HorizonCasterF c;
    if (size_ == 0) return c;
    int lo = 0, hi = size_ - 1;
    while (lo < hi) {
      const int m = (lo + hi) / 2;
      const double dza = double(z_[m]) - z, dsa = s - s_[m];
      const double dzb = double(z_[m + 1]) - z, dsb = s - s_[m + 1];
      if (dza * dsb >= dzb * dsa)
        hi = m;
      else
        lo = m + 1;
    }
    c.any = true;
    c.dz = double(z_[lo]) - z;
    c.ds = s - s_[lo];
    return c;
  }

 private:
  std::vector<double> s_;
  std::vector<float> z_;
  int size_ = 0;
};

}  // namespace hfbake::p1
