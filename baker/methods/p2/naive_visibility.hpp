// The naive intervisibility search P2 compares against (P2 §1): march outward from the receiver one
// sample at a time; a sample is visible when its slope exceeds the running maximum. O(r) per receiver.
// Same slopes and tie rule as the convex hull tree (hull_tree.hpp): the two give identical visible sets.
#pragma once

#include <algorithm>
#include <limits>
#include <vector>

#include "methods/p2/hull_tree.hpp"

namespace hfbake {

// Indices of the samples visible from receiver r (0 <= r), increasing. `visible` is cleared first.
// Only samples 0..terrain_end-1 are terrain (default: all samples before r). x: the samples' positions
// (null: unit spacing).
inline void naive_visible(const double* h, int r, std::vector<int>& visible, int terrain_end = -1,
                          const double* x = nullptr) {
  visible.clear();
  double running = -std::numeric_limits<double>::infinity();
  for (int j = (terrain_end < 0 ? r : std::min(r, terrain_end)) - 1; j >= 0; --j) {
    const double s = visibility_slope(h, x, j, r);
    if (s > running) {
      running = s;
      visible.push_back(j);
    }
  }
  for (std::size_t a = 0, b = visible.size(); a + 1 < b; ++a, --b) std::swap(visible[a], visible[b - 1]);
}

}  // namespace hfbake
