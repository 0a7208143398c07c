#include "methods/p2/indirect_gather.hpp"

#include <algorithm>
#include <limits>

namespace hfbake {

Rgb gather_stretches(const double* h, const Rgb* L, int r, int terrain_end, std::span<const int> horizons,
                     double inv_step, const WedgeWeights& w, double* weight, const double* inv_dist,
                     GatherScratch* scratch) {
  std::vector<Rgb> mean(std::size_t(std::max(r, 0))), slope(mean.size());
  for (int j = 0; j < r; ++j) {
    mean[j] = 0.5f * (L[j] + L[j + 1]);
    slope[j] = L[j + 1] - L[j];
  }
  SegmentRadiance seg;
  seg.mean = mean.data();
  seg.slope = slope.data();
  seg.crease = L[r];
  return gather_segments(h, seg, r, terrain_end, horizons, inv_step, w, weight, inv_dist, scratch);
}

namespace {
// gather_segments for unit spacing (kX false, x null) or positions (kX true): the same operations, the
// choice made once instead of at every visible sample.
template <bool kX>
Rgb gather_segments_impl(const double* h, const SegmentRadiance& L, int r, int terrain_end,
                         std::span<const int> horizons, double inv_step, const WedgeWeights& w,
                         double* weight, const double* inv_dist, GatherScratch* scratch, const double* x,
                         const double* horizon_slopes) {
  GatherScratch local;
  GatherScratch& sc = scratch ? *scratch : local;
  const int m = int(horizons.size());
  const double t_n = w.t_n;
  const double hr = h[r];
  const double xr = kX ? x[r] : 0;
  if (kX) inv_dist = nullptr;
  // The distance from sample j to the receiver (positions) and its world-slope factor.
  auto dist = [&](int j) { return kX ? xr - x[j] : double(r - j); };
  // The slope of horizon k seen from r.
  auto horizon_slope = [&](int k) {
    return horizon_slopes ? horizon_slopes[k] : visibility_slope(h, x, horizons[k], r);
  };
  if (weight) *weight = 0;
  if (m == 0) return {};
  // The visible stretches tile the elevations from the global horizon down to the tangent plane: each
  // stretch ends (its last, partly visible segment) at the line of sight to the next horizon, which is
  // where the next stretch starts (the same slope, computed the same way). Collect the boundaries
  // t_0 > t_1 > ... > t_M >= t_n and the radiance of each interval; M <= r + 1 intervals.
  sc.reserve(std::size_t(r) + 3);
  float* T = sc.t.data();
  Rgb* LI = sc.L.data();
  int M = 0;  // intervals so far; T[M] is the current upper boundary
  {
    const double t0 = horizon_slope(0) * inv_step;
    if (!(t0 > t_n)) return {};  // everything lies below the tangent plane
    T[0] = float(t0);
  }
  for (int k = 0; k < m; ++k) {
    int j = horizons[k];
    const bool last = k + 1 == m;
    const int end = last ? terrain_end : horizons[k + 1];
    const double limit = last ? -std::numeric_limits<double>::infinity() : horizon_slope(k + 1);
    // Fully visible segments j -> j+1. (The test s_next > limit by multiplication: the same as the
    // division up to rounding at exact ties, where the segment's weight is zero anyway.)
    bool done = false;
    while (j + 1 < end) {
      const double d = dist(j + 1);
      const double dz = h[j + 1] - hr;
      if (!(dz > limit * d)) break;
      const double t_next = dz * (inv_dist ? inv_dist[r - j - 1] : inv_step / d);
      LI[M] = L.mean[j];
      if (!(t_next > t_n)) {  // the segment crosses the tangent plane: nothing below it counts
        T[++M] = float(t_n);
        done = true;
        break;
      }
      T[++M] = float(t_next);
      ++j;
    }
    if (done) break;
    if (last) {  // j == terrain_end - 1: below it the ray meets the receiver's own surface
      if (!L.has_crease) break;
      LI[M] = L.crease;
      T[++M] = float(t_n);
      break;
    }
    // The segment j -> j+1 is visible down to the next horizon's line of sight (slope `limit`):
    // parameter u of the crossing, from h_j + u dh - h_r = limit (x_r - x_j - u dx) (unit spacing: dx = 1).
    const double dh = h[j + 1] - h[j];
    const double den = kX ? dh + limit * (x[j + 1] - x[j]) : dh + limit;
    double u = den < 0 ? (limit * dist(j) - (h[j] - hr)) / den : 1.0;
    u = std::clamp(u, 0.0, 1.0);
    LI[M] = L.mean[j] + L.slope[j] * float(0.5 * (u - 1));
    const double t_lim = limit * inv_step;
    if (!(t_lim > t_n)) {
      T[++M] = float(t_n);
      break;
    }
    T[++M] = float(t_lim);  // == the next stretch's first slope
  }
  // Weights: branch-free over the boundaries.
  float* F = sc.F.data();
  w.F_many(T, F, M + 1);
  double acc_r = 0, acc_g = 0, acc_b = 0;
  for (int i = 0; i < M; ++i) {
    const double wi = double(F[i]) - double(F[i + 1]);
    acc_r += LI[i].r * wi;
    acc_g += LI[i].g * wi;
    acc_b += LI[i].b * wi;
  }
  if (weight) *weight = (double(F[0]) - double(F[M])) / kPi;  // T[M]: t_n (no crease: the lowest far slope)
  return {float(acc_r / kPi), float(acc_g / kPi), float(acc_b / kPi)};
}

}  // namespace

Rgb gather_segments(const double* h, const SegmentRadiance& L, int r, int terrain_end,
                    std::span<const int> horizons, double inv_step, const WedgeWeights& w, double* weight,
                    const double* inv_dist, GatherScratch* scratch, const double* x,
                    const double* horizon_slopes) {
  return x ? gather_segments_impl<true>(h, L, r, terrain_end, horizons, inv_step, w, weight, inv_dist,
                                        scratch, x, horizon_slopes)
           : gather_segments_impl<false>(h, L, r, terrain_end, horizons, inv_step, w, weight, inv_dist,
                                         scratch, nullptr, horizon_slopes);
}

void run_starts(const double* h, int r, std::span<const int> horizons, std::vector<int>& out,
                const double* x) {
  out.clear();
  for (int c : horizons)
    if (c == 0 || !(visibility_slope(h, x, c - 1, r) > visibility_slope(h, x, c, r))) out.push_back(c);
}

int run_starts(const double* h, int r, const int* horizons, const double* slopes, int m, int* out,
               double* out_slopes, const double* x) {
  // Written without a branch on the outcome (it is hard to predict): every horizon is stored, and the
  // count moves past it when it is kept.
  int n = 0;
  for (int k = 0; k < m; ++k) {
    const int c = horizons[k];
    const bool keep = (c == 0) | !(visibility_slope(h, x, std::max(c - 1, 0), r) > slopes[k]);
    out[n] = c, out_slopes[n] = slopes[k];
    n += keep;
  }
  return n;
}

void run_starts_of_visible(std::span<const int> visible, std::vector<int>& out) {
  out.clear();
  for (std::size_t a = 0; a < visible.size(); ++a)
    if (a == 0 || visible[a - 1] != visible[a] - 1) out.push_back(visible[a]);
}

}  // namespace hfbake
