// The convex hull tree of P2 (Timonen 2012, "Low-Complexity Intervisibility in Height Fields", §4-5):
// for every sample R of a line, the local visibility horizons of R, i.e. the samples behind R that start
// each visible stretch of the line, in time linear in the number of horizons (t <= 2m + n, P2 §6).
//
// A line is a sequence of samples p_0, p_1, ... at unit spacing (distance d_i = i, in steps), or at any
// increasing positions x_i (push_at: P2's exact line profiles, whose samples are the columns and the row and
// diagonal crossings between them), with heights h_i (any unit; visibility depends only on the order of
// slopes). Seen from the receiver R = p_r, the slope of an earlier sample p_j is
//     s_r(j) = (h_j - h_r) / (x_r - x_j)      (computed in double exactly like this, see visibility_slope)
// and p_j is VISIBLE from R when it strictly exceeds the slope of every sample between it and R:
//     s_r(j) > max_{j < l < r} s_r(l)         (p_{r-1} is always visible).
// A sample collinear with a nearer sample and R grazes it and is hidden (ties hide). Both this tree and
// the naive march (naive_visibility.hpp) compare the same computed slopes, so the visible sets are
// identical (tests/p2/test_hull_tree.cpp).
//
// The tree (P2 §4): the union of the upper convex hulls from the first sample of every convex section
// (Eq. 1 with collinear triples counted as convex, see hull_tree.cpp; segment starts are permanent
// leaves) to R; R is the root, children are ordered farthest first;
// the root's direct children are the local horizons. Hulls keep collinear points (the tie rule above):
// a child is detached from its parent only when it is strictly above the line of sight root -> parent.
// Adding a sample makes it the new root with the old root as only child and repairs convexity
// recursively (Algorithm 1: "deeper" and "wider"); instead of duplicating a segment's first sample as a
// separate leaf (Algorithm 1 / ProcessLineP2) the node itself is marked permanent and never deleted when
// orphaned, which is the same tree without the duplicate horizon.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace hfbake {

// The slope of sample j seen from receiver r > j: the one number both methods compare.
inline double visibility_slope(const double* h, int j, int r) {
  return (h[j] - h[r]) / double(r - j);
}
// The same for samples at positions x (increasing; x[j] = j gives the same bits as above, since
// double(r) - double(j) is exact). x null: unit spacing.
inline double visibility_slope(const double* h, const double* x, int j, int r) {
  return (h[j] - h[r]) / (x ? x[r] - x[j] : double(r - j));
}

class HullTree {
 public:
  // Starts a new line of at most `capacity` samples (allocates only when capacity grows).
  void reset(int capacity);

  // Appends the next sample (its height) and updates the tree; afterwards horizons() are those of it.
  // push: at position size() (unit spacing); push_at: at position x, beyond every earlier one (a line is
  // pushed one way or the other from its reset).
  void push(double height) { push_at(double(n_), height); }
  void push_at(double x, double height);

  int size() const { return n_; }

  // The local horizons of the last pushed sample: sample indices, farthest first (strictly increasing).
  // Empty for the first sample of a line. The first one casts the global horizon (the largest slope).
  std::span<const int> horizons() const { return {horizons_.data(), std::size_t(nh_)}; }
  // Their slopes seen from the last pushed sample, the same numbers visibility_slope gives.
  std::span<const double> horizon_slopes() const { return {horizon_slopes_.data(), std::size_t(nh_)}; }

  // The local horizons of a receiver that is not terrain: at position `x` beyond the last pushed sample
  // (unit spacing: its index >= size(); a gap of non-terrain samples may lie between them) with height
  // `height`, seeing the pushed samples only. The same traversal as push() without changing the tree; the
  // last pushed sample is always listed (it is visible; run_starts drops it when it does not start a
  // run). Returns the checks made.
  std::uint64_t query(double x, double height, std::vector<int>& horizons);
  // The same into horizons[0..m) and their slopes seen from the receiver (visibility_slope's numbers) into
  // slopes[0..m), both with room for size() entries; returns m and adds the checks made to *checks.
  int query(double x, double height, int* horizons, double* slopes, std::uint64_t* checks);

  // Convexity checks performed (P2's iterations t), summed over the line so far (push only).
  std::uint64_t iterations() const { return iterations_; }

 private:
  // One sample, everything a traversal reads of it in one place.
  struct Node {
    double h, x;       // height and position
    int first_child;   // farthest child (-1: none)
    int next_sibling;  // the next nearer child of its parent (-1: none)
    int permanent;     // a segment start (never deleted when orphaned)
    int pad;
  };
  struct Frame {
    int parent;    // the node whose children are being scanned
    int child;     // the next child to test (-1: none left)
    double slope;  // the parent's slope seen from the root
  };
  std::vector<Node> nodes_;
  std::vector<Frame> stack_;  // capacity + 1 frames (the deepest chain)
  std::vector<int> horizons_;
  std::vector<double> horizon_slopes_;
  int nh_ = 0;  // horizons of the last pushed sample
  int n_ = 0;
  int prev_class_ = 1;  // class of the last classified sample: 1 convex, 0 concave
  bool unit_ = true;    // every sample so far at x_i = i (Eq. 1 in its unit-spacing form)
  std::uint64_t iterations_ = 0;
};

// A visible stretch of the line seen from a receiver r: samples first..last (first <= last < r) are
// visible, and the segment from `last` to `last + 1` is visible down to the slope `end_slope` (the next
// horizon's slope), or, for the stretch nearest to R, it ends at R (end_slope = -infinity, last = r - 1).
struct VisibleStretch {
  int first = 0, last = 0;
  double end_slope = 0;
};

// Walks from each horizon towards R while the samples stay above the next horizon (P2 §10.1, method 3).
// `out` is cleared and filled nearest-last. Cost: the number of visible samples. x: the samples'
// positions (null: unit spacing).
void visible_stretches(const double* h, int r, std::span<const int> horizons,
                       std::vector<VisibleStretch>& out, const double* x = nullptr);

}  // namespace hfbake
