#include "methods/p2/indirect_sweep.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "methods/p1/fast_math.hpp"
#include "methods/p2/hull_tree.hpp"
#include "methods/p2/indirect_gather.hpp"
#include "methods/p2/naive_visibility.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake {
namespace {

// Per receiver sample: E/pi gathered with the sample's normal (RGB), the terrain weight it was gathered
// over, and the global horizon's elevation. The texel visitor turns them into
//   indirect_k(texel) = (blended E/pi / blended weight) * terrain_weight(texel normal, blended elevation):
// the mean terrain radiance seen from the samples, over exactly the part of the texel's cosine lobe that
// P1 does not give to the sky (P1 blends the same elevations to the texel the same way). So P1's direct
// and this indirect tile the texel's lobe: a uniform emitting furnace gives direct + indirect = 1.
constexpr int kChannels = 5;

struct LineWorker {
  const HeightField* field = nullptr;
  const std::vector<Vec3f>* normals = nullptr;
  const std::vector<Rgb>* exit = nullptr;
  const IndirectSweepSpec* spec = nullptr;
  double wedge = 0;
  // Scratch, grown once per thread.
  HullTree tree;
  std::vector<double> h;
  std::vector<Rgb> L;
  std::vector<Rgb> seg_mean, seg_slope;  // per segment q -> q+1 (SegmentRadiance)
  std::vector<double> inv_dist;          // inv_step / d
  double inv_dist_step = 0;
  std::vector<int> visible, starts;
  GatherScratch gather_scratch;
  P2SweepStats stats;
  // Each worker adds its counts to the caller's totals when the driver destroys it (integer sums: the
  // totals do not depend on which thread did which line).
  P2SweepStats* sink = nullptr;
  std::mutex* sink_mutex = nullptr;

  LineWorker() = default;
  LineWorker(const LineWorker&) = default;
  LineWorker& operator=(const LineWorker&) = default;
  ~LineWorker() {
    if (!sink) return;
    std::lock_guard<std::mutex> lock(*sink_mutex);
    sink->receivers += stats.receivers;
    sink->iterations += stats.iterations;
    sink->naive_iterations += stats.naive_iterations;
    sink->horizons += stats.horizons;
    sink->run_starts += stats.run_starts;
    sink->pushed += stats.pushed;
    sink->horizons_pushed += stats.horizons_pushed;
  }

  // Bilinear exit radiance at continuous texel coordinates (like HeightField::bilinear).
  Rgb exit_bilinear(double x, double y) const {
    const double fx = std::floor(x), fy = std::floor(y);
    const int i = int(fx), j = int(fy);
    const float tx = float(x - fx), ty = float(y - fy);
    const HeightField& f = *field;
    auto at = [&](int a, int b) { return (*exit)[f.index(f.wrap_i(a), f.wrap_j(b))]; };
    return (at(i, j) * (1 - tx) + at(i + 1, j) * tx) * (1 - ty) +
           (at(i, j + 1) * (1 - tx) + at(i + 1, j + 1) * tx) * ty;
  }

  void operator()(const SweepLine& line, float* out) {
    const int S = std::max(1, spec->supersampling);
    const int n0 = line.count, n = (n0 - 1) * S + 1;  // fine samples: sample q is driver sample q / S
    const int ib = line.inside_begin * S;
    const int ie = line.inside_end > line.inside_begin ? (line.inside_end - 1) * S + 1 : ib;
    if (int(h.size()) < n) {
      h.resize(n);
      L.resize(n);
      seg_mean.resize(n);
      seg_slope.resize(n);
    }
    const bool gather = spec->gather;
    const bool facets = spec->exit_facets != nullptr;
    auto fine_xy = [&](int q, double* x, double* y) {
      const int s = q / S, sub = q % S;
      *x = line.x(s), *y = line.y(s);
      if (sub == 0) return;
      const double f = double(sub) / S;
      *x += f * (line.x(s + 1) - line.x(s));
      *y += f * (line.y(s + 1) - line.y(s));
    };
    for (int q = 0; q < n; ++q) {
      const int s = q / S, sub = q % S;
      if (sub == 0) {
        h[q] = line.z[s];
        if (gather && !facets) {
          const TexelPair t = line.height_taps(s, *field);
          L[q] = (*exit)[t.texel[0]] * t.weight[0] + (*exit)[t.texel[1]] * t.weight[1];
        }
      } else {
        double x, y;
        fine_xy(q, &x, &y);
        h[q] = facets ? field->triangle_height(x, y) : field->bilinear(x, y);
        if (gather && !facets) L[q] = exit_bilinear(x, y);
      }
    }
    if (gather) {  // the radiance of every segment, once per line
      if (facets) {
        double x0, y0, x1, y1;
        fine_xy(0, &x0, &y0);
        for (int q = 0; q + 1 < n; ++q) {
          fine_xy(q + 1, &x1, &y1);
          facet_segment_radiance(*field, spec->exit_facets->data(), x0, y0, x1, y1, &seg_mean[q],
                                 &seg_slope[q]);
          x0 = x1, y0 = y1;
        }
      } else {
        for (int q = 0; q + 1 < n; ++q) {
          seg_mean[q] = 0.5f * (L[q] + L[q + 1]);
          seg_slope[q] = L[q + 1] - L[q];
        }
      }
    }
    const bool naive = spec->visibility == P2Visibility::naive;
    const double* hh = h.data() + ib;  // terrain-relative indexing: sample s is index s - ib
    SegmentRadiance seg;               // terrain-relative like hh
    seg.mean = seg_mean.data() + ib;
    seg.slope = seg_slope.data() + ib;
    const int T = ie - ib;
    const double inv_step = S / line.step;
    if (gather && (int(inv_dist.size()) < n || inv_dist_step != inv_step)) {
      inv_dist.resize(std::max<std::size_t>(inv_dist.size(), std::size_t(n)));
      inv_dist[0] = 0;
      for (std::size_t d = 1; d < inv_dist.size(); ++d) inv_dist[d] = inv_step / double(d);
      inv_dist_step = inv_step;
    }
    if (!naive) tree.reset(T);
    const std::uint64_t it0 = tree.iterations();
    for (int q = 0; q < n; ++q) {
      const bool terrain = q >= ib && q < ie;
      if (terrain && !naive) {
        tree.push(h[q]);
        stats.pushed += 1;
        stats.horizons_pushed += tree.horizons().size();
      }
      if (q % S != 0) continue;
      const int s = q / S;  // the driver's sample
      if (s < line.first_receiver) continue;
      float* o = out + std::size_t(s - line.first_receiver) * kChannels;
      o[0] = o[1] = o[2] = o[3] = 0;
      o[4] = -p1::kHalfPiF;  // nothing behind: P1's convention
      const int r = q - ib;
      if (r <= 0 || T <= 0) continue;  // no terrain behind this receiver
      const int terrain_end = std::min(r, T);
      if (terrain) {
        stats.receivers += 1;
        stats.naive_iterations += std::uint64_t(r);
      }
      if (naive) {
        naive_visible(hh, r, visible, terrain_end);
        run_starts_of_visible(visible, starts);
        if (terrain) stats.iterations += std::uint64_t(r);
      } else if (terrain) {
        run_starts(hh, r, tree.horizons(), starts);
        stats.horizons += tree.horizons().size();
      } else {  // beyond a clamp field's border: sees the terrain, is not terrain itself
        tree.query(r, hh[r], visible);
        run_starts(hh, r, visible, starts);
      }
      if (terrain) stats.run_starts += starts.size();
      if (!gather) continue;
      const TexelPair t = line.height_taps(s, *field);
      const Vec3 nrm =
          normalize((*normals)[t.texel[0]].d() * t.weight[0] + (*normals)[t.texel[1]].d() * t.weight[1]);
      const WedgeWeights w = WedgeWeights::make(nrm, line.dir->dx, line.dir->dy, wedge);
      double weight = 0;
      // Below the nearest sample the receiver sees its own surface: its radiance, or with facet senders
      // the segment it stands at the end of.
      seg.crease = facets ? seg_mean[ib + r - 1] : L[ib + r];
      const Rgb e = gather_segments(hh, seg, r, terrain_end, starts, inv_step, w, &weight, inv_dist.data(),
                                    &gather_scratch);
      o[0] = e.r;
      o[1] = e.g;
      o[2] = e.b;
      o[3] = float(weight);
      // The global horizon's elevation exactly as P1's HorizonLineWorker computes it.
      if (!spec->p1_sin_horizon && !starts.empty()) {  // (unused when P1's horizons split the lobe)
        const int c = starts.front();
        o[4] = p1::fast_elevation(float(hh[c] - hh[r]), float(r - c) * float(line.step / S));
      }
    }
    if (!naive) stats.iterations += tree.iterations() - it0;
  }
};

}  // namespace

void facet_segment_radiance(const HeightField& f, const Rgb* facet_exit, double x0, double y0, double x1,
                            double y1, Rgb* mean, Rgb* slope) {
  // Parameters where x, y or x + y (the quads' diagonals) pass an integer: on a segment no longer than a
  // texel along its major axis at most 1 + 1 + 2 (the bound guards longer ones).
  double t[8];
  int n = 0;
  auto cross = [&](double a0, double a1) {
    const double d = a1 - a0;
    if (!(d != 0)) return;
    const double lo = d > 0 ? a0 : a1, hi = d > 0 ? a1 : a0;
    for (int c = floor_int(lo) + 1; c < hi && n < 6; ++c) t[n++] = (c - a0) / d;
  };
  cross(x0, x1);
  cross(y0, y1);
  cross(x0 + y0, x1 + y1);
  for (int a = 1; a < n; ++a)  // insertion sort of a handful of values
    for (int b = a; b > 0 && t[b] < t[b - 1]; --b) std::swap(t[b], t[b - 1]);
  t[n++] = 1;
  Rgb m{}, m1{};
  double a = 0;
  for (int p = 0; p < n; ++p) {
    const double b = t[p];
    if (!(b > a)) continue;
    const double u = 0.5 * (a + b), x = x0 + u * (x1 - x0), y = y0 + u * (y1 - y0);
    const int i = floor_int(x), j = floor_int(y);
    // The facet under the piece: the triangle (i, j), (i+1, j), (i, j+1) is facet 0 of texel (i, j), the
    // triangle (i+1, j+1), (i, j+1), (i+1, j) facet 1 of texel (i+1, j+1).
    const int q = (x - i) + (y - j) <= 1 ? 0 : 1;
    const int ti = i + q, tj = j + q;
    const int wi = ti >= 0 && ti < f.width ? ti : f.wrap_i(ti),
              wj = tj >= 0 && tj < f.height ? tj : f.wrap_j(tj);
    const Rgb v = facet_exit[2 * f.index(wi, wj) + q];
    m += v * float(b - a);
    // first moment about the middle, for the least-squares linear trend: integral of (u - 1/2) du
    m1 += v * float(0.5 * (b - a) * (a + b - 1));
    a = b;
  }
  *mean = m;
  *slope = m1 * 12.0f;  // / integral of (u - 1/2)^2 over [0, 1]
}

std::vector<Rgb> sweep_indirect(const HeightField& field, const std::vector<Vec3f>& normals,
                                const std::vector<Rgb>& exit, const IndirectSweepSpec& spec,
                                const RunControl& rc, P2SweepStats* stats, std::vector<Rgb>* facet_result) {
  const std::size_t texels = field.texel_count();
  std::vector<double> acc(texels * 3, 0.0);
  const bool facets = spec.exit_facets && spec.facet_normals && facet_result;
  std::vector<double> acc_f(facets ? texels * 6 : 0, 0.0);  // [(2 * texel + q) * 3 + channel]
  SweepSpec ss;
  ss.directions = spec.directions;
  ss.channels = kChannels;
  ss.wrap_periods = spec.wrap_periods;
  const int K = spec.directions;
  const double wedge = 2 * kPi / K;
  std::vector<double> cs(K), sn(K);
  for (int k = 0; k < K; ++k) {
    cs[k] = std::cos(2 * kPi * k / K);
    sn[k] = std::sin(2 * kPi * k / K);
  }
  P2SweepStats totals;
  std::mutex totals_mutex;
  sweep_lines(
      field, ss, rc,
      [&] {
        LineWorker w;
        w.field = &field;
        w.normals = &normals;
        w.exit = &exit;
        w.spec = &spec;
        w.wedge = wedge;
        w.sink = &totals;
        w.sink_mutex = &totals_mutex;
        return w;
      },
      [&](int k, int i, int j, const TexelTaps& t) {
        if (!spec.gather) return;
        const std::size_t idx = field.index(i, j);
        // The horizon's elevation, sine and cosine: from P1's sines (asin by the fast atan: both within
        // 1e-7 of P1's own), or the line samples' blended elevation.
        double e, se, ce;
        if (spec.p1_sin_horizon) {
          const float sf = std::clamp((*spec.p1_sin_horizon)[std::size_t(k) * texels + idx], -1.0f, 1.0f);
          const float cf = std::sqrt(std::max(0.0f, 1 - sf * sf));
          se = sf, ce = cf;
          e = cf > 0 ? double(p1::fast_atan(sf / cf)) : std::copysign(kPi / 2, double(sf));
        } else {
          e = t.value(4);
          float sf, cf;
          p1::fast_sincos(float(e), sf, cf);
          se = sf, ce = cf;
        }
        const double wb = t.value(3);
        if (facets)  // the same mean terrain radiance over the facets' lobes
          for (int q = 0; q < 2; ++q) {
            const std::size_t fi = 2 * idx + q;
            const double tf = terrain_weight((*spec.facet_normals)[fi].d(), cs[k], sn[k], K, e, se, ce);
            if (!(tf > 0)) continue;
            double* a = acc_f.data() + fi * 3;
            if (wb > 0) {
              a[0] += t.value(0) * tf / wb, a[1] += t.value(1) * tf / wb, a[2] += t.value(2) * tf / wb;
            } else {
              const Rgb x = (*spec.exit_facets)[fi];
              a[0] += x.r * tf, a[1] += x.g * tf, a[2] += x.b * tf;
            }
          }
        const double tw = terrain_weight(normals[idx].d(), cs[k], sn[k], K, e, se, ce);
        if (!(tw > 0)) return;
        double* a = acc.data() + idx * 3;
        if (wb > 0) {
          const double f = tw / wb;
          a[0] += t.value(0) * f;
          a[1] += t.value(1) * f;
          a[2] += t.value(2) * f;
        } else {  // the samples see no terrain above their tangent planes, the texel does: its own surface
          a[0] += exit[idx].r * tw;
          a[1] += exit[idx].g * tw;
          a[2] += exit[idx].b * tw;
        }
      });
  std::vector<Rgb> result(texels);
  for (std::size_t p = 0; p < texels; ++p)
    result[p] = {float(acc[3 * p]), float(acc[3 * p + 1]), float(acc[3 * p + 2])};
  if (facets) {
    facet_result->resize(2 * texels);
    for (std::size_t p = 0; p < 2 * texels; ++p)
      (*facet_result)[p] = {float(acc_f[3 * p]), float(acc_f[3 * p + 1]), float(acc_f[3 * p + 2])};
  }
  if (stats) *stats = totals;
  return result;
}

}  // namespace hfbake
