#include "methods/p2/indirect_gather.hpp"

#include <algorithm>
#include <limits>

namespace hfbake {

Rgb gather_stretches(const double* h, const Rgb* L, int r, int terrain_end, std::span<const int> horizons,
                     double inv_step, const WedgeWeights& w, double* weight, const double* inv_dist) {
  double acc_r = 0, acc_g = 0, acc_b = 0;
  auto add = [&](Rgb l, double weight) {
    acc_r += l.r * weight;
    acc_g += l.g * weight;
    acc_b += l.b * weight;
  };
  const int m = int(horizons.size());
  const double t_n = w.t_n;
  const double F_n = w.F(t_n);
  const double hr = h[r];
  if (weight) {
    *weight = 0;
    if (m > 0) {
      const double top = visibility_slope(h, horizons[0], r) * inv_step;
      if (top > t_n) *weight = (w.F(top) - F_n) / kPi;
    }
  }
  for (int k = 0; k < m; ++k) {
    int j = horizons[k];
    const double sj = (h[j] - hr) / double(r - j);
    const double tj = sj * inv_step;
    if (!(tj > t_n)) break;  // this stretch and all nearer ones lie below the tangent plane
    double Fj = w.F(tj);
    const bool last = k + 1 == m;
    const int end = last ? terrain_end : horizons[k + 1];
    const double limit = last ? -std::numeric_limits<double>::infinity() : visibility_slope(h, end, r);
    // Fully visible segments j -> j+1. (The test s_next > limit by multiplication: the same as the
    // division up to rounding at exact ties, where the segment's weight is zero anyway.)
    while (j + 1 < end) {
      const int d = r - j - 1;
      const double dz = h[j + 1] - hr;
      if (!(dz > limit * double(d))) break;
      const double t_next = dz * (inv_dist ? inv_dist[d] : inv_step / double(d));
      if (!(t_next > t_n)) {  // the segment crosses the tangent plane: nothing below it counts
        add(0.5f * (L[j] + L[j + 1]), Fj - F_n);
        return {float(acc_r / kPi), float(acc_g / kPi), float(acc_b / kPi)};
      }
      const double F_next = w.F(t_next);
      add(0.5f * (L[j] + L[j + 1]), Fj - F_next);
      Fj = F_next;
      ++j;
    }
    if (last) {
      // j == terrain_end - 1: below it the ray meets the receiver's own surface.
      add(L[r], Fj - F_n);
      break;
    }
    // The segment j -> j+1 is visible down to the next horizon's line of sight (slope `limit`):
    // parameter u of the crossing, from h_j + u dh - h_r = limit (r - j - u).
    const double dh = h[j + 1] - h[j];
    const double den = dh + limit;
    double u = den < 0 ? (limit * double(r - j) - (h[j] - hr)) / den : 1.0;
    u = std::clamp(u, 0.0, 1.0);
    const Rgb Lm = L[j] + (L[j + 1] - L[j]) * float(0.5 * u);
    const double t_lim = limit * inv_step;
    if (!(t_lim > t_n)) {
      add(Lm, Fj - F_n);
      break;
    }
    add(Lm, Fj - w.F(t_lim));
  }
  return {float(acc_r / kPi), float(acc_g / kPi), float(acc_b / kPi)};
}

void run_starts(const double* h, int r, std::span<const int> horizons, std::vector<int>& out) {
  out.clear();
  for (int c : horizons)
    if (c == 0 || !(visibility_slope(h, c - 1, r) > visibility_slope(h, c, r))) out.push_back(c);
}

void run_starts_of_visible(std::span<const int> visible, std::vector<int>& out) {
  out.clear();
  for (std::size_t a = 0; a < visible.size(); ++a)
    if (a == 0 || visible[a - 1] != visible[a] - 1) out.push_back(visible[a]);
}

}  // namespace hfbake
