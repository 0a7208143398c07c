#include "methods/ao/obscurance_hull.hpp"

#include <algorithm>

namespace hfbake {

void sweep_obscurance_line(const SlicePoint* pts, std::size_t count, std::size_t first_receiver,
                           const OcclusionFunction& f, ObscuranceHull& hull, double* out) {
  hull.clear();
  for (std::size_t i = 0; i < count; ++i) {
    if (i >= first_receiver) {
      out[i] = hull.receive(pts[i], f);
    } else if (hull.size() >= 2) {
      hull.receive(pts[i], f);  // warm-up receivers still prune, so the hull is the same as in a long line
    }
    hull.push(pts[i]);
  }
}

void brute_force_obscurance_line(const SlicePoint* pts, std::size_t count, const OcclusionFunction& f,
                                 bool visible_only, double* out) {
  for (std::size_t i = 0; i < count; ++i) {
    double best = f.none();
    double max_sin = -2.0;
    for (std::size_t j = i; j-- > 0;) {
      const double hs = pts[i].s - pts[j].s, hz = pts[j].z - pts[i].z;
      const double se = sine_elevation(hs, hz);
      if (visible_only) {
        if (se < max_sin) continue;
        max_sin = se;
      }
      best = std::max(best, f(hs, hz));
    }
    out[i] = best;
  }
}

}  // namespace hfbake
