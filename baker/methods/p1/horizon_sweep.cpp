#include "methods/p1/horizon_sweep.hpp"

namespace hfbake::p1 {

std::vector<NearCrossing> near_field_stencil(double dx, double dy, double radius, double texel_size) {
  std::vector<NearCrossing> out;
  std::vector<double> dist;  // each crossing's s, the sort's key (float inv_s ties crossings a hair apart)
  auto add = [&](double s) {
    dist.push_back(s);
    double x = s * dx, y = s * dy;
    // Snap coordinates that are integers up to rounding, so the cell below is chosen consistently.
    if (std::fabs(x - std::round(x)) < 1e-9) x = std::round(x);
    if (std::fabs(y - std::round(y)) < 1e-9) y = std::round(y);
    const double fx0 = std::floor(x), fy0 = std::floor(y), fx = x - fx0, fy = y - fy0;
    const int i = int(fx0), j = int(fy0);
    // Barycentric weights of the point in its triangle of cell (i, j), as four corner weights.
    double w[4];  // (i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)
    if (fx + fy <= 1)
      w[0] = 1 - fx - fy, w[1] = fx, w[2] = fy, w[3] = 0;
    else
      w[0] = 0, w[1] = 1 - fy, w[2] = 1 - fx, w[3] = fx + fy - 1;
    static const int ci[4] = {0, 1, 0, 1}, cj[4] = {0, 0, 1, 1};
    // A crossing lies on an edge: at most two corners weigh (the rest are zero up to rounding).
    int first = -1, second = -1;
    for (int c = 0; c < 4; ++c) {
      if (w[c] <= 1e-9) continue;
      if (first < 0 || w[c] > w[first]) {
        second = first;
        first = c;
      } else if (second < 0 || w[c] > w[second]) {
        second = c;
      }
    }
    if (second < 0) second = first;
    NearCrossing n;
    n.ai = i + ci[first], n.aj = j + cj[first], n.bi = i + ci[second], n.bj = j + cj[second];
    n.w = second == first ? 0.0f : float(w[second] / (w[first] + w[second]));
    n.x = float(x), n.y = float(y);
    n.inv_s = float(1.0 / (s * texel_size));
    out.push_back(n);
  };
  auto family = [&](double d) {  // crossings of s * d = integer, 0 < s <= radius
    if (std::fabs(d) < 1e-12) return;
    for (int m = 1;; ++m) {
      const double s = m / std::fabs(d);
      if (s > radius + 1e-9) break;
      add(s);
    }
  };
  family(dx);
  family(dy);
  family(dx + dy);
  // By distance, exactly: a ray a hair off an axis crosses a column and a diagonal within float rounding of
  // each other, and the farther one reads the column beyond (LaneDirection::build bounds a texel's crossings
  // by the columns they read). Equal distances keep the families' order.
  std::vector<std::size_t> order(out.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return dist[a] < dist[b]; });
  std::vector<NearCrossing> sorted;
  sorted.reserve(out.size());
  for (const std::size_t k : order) sorted.push_back(out[k]);
  return sorted;
}

float near_slope(const HeightField& f, const std::vector<NearCrossing>& stencil, int i, int j, int* which) {
  const bool clamp = f.wrap == Wrap::clamp;
  const float Z = f.z[f.index(i, j)];
  float best = -1e30f;
  *which = -1;
  for (std::size_t c = 0; c < stencil.size(); ++c) {
    const NearCrossing& x = stencil[c];
    const float px = float(i) + x.x, py = float(j) + x.y;
    if (clamp &&
        (px < -1e-4f || py < -1e-4f || px > float(f.width - 1) + 1e-4f || py > float(f.height - 1) + 1e-4f))
      continue;
    const float za = f.at(i + x.ai, j + x.aj), zb = f.at(i + x.bi, j + x.bj);
    const float m = ((za - Z) + (zb - za) * x.w) * x.inv_s;
    if (m > best) best = m, *which = int(c);
  }
  return best;
}

NearStencil near_stencil(const HeightField& f, const SweepDirection& d, double near_radius) {
  NearStencil s;
  const double radius = near_radius_of(d, near_radius);
  s.crossings = near_field_stencil(d.dx, d.dy, radius, f.texel_size);
  for (const NearCrossing& c : s.crossings) {
    s.a.push_back(std::ptrdiff_t(c.aj) * f.width + c.ai);
    s.b.push_back(std::ptrdiff_t(c.bj) * f.width + c.bi);
  }
  s.margin = int(std::ceil(radius)) + 2;
  return s;
}

void near_slopes_row(const HeightField& f, const NearStencil& s, int i0, int j, int w, float* out) {
  const float* Z = f.z.data() + f.index(i0, j);
  for (int x = 0; x < w; ++x) out[x] = -1e30f;
  int xa = w, xb = w;  // the interior run [xa, xb) of the row
  if (j >= s.margin && j < f.height - s.margin) {
    xa = std::clamp(s.margin - i0, 0, w);
    xb = std::clamp(f.width - s.margin - i0, xa, w);
  }
  for (std::size_t c = 0; c < s.crossings.size(); ++c) {
    const float* za = Z + s.a[c];
    const float* zb = Z + s.b[c];
    const float wc = s.crossings[c].w, inv_s = s.crossings[c].inv_s;
    for (int x = xa; x < xb; ++x) {
      const float m = ((za[x] - Z[x]) + (zb[x] - za[x]) * wc) * inv_s;
      out[x] = m > out[x] ? m : out[x];
    }
  }
  int which;
  for (int x = 0; x < xa; ++x) out[x] = near_slope(f, s.crossings, i0 + x, j, &which);
  for (int x = xb; x < w; ++x) out[x] = near_slope(f, s.crossings, i0 + x, j, &which);
}

float near_slope_at(const HeightField& f, const NearStencil& s, int i, int j) {
  if (i < s.margin || j < s.margin || i >= f.width - s.margin || j >= f.height - s.margin) {
    int which;
    return near_slope(f, s.crossings, i, j, &which);
  }
  const float* Z = f.z.data() + f.index(i, j);
  float m = -1e30f;
  for (std::size_t c = 0; c < s.crossings.size(); ++c) {
    const float za = Z[s.a[c]], zb = Z[s.b[c]];
    const float mc = ((za - Z[0]) + (zb - za) * s.crossings[c].w) * s.crossings[c].inv_s;
    m = mc > m ? mc : m;
  }
  return m;
}

}  // namespace hfbake::p1
