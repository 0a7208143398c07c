#include "methods/p2/indirect_sweep.hpp"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <mutex>
#include <tuple>
#include <utility>

#include "core/azimuth.hpp"
#include "core/direction_blocks.hpp"
#include "field/edge_crossings.hpp"
#include "field/triangulation.hpp"
#include "methods/p1/fast_math.hpp"
#include "methods/p1/horizon_sweep.hpp"
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
// The slots of one sample's result, in this order.
enum Slot : int {
  kRadianceR = 0,  // E/pi gathered with the sample's normal, weighted: R, G, B
  kRadianceG = 1,
  kRadianceB = 2,
  kTerrainWeight = 3,     // the terrain weight it was gathered over
  kHorizonElevation = 4,  // the global horizon's elevation (radians)
  kChannels = 5
};

// The two facets on either side of a piece of a ray with midpoint (x, y) and direction (ux, uy): the same
// facet twice, or, when the piece runs along a column, a row or a diagonal (an edge), the two facets the
// edge separates (a wedge of azimuths around the ray sees both halves).
std::pair<FacetRef, FacetRef> facets_beside(double x, double y, double ux, double uy) {
  const double len = std::hypot(ux, uy), px = -uy / len * 1e-6, py = ux / len * 1e-6;
  return {facet_under(x + px, y + py), facet_under(x - px, y - py)};
}

Rgb facet_value(const HeightField& f, const Rgb* facet_exit, FacetRef r) {
  const int wi = r.i >= 0 && r.i < f.width ? r.i : f.wrap_i(r.i);
  const int wj = r.j >= 0 && r.j < f.height ? r.j : f.wrap_j(r.j);
  return facet_exit[2 * f.index(wi, wj) + r.q];
}

Rgb piece_radiance(const HeightField& f, const Rgb* facet_exit, double x, double y, double ux, double uy) {
  const auto [a, b] = facets_beside(x, y, ux, uy);
  const Rgb va = facet_value(f, facet_exit, a);
  return a == b ? va : (va + facet_value(f, facet_exit, b)) * 0.5f;
}

constexpr double kMinGap = 1e-6;  // line parameter: the least gap between two points of an exact profile
// Texel units on the minor axis: receivers farther than 1 + kReadMargin off a clamp field are never read
// (the margin covers the rounding of the taps' line positions).
constexpr double kReadMargin = 1e-6;

// The parameters in (0, 1), increasing, where the segment (x0, y0) -> (x1, y1) crosses an edge of the
// triangulation (field/edge_crossings.hpp). t must hold kMaxEdgeCrossings values (callers may append more).
int edge_crossings(double x0, double y0, double x1, double y1, double* t) {
  EdgeCrossing c[kMaxEdgeCrossings];
  const int n = edge_crossings(x0, y0, x1, y1, c);
  for (int k = 0; k < n; ++k) t[k] = c[k].t;
  return n;
}

struct LineWorker {
  const HeightField* field = nullptr;
  const std::vector<Vec3f>* normals = nullptr;
  const std::vector<Rgb>* exit = nullptr;
  const IndirectSweepSpec* spec = nullptr;
  double wedge = 0;
  bool near_field = false;  // IndirectSweepSpec::near_radius in effect
  int lag = 0;  // near field: the receivers gather the samples this many fine samples behind and farther
  // Scratch, grown once per thread.
  HullTree tree;
  std::vector<double> h;
  std::vector<Rgb> L;
  std::vector<Rgb> seg_mean, seg_slope;  // per segment q -> q+1 (SegmentRadiance)
  std::vector<double> inv_dist;          // inv_step / d
  double inv_dist_step = 0;
  std::vector<double> xs, fx, fy;    // exact profiles: fine samples' positions and texel coordinates
  std::vector<int> recv;             // exact profiles: the fine index of each driver sample
  std::vector<int> visible, starts;  // per receiver: the tree's horizons, the run starts
  std::vector<double> visible_slope, start_slope;  // their slopes seen from the receiver
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

  // The fine samples of one line (scratch h, xs, fx, fy; fine index of each driver sample in recv): the
  // driver's samples and, between consecutive ones, the S - 1 sub-samples and (exact profile) every row and
  // diagonal crossing of the triangulation, at the triangulated surface's heights. Returns their count.
  // Positions xs in fine units (driver sample s at s * S). Every crossing is kept, also where the surface
  // does not bend (coplanar facets): each piece between two points then lies on one facet (or along an
  // edge), so a partly visible piece radiates its own facet's light. (Leaving the crossings without a
  // bend out saves a quarter of p2's time on terraces, but the merged pieces' mean-and-trend radiance
  // moved blocks' bias against the centre gather from -0.00013 to -0.00035: measure_p2_centre, K = 64.)
  int exact_samples(const SweepLine& line, int S) {
    const int n0 = line.count;
    const std::size_t cap = std::size_t(n0) * std::size_t(S + 3);
    if (xs.size() < cap) xs.resize(cap), fx.resize(cap), fy.resize(cap), h.resize(cap);
    if (recv.size() < std::size_t(n0)) recv.resize(std::size_t(n0));
    int n = 0;
    double t[24];
    for (int s = 0; s < n0; ++s) {
      recv[s] = n;
      const double x0 = line.x(s), y0 = line.y(s);
      xs[n] = double(s) * S, fx[n] = x0, fy[n] = y0, h[n] = line.z[s];
      ++n;
      if (s + 1 == n0) break;
      const double x1 = line.x(s + 1), y1 = line.y(s + 1);
      int m = edge_crossings(x0, y0, x1, y1, t);
      for (int sub = 1; sub < S; ++sub) t[m++] = double(sub) / S;
      for (int a = S > 1 ? 1 : m; a < m; ++a)  // insertion sort (the crossings come sorted)
        for (int b = a; b > 0 && t[b] < t[b - 1]; --b) std::swap(t[b], t[b - 1]);
      double last = 0;
      for (int c = 0; c < m; ++c) {
        // Points within kMinGap of a sample or another point are that point already (to kMinGap times the
        // surface's slope); closer ones would make slopes between them rounding noise.
        if (!(t[c] > last + kMinGap && t[c] < 1 - kMinGap)) continue;
        last = t[c];
        const double x = x0 + t[c] * (x1 - x0), y = y0 + t[c] * (y1 - y0);
        xs[n] = (double(s) + t[c]) * S, fx[n] = x, fy[n] = y, h[n] = field->triangle_height(x, y);
        ++n;
      }
    }
    return n;
  }

  void operator()(const SweepLine& line, float* out) {
    const int S = std::max(1, spec->supersampling);
    const bool gather = spec->gather;
    const bool facets = spec->exit_facets != nullptr;
    const bool exact = facets && spec->exact_profile;
    const int n0 = line.count;
    lag = 0;
    if (near_field)  // the samples at least near_radius texels away
      lag = std::max(1, int(std::floor(spec->near_radius * S / (line.step / field->texel_size) + 1e-9)));
    int n;  // fine samples; driver sample s is fine sample fine_of(s)
    if (exact) {
      n = exact_samples(line, S);
    } else {
      n = (n0 - 1) * S + 1;  // fine sample q is driver sample q / S
      if (int(h.size()) < n) h.resize(n);
    }
    auto fine_of = [&](int s) { return exact ? recv[s] : s * S; };
    const int ib = fine_of(line.inside_begin);
    const int ie = line.inside_end > line.inside_begin ? fine_of(line.inside_end - 1) + 1 : ib;
    if (int(L.size()) < n) {
      L.resize(n);
      seg_mean.resize(n);
      seg_slope.resize(n);
    }
    auto fine_xy = [&](int q, double* x, double* y) {
      if (exact) {
        *x = fx[q], *y = fy[q];
        return;
      }
      const int s = q / S, sub = q % S;
      *x = line.x(s), *y = line.y(s);
      if (sub == 0) return;
      const double f = double(sub) / S;
      *x += f * (line.x(s + 1) - line.x(s));
      *y += f * (line.y(s + 1) - line.y(s));
    };
    if (!exact)
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
      if (exact) {
        // Each piece between two points of an exact profile lies on one facet (or along an edge: both
        // halves), so its radiance is that facet's: facet_segment_radiance of a single piece, without the
        // search for crossings.
        const double px = -line.dir->dy * 1e-6, py = line.dir->dx * 1e-6;
        const Rgb* fe = spec->exit_facets->data();
        for (int q = 0; q + 1 < n; ++q) {
          const double mx = 0.5 * (fx[q] + fx[q + 1]), my = 0.5 * (fy[q] + fy[q + 1]);
          const FacetRef a = facet_under(mx + px, my + py), b = facet_under(mx - px, my - py);
          const Rgb va = facet_value(*field, fe, a);
          seg_mean[q] = a == b ? va : (va + facet_value(*field, fe, b)) * 0.5f;
          seg_slope[q] = Rgb{};
        }
      } else if (facets) {
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
    const double* X = exact ? xs.data() + ib : nullptr;  // positions (null: sample q at q)
    SegmentRadiance seg;                                 // terrain-relative like hh
    seg.mean = seg_mean.data() + ib;
    seg.slope = seg_slope.data() + ib;
    const int T = ie - ib;
    const double inv_step = S / line.step;
    if (gather && !exact && (int(inv_dist.size()) < n || inv_dist_step != inv_step)) {
      inv_dist.resize(std::max<std::size_t>(inv_dist.size(), std::size_t(n)));
      inv_dist[0] = 0;
      for (std::size_t d = 1; d < inv_dist.size(); ++d) inv_dist[d] = inv_step / double(d);
      inv_dist_step = inv_step;
    }
    // The world slope from terrain sample j up to receiver r.
    auto slope_to = [&](int j, int r) {
      return X ? (hh[j] - hh[r]) * inv_step / (X[r] - X[j]) : (hh[j] - hh[r]) * inv_dist[r - j];
    };
    if (!naive) {
      tree.reset(T);
      if (visible.size() < std::size_t(T)) {  // the tree's horizons and the run starts, with slopes
        visible.resize(std::size_t(T)), visible_slope.resize(std::size_t(T));
        starts.resize(std::size_t(T)), start_slope.resize(std::size_t(T));
      }
    }
    const std::uint64_t it0 = tree.iterations();
    // Exact near field at the texels: the receivers gather only the samples at least `lag` fine samples
    // (fine units of position) behind them (near_radius texels), from a tree that lags that far.
    const bool near = lag > 0;
    const bool repeat = line.dir->repeat;
    int pushed = ib;  // the next terrain sample to push
    for (int s = 0; s < n0; ++s) {
      const int q = fine_of(s);
      const double pos_q = X ? xs[q] : double(q);
      if (!naive)
        for (; pushed < ie && (X ? xs[pushed] <= pos_q - lag : pushed <= q - lag); ++pushed) {
          if (X)
            tree.push_at(xs[pushed], h[pushed]);
          else
            tree.push(h[pushed]);
          stats.pushed += 1;
          stats.horizons_pushed += tree.horizons().size();
        }
      if (s < line.first_receiver) continue;
      const bool terrain = q >= ib && q < ie;
      float* o = out + std::size_t(s - line.first_receiver) * kChannels;
      o[kRadianceR] = o[kRadianceG] = o[kRadianceB] = o[kTerrainWeight] = 0;
      o[kHorizonElevation] = -p1::kHalfPiF;  // nothing behind: P1's convention
      // Beyond a clamp field's edge only the receivers within a texel of it are read (texel_taps: a texel
      // blends the lines just below and above it on its column); the rest of the line's run off the field
      // stays at the values above, unread.
      if (!terrain && !repeat) {
        const double v = line.dir->x_major ? line.y(s) : line.x(s);
        if (v < -1 - kReadMargin || v > double(line.dir->n_minor) + kReadMargin) continue;
      }
      const int r = q - ib;
      // The terrain samples gathered here, 0..terrain_end-1: all before the receiver, or with the near
      // field those at least `lag` behind it (what the lagging tree holds).
      int terrain_end;
      if (!near)
        terrain_end = std::min(r, T);
      else if (!X)
        terrain_end = std::min(r - lag + 1, T);
      else if (!naive)  // the samples pushed: those at least `lag` behind (all before r, since lag > 0)
        terrain_end = pushed - ib;
      else
        terrain_end = int(std::upper_bound(X, X + std::max(0, std::min(r, T)), pos_q - lag) - X);
      if (terrain_end <= 0) continue;  // no (far) terrain behind this receiver
      if (terrain) {
        stats.receivers += 1;
        stats.naive_iterations += std::uint64_t(r);
      }
      int ns = 0;                      // run starts
      const double* slopes = nullptr;  // their slopes (null: the gather computes them)
      if (naive) {
        naive_visible(hh, r, visible, terrain_end, X);
        run_starts_of_visible(visible, starts);
        ns = int(starts.size());
        if (terrain) stats.iterations += std::uint64_t(r);
      } else {
        if (near || !terrain) {
          // near: the tree holds the samples 0..terrain_end-1, what the receiver sees of them; !terrain:
          // beyond a clamp field's border, sees the terrain, is not terrain itself
          std::uint64_t checks = 0;
          const int m =
              tree.query(X ? X[r] : double(r), hh[r], visible.data(), visible_slope.data(), &checks);
          ns = run_starts(hh, r, visible.data(), visible_slope.data(), m, starts.data(), start_slope.data(),
                          X);
        } else {
          const auto hz = tree.horizons();
          ns = run_starts(hh, r, hz.data(), tree.horizon_slopes().data(), int(hz.size()), starts.data(),
                          start_slope.data(), X);
          stats.horizons += hz.size();
        }
        slopes = start_slope.data();
      }
      if (terrain) stats.run_starts += std::uint64_t(ns);
      if (!gather) continue;
      const TexelPair t = line.height_taps(s, *field);
      const Vec3 nrm =
          normalize((*normals)[t.texel[0]].d() * t.weight[0] + (*normals)[t.texel[1]].d() * t.weight[1]);
      const WedgeWeights w = WedgeWeights::make(nrm, line.dir->dx, line.dir->dy, wedge);
      double weight = 0;
      // Below the nearest sample the receiver sees its own surface: its radiance, or with facet senders
      // the segment it stands at the end of.
      seg.crease = facets ? seg_mean[ib + r - 1] : L[ib + r];
      seg.has_crease = !near;
      // With the near field the texel uses this far terrain only above its near field's horizon: gather
      // it above this sample's own near horizon (its samples within the lag), so that far terrain hidden
      // behind the near field does not enter the mean (when nothing is left, the texel's near field's
      // mean fills in).
      WedgeWeights wf = w;
      if (near)
        for (int j = std::max(0, terrain_end); j < std::min(r, T); ++j)
          wf.t_n = std::max(wf.t_n, slope_to(j, r));
      const Rgb e = gather_segments(hh, seg, r, terrain_end, {starts.data(), std::size_t(ns)}, inv_step, wf,
                                    &weight, X ? nullptr : inv_dist.data(), &gather_scratch, X, slopes);
      o[kRadianceR] = e.r;
      o[kRadianceG] = e.g;
      o[kRadianceB] = e.b;
      o[kTerrainWeight] = float(weight);
      // The global horizon's elevation exactly as P1's HorizonLineWorker computes it.
      if (!spec->p1_sin_horizon && ns > 0) {  // (unused when P1's horizons split the lobe)
        const int c = starts.front();
        const double run = X ? X[r] - X[c] : double(r - c);
        o[kHorizonElevation] = p1::fast_elevation(float(hh[c] - hh[r]), float(run) * float(line.step / S));
      }
    }
    if (!naive) stats.iterations += tree.iterations() - it0;
  }
};

// One crossing of P1's near-field stencil (p1::NearCrossing) with the facets beside the piece of the ray
// that ends at it (from the previous crossing, or from the texel centre).
struct NearPiece {
  p1::NearCrossing c;
  FacetRef a, b;  // the facets beside the piece (facets_beside), relative to the texel
  // The first piece (from the texel centre): which of the texel's corner facets a and b are.
  int ca = -1, cb = -1;
  // For texels whose stencil lies on the field (NearStencil::margin): the offsets of the edge's end points
  // in the field's heights, from the texel's own.
  std::ptrdiff_t za = 0, zb = 0;
};

// P1's near stencil of one direction with its facets, and how far it reaches: texels at least `margin`
// texels from every border read only heights and facets on the field, unwrapped and unclamped.
struct NearStencil {
  std::vector<NearPiece> pieces;
  int margin = 0;
};

NearStencil near_stencil(const HeightField& f, double dx, double dy, double radius) {
  NearStencil out;
  float px = 0, py = 0;
  int reach = 0;
  auto cover = [&](int d) { reach = std::max(reach, std::abs(d)); };
  const std::ptrdiff_t w = f.width;
  for (const p1::NearCrossing& c : p1::near_field_stencil(dx, dy, radius, f.texel_size)) {
    NearPiece p;
    p.c = c;
    std::tie(p.a, p.b) = facets_beside(0.5 * (px + c.x), 0.5 * (py + c.y), dx, dy);
    p.za = c.ai + c.aj * w, p.zb = c.bi + c.bj * w;
    if (out.pieces.empty()) {
      p.ca = corner_facet_index(p.a.i, p.a.j, p.a.q), p.cb = corner_facet_index(p.b.i, p.b.j, p.b.q);
      if (p.ca < 0 || p.cb < 0) throw std::logic_error("near_stencil: a first piece off the texel's facets");
    }
    for (int d : {c.ai, c.aj, c.bi, c.bj, p.a.i, p.a.j, p.b.i, p.b.j}) cover(d);
    cover(int(std::ceil(std::fabs(c.x))) + 1), cover(int(std::ceil(std::fabs(c.y))) + 1);
    out.pieces.push_back(p);
    px = c.x, py = c.y;
  }
  out.margin = reach;
  return out;
}

// The visible near field of texel (i, j) along one direction: elevation intervals (world slopes, the
// lowest from -infinity: the crease down to any tangent plane) and the facet radiance of each, in `out`
// (empty when the stencil leaves a clamp field at once). Marched outward: a piece is visible above
// everything nearer, so the intervals tile the elevations up to the steepest near crossing.
// The crease radiates the first piece's corner facet light at the texel (IndirectSweepSpec::corner_exit), and
// a piece the light at the middle of its visible part, interpolated over its facet (corner_light).
struct NearInterval {
  double lo, hi;
  Rgb L;
};

// The light of facet r (texel-centred, absolute) at the point (x, y) of it (texel coordinates), from its
// three corners' values in corner_exit (the barycentric weights of facet_weights, the facet's own).
Rgb corner_light(const HeightField& f, const Rgb* corner_exit, FacetRef r, double x, double y) {
  const int qi = r.i - r.q, qj = r.j - r.q;  // the quad the facet lies in
  const double fx = std::clamp(x - qi, 0.0, 1.0), fy = std::clamp(y - qj, 0.0, 1.0);
  double w[3];
  facet_corner_weights(r.q, fx, fy, w);
  Rgb sum{};
  for (int c = 0; c < 3; ++c) {
    const std::size_t t =
        f.index(f.wrap_i(qi + kWeightCorner[r.q][c][0]), f.wrap_j(qj + kWeightCorner[r.q][c][1]));
    sum += corner_exit[kCornerFacets * t + kWeightCornerFacet[r.q][c]] * float(std::max(0.0, w[c]));
  }
  return sum;
}

void march_near(const HeightField& f, const NearStencil& st, const Rgb* corner_exit, int i, int j,
                std::vector<NearInterval>& out) {
  out.clear();
  const std::size_t idx = f.index(i, j);
  const double z0 = f.z[idx];
  double m = -std::numeric_limits<double>::infinity();
  // The previous crossing (the texel centre at first): its height above the texel and world distance.
  double prev_dz = 0, prev_s = 0, prev_x = 0, prev_y = 0;
  const bool clamp = f.wrap == Wrap::clamp;
  const int g = st.margin;
  const bool inside = i >= g && j >= g && i + g < f.width && j + g < f.height;  // the stencil on the field
  for (const NearPiece& p : st.pieces) {
    const p1::NearCrossing& c = p.c;
    float za, zb;
    if (inside) {
      za = f.z[std::size_t(std::ptrdiff_t(idx) + p.za)], zb = f.z[std::size_t(std::ptrdiff_t(idx) + p.zb)];
    } else {
      const float px = float(i) + c.x, py = float(j) + c.y;
      if (clamp &&
          (px < -1e-4f || py < -1e-4f || px > float(f.width - 1) + 1e-4f || py > float(f.height - 1) + 1e-4f))
        break;  // the terrain ends at the border
      za = f.at(i + c.ai, j + c.aj), zb = f.at(i + c.bi, j + c.bj);
    }
    const double dz = double(za + (zb - za) * c.w) - z0, s = 1.0 / double(c.inv_s);
    const double slope = dz * c.inv_s;
    if (slope > m) {
      const FacetRef a{i + p.a.i, j + p.a.j, p.a.q}, b{i + p.b.i, j + p.b.j, p.b.q};
      Rgb L;
      if (out.empty()) {  // the crease: the first piece's facet at the texel itself
        const Rgb* x = corner_exit + kCornerFacets * idx;
        L = p.ca == p.cb ? x[p.ca] : (x[p.ca] + x[p.cb]) * 0.5f;
      } else {
        // The part of the piece above m starts where the line from the previous crossing (prev_s, prev_dz)
        // to this one is seen at slope m; its middle is where the light is read.
        const double den = (dz - prev_dz) - m * (s - prev_s);
        double t0 = den > 0 ? (m * prev_s - prev_dz) / den : 0.0;
        t0 = std::clamp(t0, 0.0, 1.0);
        const double h = 0.5 * (t0 + 1);
        const double x = i + prev_x + h * (c.x - prev_x), y = j + prev_y + h * (c.y - prev_y);
        L = p.a == p.b
                ? corner_light(f, corner_exit, a, x, y)
                : (corner_light(f, corner_exit, a, x, y) + corner_light(f, corner_exit, b, x, y)) * 0.5f;
      }
      out.push_back({m, slope, L});
      m = slope;
    }
    prev_dz = dz, prev_s = s, prev_x = c.x, prev_y = c.y;
  }
}

// Per thread of the texel visitor: the near intervals, and the facet normals of the last texel (the
// visitor runs the directions of a batch texel by texel).
struct NearScratch {
  std::vector<NearInterval> intervals;
  int fi = -1, fj = -1;
  Vec3f fn[kCornerFacets];  // corner_facet_normals of texel (fi, fj)
};

}  // namespace

void facet_segment_radiance(const HeightField& f, const Rgb* facet_exit, double x0, double y0, double x1,
                            double y1, Rgb* mean, Rgb* slope) {
  // Split where x, y or x + y (the quads' diagonals) pass an integer.
  double t[8];
  int n = edge_crossings(x0, y0, x1, y1, t);
  t[n++] = 1;
  Rgb m{}, m1{};
  double a = 0;
  for (int p = 0; p < n; ++p) {
    const double b = t[p];
    if (!(b > a)) continue;
    const double u = 0.5 * (a + b), x = x0 + u * (x1 - x0), y = y0 + u * (y1 - y0);
    const Rgb v = piece_radiance(f, facet_exit, x, y, x1 - x0, y1 - y0);
    m += v * float(b - a);
    // first moment about the middle, for the least-squares linear trend: integral of (u - 1/2) du
    m1 += v * float(0.5 * (b - a) * (a + b - 1));
    a = b;
  }
  *mean = m;
  *slope = m1 * 12.0f;  // / integral of (u - 1/2)^2 over [0, 1]
}

std::size_t indirect_line_scratch_bytes(int count, int supersampling, bool exact_profile) {
  const std::size_t fine =
      std::size_t(std::max(count, 1)) * std::size_t(supersampling + (exact_profile ? 3 : 0));
  // h, inv_dist 8 + 8; L, seg_mean, seg_slope 36; exact: xs, fx, fy 24; recv 4 per driver sample; the hull
  // tree's nodes 32, its stack 16 and horizons with slopes 12; gather scratch 20; visible and starts with
  // their slopes 24.
  return fine * (16 + 36 + (exact_profile ? 24 : 0) + 60 + 20 + 24) + std::size_t(count) * 4;
}

RunControl p2_sub_range(const RunControl& rc, double a, double span) {
  RunControl s;
  s.cancel = rc.cancel;
  if (rc.progress) s.progress = [&rc, a, span](double f) { rc.report(a + span * f); };
  return s;
}

SweepSpec indirect_sweep_spec(const IndirectSweepSpec& spec) {
  SweepSpec ss;
  ss.directions = spec.directions;
  const int k1 = spec.k_end < 0 ? spec.directions : spec.k_end;
  for (int k = spec.k_begin; k < k1; ++k) ss.azimuths.push_back(azimuth(k, spec.directions));
  ss.channels = kChannels;
  ss.wrap_periods = spec.wrap_periods;
  ss.buffers.zero = false;  // LineWorker writes every receiver's channels
  return ss;
}

void sweep_indirect_sums(const HeightField& field, const std::vector<Vec3f>& normals,
                         const std::vector<Rgb>& exit, const IndirectSweepSpec& spec, const RunControl& rc,
                         P2SweepStats* stats, std::vector<double>& acc, std::vector<double>* facet_acc) {
  const std::size_t texels = field.texel_count();
  acc.assign(texels * 3, 0.0);
  const bool facets = spec.exit_facets && facet_acc;
  std::vector<double> no_facets;
  std::vector<double>& acc_f =
      facets ? *facet_acc : no_facets;  // [(kCornerFacets * texel + c) * 3 + channel]
  acc_f.assign(facets ? texels * kCornerFacets * 3 : 0, 0.0);
  // The sweep's direction k is direction k_begin + k of K (indirect_sweep_spec's azimuths).
  const SweepSpec ss = indirect_sweep_spec(spec);
  const int K = spec.directions, nb = int(ss.azimuths.size());
  const double wedge = 2 * kPi / K;
  std::vector<double> cs, sn;
  azimuth_table(K, cs, sn);
  cs.erase(cs.begin(), cs.begin() + spec.k_begin), cs.resize(std::size_t(nb));
  sn.erase(sn.begin(), sn.begin() + spec.k_begin), sn.resize(std::size_t(nb));
  P2SweepStats totals;
  std::mutex totals_mutex;
  // Exact near field (IndirectSweepSpec::near_radius): P1's near stencil per direction, with facets.
  const bool near = spec.near_radius > 0 && spec.exit_facets && spec.p1_sin_horizon && spec.gather;
  std::vector<NearStencil> pieces(near ? nb : 0);
  for (int k = 0; k < int(pieces.size()); ++k) {
    const SweepDirection d = plan_direction(field, ss, k);
    pieces[k] = near_stencil(field, d.dx, d.dy, spec.near_radius);
  }
  // The visitor runs for one direction at a time on each thread (its scratch is per thread).
  tbb::enumerable_thread_specific<NearScratch> near_scratch;
  // A texel's terrain part of direction k with the exact near field: the near intervals exactly (clipped to
  // each normal's tangent plane and to P1's horizon e), and above the near field up to e the mean radiance
  // the lines' receivers gathered from the far samples (terrain_weight minus the near intervals' weight:
  // the parts tile the lobe below P1's horizon exactly). For the texel's normal and, when the next bounce
  // needs them, its two facets'.
  auto texel_near_far = [&](int k, int i, int j, std::size_t idx, const TexelTaps& t, double e, double se,
                            double ce) {
    NearScratch& ns = near_scratch.local();
    std::vector<NearInterval>& iv = ns.intervals;
    march_near(field, pieces[k], spec.corner_exit->data(), i, j, iv);
    const double top = ce > 0 ? se / ce : std::numeric_limits<double>::infinity();  // tan e
    const double wb = t.value(kTerrainWeight);
    const bool has_far = wb > 0;  // else the samples saw no far terrain: the near field's mean fills in
    const Rgb far_mean = has_far ? Rgb{float(t.value(kRadianceR) / wb), float(t.value(kRadianceG) / wb),
                                       float(t.value(kRadianceB) / wb)}
                                 : Rgb{};
    auto part = [&](Vec3 n, double* a) {
      const double tw = terrain_weight(n, cs[k], sn[k], K, e, se, ce);
      if (!(tw > 0)) return;
      const WedgeWeights w = WedgeWeights::make(n, cs[k], sn[k], wedge);
      double er = 0, eg = 0, eb = 0, wn = 0;
      // The intervals tile the elevations, so an interval's lower bound is mostly the last one's upper
      // bound: F there is reused (compared bit for bit; F is a plain function of its argument).
      std::uint64_t last_t = std::bit_cast<std::uint64_t>(std::numeric_limits<double>::quiet_NaN());
      double last_F = 0;
      for (const NearInterval& v : iv) {
        const double lo = std::max(v.lo, w.t_n), hi = std::min(v.hi, top);
        if (!(hi > lo)) continue;
        const double F_lo = std::bit_cast<std::uint64_t>(lo) == last_t ? last_F : w.F(lo);
        const double F_hi = w.F(hi);
        last_t = std::bit_cast<std::uint64_t>(hi), last_F = F_hi;
        const double d = F_hi - F_lo;
        er += v.L.r * d, eg += v.L.g * d, eb += v.L.b * d, wn += d;
      }
      er /= kPi, eg /= kPi, eb /= kPi, wn /= kPi;
      const double wf = std::max(0.0, tw - wn);
      Rgb fm = far_mean;
      if (!has_far) fm = wn > 0 ? Rgb{float(er / wn), float(eg / wn), float(eb / wn)} : exit[idx];
      a[0] += er + fm.r * wf, a[1] += eg + fm.g * wf, a[2] += eb + fm.b * wf;
    };
    part(normals[idx].d(), acc.data() + idx * 3);
    if (facets) {
      if (ns.fi != i || ns.fj != j) corner_facet_normals(field, i, j, ns.fn), ns.fi = i, ns.fj = j;
      for (int q = 0; q < kCornerFacets; ++q)
        part(ns.fn[q].d(), acc_f.data() + (kCornerFacets * idx + q) * 3);
    }
  };
  sweep_lines(
      field, ss, rc,
      [&] {
        LineWorker w;
        w.field = &field;
        w.normals = &normals;
        w.exit = &exit;
        w.spec = &spec;
        w.wedge = wedge;
        w.near_field = near;
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
          const float sf = std::clamp(spec.p1_sin_horizon[std::size_t(k) * texels + idx], -1.0f, 1.0f);
          const float cf = std::sqrt(std::max(0.0f, 1 - sf * sf));
          se = sf, ce = cf;
          e = cf > 0 ? double(p1::fast_atan(sf / cf)) : std::copysign(kPi / 2, double(sf));
        } else {
          e = t.value(kHorizonElevation);
          float sf, cf;
          p1::fast_sincos(float(e), sf, cf);
          se = sf, ce = cf;
        }
        const double wb = t.value(kTerrainWeight);
        if (near) {
          texel_near_far(k, i, j, idx, t, e, se, ce);
          return;
        }
        if (facets) {  // the same mean terrain radiance over the facets' lobes
          NearScratch& ns = near_scratch.local();
          if (ns.fi != i || ns.fj != j) corner_facet_normals(field, i, j, ns.fn), ns.fi = i, ns.fj = j;
          const Vec3f* fn = ns.fn;
          for (int q = 0; q < kCornerFacets; ++q) {
            const std::size_t fi = kCornerFacets * idx + q;
            const double tf = terrain_weight(fn[q].d(), cs[k], sn[k], K, e, se, ce);
            if (!(tf > 0)) continue;
            double* a = acc_f.data() + fi * 3;
            if (wb > 0) {
              a[0] += t.value(kRadianceR) * tf / wb, a[1] += t.value(kRadianceG) * tf / wb,
                  a[2] += t.value(kRadianceB) * tf / wb;
            } else {  // the samples saw no terrain: the texel's own surface
              const Rgb x = (*spec.corner_exit)[fi];
              a[0] += x.r * tf, a[1] += x.g * tf, a[2] += x.b * tf;
            }
          }
        }
        const double tw = terrain_weight(normals[idx].d(), cs[k], sn[k], K, e, se, ce);
        if (!(tw > 0)) return;
        double* a = acc.data() + idx * 3;
        if (wb > 0) {
          const double f = tw / wb;
          a[0] += t.value(kRadianceR) * f;
          a[1] += t.value(kRadianceG) * f;
          a[2] += t.value(kRadianceB) * f;
        } else {  // the samples see no terrain above their tangent planes, the texel does: its own surface
          a[0] += exit[idx].r * tw;
          a[1] += exit[idx].g * tw;
          a[2] += exit[idx].b * tw;
        }
      });
  if (stats) *stats = totals;
}

void add_indirect_block(std::vector<float>& total, const std::vector<double>& block) {
  if (total.empty()) {  // the first block, split once
    total.resize(2 * block.size());
    for (std::size_t i = 0; i < block.size(); ++i) {
      const SplitDouble s = split_double(block[i]);
      total[2 * i] = s.hi, total[2 * i + 1] = s.lo;
    }
    return;
  }
  for (std::size_t i = 0; i < block.size(); ++i) {
    SplitDouble t{total[2 * i], total[2 * i + 1]};
    add_split(t, split_double(block[i]));
    total[2 * i] = t.hi, total[2 * i + 1] = t.lo;
  }
}

std::vector<Rgb> indirect_of_total(const float* total, std::size_t count) {
  std::vector<Rgb> out(count);
  auto at = [&](std::size_t i) { return float(join_double({total[2 * i], total[2 * i + 1]})); };
  for (std::size_t p = 0; p < count; ++p) out[p] = {at(3 * p), at(3 * p + 1), at(3 * p + 2)};
  return out;
}

void add_sweep_stats(P2SweepStats& total, const P2SweepStats& s) {
  total.receivers += s.receivers;
  total.iterations += s.iterations;
  total.naive_iterations += s.naive_iterations;
  total.horizons += s.horizons;
  total.run_starts += s.run_starts;
  total.pushed += s.pushed;
  total.horizons_pushed += s.horizons_pushed;
}

std::vector<Rgb> sweep_indirect(const HeightField& field, const std::vector<Vec3f>& normals,
                                const std::vector<Rgb>& exit, const IndirectSweepSpec& spec,
                                const RunControl& rc, P2SweepStats* stats, std::vector<Rgb>* facet_result) {
  const int K = spec.directions, B = direction_block_count(K);
  const std::size_t texels = field.texel_count();
  const bool facets = spec.exit_facets && facet_result;
  std::vector<float> total, facet_total;
  std::vector<double> acc, acc_f;
  P2SweepStats st;
  for (int b = 0; b < B; ++b) {
    IndirectSweepSpec s = spec;
    s.k_begin = direction_block_begin(b, K), s.k_end = direction_block_begin(b + 1, K);
    if (spec.p1_sin_horizon) s.p1_sin_horizon = spec.p1_sin_horizon + std::size_t(s.k_begin) * texels;
    P2SweepStats block_stats;
    sweep_indirect_sums(field, normals, exit, s,
                        p2_sub_range(rc, double(s.k_begin) / K, double(s.k_end - s.k_begin) / K),
                        &block_stats, acc, facets ? &acc_f : nullptr);
    add_sweep_stats(st, block_stats);
    add_indirect_block(total, acc);
    if (facets) add_indirect_block(facet_total, acc_f);
  }
  if (facets) *facet_result = indirect_of_total(facet_total.data(), kCornerFacets * texels);
  if (stats) *stats = st;
  return indirect_of_total(total.data(), texels);
}

}  // namespace hfbake
