#include "methods/p2/hull_tree.hpp"

#include <limits>

namespace hfbake {

void HullTree::reset(int capacity) {
  if (std::size_t(capacity) > h_.size()) {
    h_.resize(capacity);
    x_.resize(capacity);
    first_child_.resize(capacity);
    next_sibling_.resize(capacity);
    permanent_.resize(capacity);
    stack_.reserve(capacity + 1);
    horizons_.reserve(capacity + 1);
  }
  n_ = 0;
  prev_class_ = 1;
  unit_ = true;
  iterations_ = 0;
  horizons_.clear();
}

void HullTree::push_at(double x, double height) {
  const int r = n_++;
  h_[r] = height;
  x_[r] = x;
  if (x != double(r)) unit_ = false;
  first_child_[r] = -1;
  next_sibling_[r] = -1;
  permanent_[r] = 0;
  horizons_.clear();
  if (r == 0) {  // p_0 starts the first convex section: a permanent leaf
    permanent_[0] = 1;
    return;
  }
  const double* h = h_.data();
  const double* xs = x_.data();
  // Eq. 1 for p_{r-1}, now that its successor is known: convex if 2 h_i >= h_{i-1} + h_{i+1}, else
  // concave. (P2's Eq. 1 lets a collinear triple inherit the previous class; with the strict tie rule a
  // collinear p_{r-1} after a concave stretch starts a visible run -- {0, 5, 1, 1, 1} seen from the last
  // sample -- so collinear triples count as convex here.) A convex sample after a concave one starts a
  // segment: a permanent leaf. Marked before the repair below, so the old root survives it even when all
  // its children move away. At any positions: convex if the slope into p_i is not below the slope out of
  // it, (h_i - h_{i-1}) (x_{i+1} - x_i) >= (h_{i+1} - h_i) (x_i - x_{i-1}).
  if (r >= 2) {
    const int i = r - 1;
    const double lhs = unit_ ? 2 * h[i] : (h[i] - h[i - 1]) * (xs[i + 1] - xs[i]);
    const double rhs = unit_ ? h[i - 1] + h[i + 1] : (h[i + 1] - h[i]) * (xs[i] - xs[i - 1]);
    const int cls = lhs >= rhs ? 1 : 0;
    if (cls == 1 && prev_class_ == 0) permanent_[i] = 1;
    prev_class_ = cls;
  }

  // The new root r has the old root r-1 as its only child. Repair (Algorithm 1, iteratively): scan the
  // children of a node P attached to the root, farthest first; a child strictly above the line of sight
  // root -> P leaves P for the root (placed before P) and its own children are scanned the same way
  // (deeper); the scan of P goes on with P's next child (wider) and stops at the first child that passes,
  // since children are ordered by their angle from P. P stays a root child while it keeps a child or is
  // permanent. Emitting nodes in post-order gives the root's children farthest first.
  int tail = -1;
  auto append = [&](int node) {
    if (tail < 0)
      first_child_[r] = node;
    else
      next_sibling_[tail] = node;
    next_sibling_[node] = -1;
    tail = node;
    horizons_.push_back(node);
  };
  stack_.clear();
  stack_.push_back({r - 1, first_child_[r - 1], visibility_slope(h, xs, r - 1, r)});
  while (!stack_.empty()) {
    Frame& f = stack_.back();
    if (f.child >= 0) {
      ++iterations_;
      const double s = visibility_slope(h, xs, f.child, r);
      if (s > f.slope) {
        const int c = f.child;
        f.child = next_sibling_[c];
        stack_.push_back({c, first_child_[c], s});
        continue;
      }
    }
    const int p = f.parent;
    first_child_[p] = f.child;
    const bool keep = f.child >= 0 || permanent_[p];
    stack_.pop_back();
    if (keep) append(p);
  }
}

std::uint64_t HullTree::query(double x, double height, std::vector<int>& horizons) {
  horizons.clear();
  if (n_ == 0) return 0;
  const double* h = h_.data();
  const double* xs = x_.data();
  auto slope = [&](int j) { return (h[j] - height) / (x - xs[j]); };  // == visibility_slope
  std::uint64_t checks = 0;
  stack_.clear();
  stack_.push_back({n_ - 1, first_child_[n_ - 1], slope(n_ - 1)});
  while (!stack_.empty()) {
    Frame& f = stack_.back();
    if (f.child >= 0) {
      ++checks;
      const double s = slope(f.child);
      if (s > f.slope) {
        const int c = f.child;
        f.child = next_sibling_[c];
        stack_.push_back({c, first_child_[c], s});
        continue;
      }
    }
    const int p = f.parent;
    const bool keep = f.child >= 0 || permanent_[p] || p == n_ - 1;
    stack_.pop_back();
    if (keep) horizons.push_back(p);
  }
  return checks;
}

void visible_stretches(const double* h, int r, std::span<const int> horizons,
                       std::vector<VisibleStretch>& out, const double* x) {
  out.clear();
  const int m = int(horizons.size());
  for (int k = 0; k < m; ++k) {
    const int start = horizons[k];
    if (k + 1 == m) {
      out.push_back({start, r - 1, -std::numeric_limits<double>::infinity()});
      break;
    }
    const int next = horizons[k + 1];
    const double limit = visibility_slope(h, x, next, r);
    int j = start;
    while (j + 1 < next && visibility_slope(h, x, j + 1, r) > limit) ++j;
    out.push_back({start, j, limit});
  }
}

}  // namespace hfbake
