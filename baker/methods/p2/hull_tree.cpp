#include "methods/p2/hull_tree.hpp"

#include <limits>

namespace hfbake {

void HullTree::reset(int capacity) {
  if (std::size_t(capacity) > nodes_.size()) {
    nodes_.resize(capacity);
    stack_.resize(std::size_t(capacity) + 1);
    horizons_.resize(capacity);
    horizon_slopes_.resize(capacity);
  }
  n_ = 0;
  nh_ = 0;
  prev_class_ = 1;
  unit_ = true;
  iterations_ = 0;
}

void HullTree::push_at(double x, double height) {
  const int r = n_++;
  Node* nd = nodes_.data();
  nd[r] = {height, x, -1, -1, 0, 0};
  if (x != double(r)) unit_ = false;
  nh_ = 0;
  if (r == 0) {  // p_0 starts the first convex section: a permanent leaf
    nd[0].permanent = 1;
    return;
  }
  // Eq. 1 for p_{r-1}, now that its successor is known: convex if 2 h_i >= h_{i-1} + h_{i+1}, else
  // concave. (P2's Eq. 1 lets a collinear triple inherit the previous class; with the strict tie rule a
  // collinear p_{r-1} after a concave stretch starts a visible run -- {0, 5, 1, 1, 1} seen from the last
  // sample -- so collinear triples count as convex here.) A convex sample after a concave one starts a
  // segment: a permanent leaf. Marked before the repair below, so the old root survives it even when all
  // its children move away. At any positions: convex if the slope into p_i is not below the slope out of
  // it, (h_i - h_{i-1}) (x_{i+1} - x_i) >= (h_{i+1} - h_i) (x_i - x_{i-1}).
  if (r >= 2) {
    const Node &a = nd[r - 2], &b = nd[r - 1];
    const double lhs = unit_ ? 2 * b.h : (b.h - a.h) * (x - b.x);
    const double rhs = unit_ ? a.h + height : (height - b.h) * (b.x - a.x);
    const int cls = lhs >= rhs ? 1 : 0;
    if (cls == 1 && prev_class_ == 0) nd[r - 1].permanent = 1;
    prev_class_ = cls;
  }

  // The new root r has the old root r-1 as its only child. Repair (Algorithm 1, iteratively): scan the
  // children of a node P attached to the root, farthest first; a child strictly above the line of sight
  // root -> P leaves P for the root (placed before P) and its own children are scanned the same way
  // (deeper); the scan of P goes on with P's next child (wider) and stops at the first child that passes,
  // since children are ordered by their angle from P. P stays a root child while it keeps a child or is
  // permanent. Emitting nodes in post-order gives the root's children farthest first.
  // Slopes are visibility_slope's: (h_j - h_r) / (x_r - x_j).
  int* hz = horizons_.data();
  double* hs = horizon_slopes_.data();
  Frame* st = stack_.data();
  int top = 0, tail = -1, nh = 0;
  std::uint64_t it = 0;
  auto append = [&](int p, double slope) {  // the root's next child
    if (tail < 0)
      nd[r].first_child = p;
    else
      nd[tail].next_sibling = p;
    nd[p].next_sibling = -1;
    tail = p;
    hz[nh] = p, hs[nh] = slope, ++nh;
  };
  st[0] = {r - 1, nd[r - 1].first_child, (nd[r - 1].h - height) / (x - nd[r - 1].x)};
  while (top >= 0) {
    Frame& f = st[top];
    if (f.child >= 0) {
      ++it;
      const int ci = f.child;
      const Node& c = nd[ci];
      const double s = (c.h - height) / (x - c.x);
      if (s > f.slope) {  // c leaves its parent for the root (deeper)
        f.child = c.next_sibling;
        // The scan of c's children starts with its farthest, g. Mostly g stays (then so do the rest): c is
        // the root's next child at once, without a frame of its own. The same steps as with one.
        const int g = c.first_child;
        if (g >= 0) {
          ++it;
          const double sg = (nd[g].h - height) / (x - nd[g].x);
          if (sg > s) {  // g moves too: c's scan goes on after g, and g's own children are scanned
            st[++top] = {ci, nd[g].next_sibling, s};
            st[++top] = {g, nd[g].first_child, sg};
            continue;
          }
        }
        if (g >= 0 || c.permanent) append(ci, s);
        continue;
      }
    }
    const int p = f.parent;
    nd[p].first_child = f.child;
    if (f.child >= 0 || nd[p].permanent) append(p, f.slope);
    --top;
  }
  nh_ = nh;
  iterations_ += it;
}

int HullTree::query(double x, double height, int* horizons, double* slopes, std::uint64_t* checks) {
  if (n_ == 0) return 0;
  const Node* nd = nodes_.data();
  const int last = n_ - 1;
  Frame* st = stack_.data();
  int top = 0, m = 0;
  std::uint64_t it = 0;
  st[0] = {last, nd[last].first_child, (nd[last].h - height) / (x - nd[last].x)};  // == visibility_slope
  while (top >= 0) {
    Frame& f = st[top];
    if (f.child >= 0) {
      ++it;
      const int ci = f.child;
      const Node& c = nd[ci];
      const double s = (c.h - height) / (x - c.x);
      if (s > f.slope) {
        f.child = c.next_sibling;
        const int g = c.first_child;  // as in push_at: c listed at once when its farthest child stays
        if (g >= 0) {
          ++it;
          const double sg = (nd[g].h - height) / (x - nd[g].x);
          if (sg > s) {
            st[++top] = {ci, nd[g].next_sibling, s};
            st[++top] = {g, nd[g].first_child, sg};
            continue;
          }
        }
        horizons[m] = ci, slopes[m] = s;
        m += (g >= 0) | (c.permanent != 0) | (ci == last);
        continue;
      }
    }
    const int p = f.parent;
    horizons[m] = p, slopes[m] = f.slope;  // kept (counted) or overwritten by the next
    m += (f.child >= 0) | (nd[p].permanent != 0) | (p == last);
    --top;
  }
  *checks += it;
  return m;
}

std::uint64_t HullTree::query(double x, double height, std::vector<int>& horizons) {
  horizons.resize(std::size_t(n_));
  std::vector<double> slopes(static_cast<std::size_t>(n_));
  std::uint64_t checks = 0;
  horizons.resize(std::size_t(query(x, height, horizons.data(), slopes.data(), &checks)));
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
