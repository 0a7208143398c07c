#include "methods/ao/lsao.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/azimuth.hpp"
#include "core/direction_blocks.hpp"
#include "field/edge_crossings.hpp"
#include "field/triangulation.hpp"
#include "methods/ao/bake_ao.hpp"
#include "methods/ao/lsao_chain_hull.hpp"
#include "methods/ao/obscurance_params.hpp"
#include "methods/ao/slice_integral.hpp"
#include "methods/ao/triangle_profile.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake {
namespace {

// The vertices of the triangulated surface (field/triangulation.hpp) on the segment between two consecutive
// line samples A = (xa, ya) and B (one column or row apart): where it crosses a row, a column or a quad's
// diagonal (x + y integer), strictly between them, as visit(w, height) in increasing w (A + w (B - A)).
// The samples themselves lie on cell edges, where the triangulated and bilinear surfaces agree.
template <class Visit>
void line_crossings(const HeightField& f, double xa, double ya, double xb, double yb, Visit&& visit) {
  EdgeCrossing c[kMaxEdgeCrossings];
  const int count = edge_crossings(xa, ya, xb, yb, c);
  for (int k = 0; k < count; ++k) {
    const double t = c[k].t;
    if (!(t > 1e-9 && t < 1 - 1e-9)) continue;
    // Exactly on the edge's line.
    const double m = c[k].m;
    const double x = c[k].family == EdgeFamily::column ? m : xa + t * (xb - xa);
    const double y = c[k].family == EdgeFamily::row        ? m
                     : c[k].family == EdgeFamily::diagonal ? m - x
                                                           : ya + t * (yb - ya);
    const double fx = std::floor(x), fy = std::floor(y);
    const int ii = int(fx), jj = int(fy);
    visit(t, facet_height(x - fx, y - fy, [&](int di, int dj) { return double(f.at(ii + di, jj + dj)); }));
  }
}

// Per receiver sample, two channels: the value for the texel centre below the sample on its column
// (channel 0, floor v) and for the one above (channel 1, floor v + 1), each at the texel's own height and
// at the sample's along-distance. The gather then takes for each texel the channel that is that texel, so
// a receiver is never an interpolated height (on rough terrain that is worth about 1 % of AO against a
// march from the texel centres); axis and diagonal directions sample texel centres exactly.
// With the bent normal (receiver tangent, or the fixed one's hull estimator with texel receivers), four more
// channels: per texel (c = 0, 1) the slice components (along the direction, up) of the cosine-weighted open
// direction about the texel's normal (lsao_sums).
struct LsaoWorker {
  const LsaoOptions* options = nullptr;
  const HeightField* field = nullptr;
  const std::vector<Vec3f>* normals = nullptr;  // empty: recomputed per tap (normal_at)
  std::atomic<std::uint64_t>* samples = nullptr;
  std::atomic<std::uint64_t>* iterations = nullptr;
  std::atomic<std::uint64_t>* work = nullptr;  // LsaoStats queries, walked, bands
  ObscuranceHull hull;
  std::vector<SlicePoint> terrain;  // brute force only: the terrain samples seen so far

  double brute(SlicePoint p) const {
    const OcclusionFunction& f = options->occlusion;
    const bool visible_only = options->estimator == LsaoEstimator::brute_visible;
    double v = f.none(), max_sin = -2.0;
    for (std::size_t q = terrain.size(); q-- > 0;) {
      const double hs = p.s - terrain[q].s, hz = terrain[q].z - p.z;
      const double se = sine_elevation(hs, hz);
      if (visible_only) {
        if (se < max_sin) continue;
        max_sin = se;
      }
      v = std::max(v, f(hs, hz));
    }
    return v;
  }

  bool bent = false;
  // LsaoTangent::receiver: the chain hull of the current block and the window's previous block.
  ChainHull chain_hull;
  WindowHull window;

  // The texel's normal: held (compute_normals) or recomputed from the heights (normal_at, the same values)
  // on fields too large to hold them (lsao_holds_normals).
  Vec3f normal(std::size_t ti) const {
    return !normals->empty()
               ? (*normals)[ti]
               : normal_at(*field, int(ti % std::size_t(field->width)), int(ti / std::size_t(field->width)));
  }

  // The near field of texel ti (LsaoOptions::near_radius): its own ray towards the line's azimuth over
  // every column, row and diagonal crossing of the triangulated surface up to `near` texels (the field's
  // border on clamp fields), each vertex a band of the chain at its own distance.
  void near_field(std::size_t ti, double near, TangentChain& chain) const {
    const HeightField& fd = *field;
    const int i = int(ti % std::size_t(fd.width)), j = int(ti / std::size_t(fd.width));
    const double dx = line_dx, dy = line_dy, ts = fd.texel_size, z0 = double(fd.z[ti]);
    const double t_end = profile_end(fd, i, j, dx, dy, near);
    if (t_end > 1e-9)
      triangle_profile(fd, i, j, dx, dy, t_end,
                       [&](double t, double z) { chain.add(t * ts, z - z0, t * ts); });
  }
  double line_dx = 1, line_dy = 0;  // the current line's unit direction towards its azimuth

  // The line's terrain points (receiver tangent), walk order; group: count + 1 entries (see receiver_line).
  std::vector<ChainPoint> points;
  std::vector<int> group;
  void line_points(const SweepLine& line, bool crossings) {
    points.clear();
    group.clear();
    points.reserve(std::size_t(crossings ? 4 : 1) * std::size_t(line.count));
    group.reserve(std::size_t(line.count) + 1);
    for (int n = 0; n < line.count; ++n) {
      group.push_back(int(points.size()));
      if (!line.is_terrain(n)) continue;
      if (crossings && n > 0 && line.is_terrain(n - 1))
        line_crossings(*field, line.x(n - 1), line.y(n - 1), line.x(n), line.y(n), [&](double w, double z) {
          points.push_back({line.s(n - 1) + w * line.step, z, 0, 0, 0, n});
        });
      const double s = line.s(n), z = double(line.z[n]);
      points.push_back({s, z, s, z, z, n});
    }
    group.push_back(int(points.size()));
  }

  // LsaoTangent::receiver (lsao_chain_hull.hpp): every texel a receiver at its own height and tangent.
  void receiver_line(const SweepLine& line, float* out) {
    line_dx = line.dir->dx, line_dy = line.dir->dy;
    const OcclusionFunction& f = options->occlusion;
    const int C = bent ? 6 : 2;
    const bool use_brute = options->estimator != LsaoEstimator::hull;
    const Weighting weighting =
        f.weighting == ObscuranceWeighting::cosine ? Weighting::cosine : Weighting::uniform;
    const double support = f.rho.support(1e-4);
    const double coalesce = options->band_tolerance;
    // The near field (texels): marched from each texel itself; the hull's points nearer than it left out.
    const double near = std::min(options->near_radius, support / field->texel_size);
    const double near_world = near > 0 ? near * field->texel_size : 0.0;
    const double tol = near_world > 0 ? options->near_rho_tolerance : options->rho_tolerance;
    // The line's terrain points in walk order: its samples and (surface triangles) the crossings between
    // them; group[n]: the first point of sample n's group (the crossings before it, then itself).
    const bool triangles = options->surface == LsaoSurface::triangles;
    line_points(line, triangles);
    // The hull's merge test compares rho at the points it merges. A step is flat inside R, so it merged
    // every point there, and the chain lost the points near R that a receiver farther on still has inside
    // it (measured: most of the hull's error with segments). With triangles it is judged on the linear
    // falloff of the same radius: merged points then lie within `tol` R of each other.
    const Falloff merge_rho =
        triangles && f.rho.kind == FalloffKind::step ? Falloff{FalloffKind::linear, f.rho.radius} : f.rho;
    // Falloffs that end: the hull holds the current block of W samples, `window` the previous one.
    // With segments the window reaches two samples beyond the support (the segment that crosses it).
    const int W =
        use_brute
            ? 0
            : chain_window(triangles ? Falloff{f.rho.kind, f.rho.radius + 2 * line.step} : f.rho, line.step);
    const std::size_t cap = points.size();
    chain_hull.clear();
    chain_hull.reserve(W > 0 ? std::min(cap, std::size_t(group[std::min(W, line.count)])) : cap);
    window.clear();
    window.reserve(W > 0 ? std::min(cap, std::size_t(group[std::min(W, line.count)])) : 0);
    terrain.clear();
    if (use_brute) terrain.reserve(cap);
    std::uint64_t tests = 0, queries = 0, walked = 0, bands = 0;
    // With a near field the chain hull holds only the points at least `near_world` behind the receivers
    // that read it (nearer ones are the near field's, marched by each texel), pushed once they are, each
    // after a prune: its merges are judged from at least that distance, where the surface's small kinks
    // between neighbouring samples no longer hide the point behind it, so a stretch of ground that every
    // receiver farther on sees rising is held as few merged points, and a walk never steps over points it
    // leaves out. `next`: the first of `points` not yet pushed (walk order), within the current block.
    const bool delayed = !use_brute && near_world > 0;
    int next = 0;
    for (int n = 0; n < line.count; ++n) {
      const SlicePoint p{line.s(n), double(line.z[n])};
      double z_low = p.z;  // the lowest receiver at this sample
      if (W > 0) {
        if (n > 0 && n % W == 0) {  // a new block: the one before becomes the window's far part
          window.build(points.data() + group[n - W], std::size_t(group[n] - group[n - W]), p.s, merge_rho,
                       tol);
          chain_hull.clear();
          next = group[n];
        }
        window.drop_before(n - W);
      }
      // The crossings between sample n - 1 and n: behind receiver n.
      const int crossings_end = group[n + 1] - (line.is_terrain(n) ? 1 : 0);
      for (int q = group[n]; q < crossings_end && !delayed; ++q) {
        const SlicePoint c{points[std::size_t(q)].s, points[std::size_t(q)].z};
        if (use_brute)
          terrain.push_back(c);
        else
          chain_hull.push(c);
      }
      if (n >= line.first_receiver) {
        float* o = out + C * (n - line.first_receiver);
        const TexelPair taps = line.height_taps(n, *field);
        const double v = line.dir->v(line.line, n), frac = v - std::floor(v);
        for (int c = 0; c < 2; ++c) {
          if (c == 1 && frac == 0) {
            // On a texel row (axis and diagonal directions, 8 of K = 16) the gather reads channel 0 only.
            o[1] = o[0];
            if (bent) o[4] = o[2], o[5] = o[3];
            break;
          }
          const std::size_t ti = std::size_t(taps.texel[c]);
          const Vec3f nv = normal(ti);
          // The texel's height carried to the line along its own tangent plane (as the fixed tangent does).
          const double minor_slope = -(line.dir->x_major ? nv.y : nv.x) / nv.z * field->texel_size;
          const SlicePoint t{p.s, double(field->z[ti]) + (c == 0 ? frac : frac - 1.0) * minor_slope};
          z_low = std::min(z_low, t.z);
          const SliceFrame frame = slice_frame(nv.x * line.dir->dx + nv.y * line.dir->dy, nv.z);
          TangentChain chain(f.rho, weighting, frame);
          chain.want_direction = bent;
          chain.segments = triangles;
          chain.coalesce = triangles ? coalesce : 0.0;
          if (near > 0) near_field(ti, near, chain);
          if (use_brute) {
            brute_chain(terrain.data(), terrain.size(), t, chain, near_world);
          } else {
            chain_hull.query(t, support, chain, near_world);
            window.query(t, support, chain, near_world);  // farther than the whole current block
          }
          chain.finish();
          ++queries, walked += chain.walked, bands += chain.bands;
          // The cosine measure scales with the normal's length in the slice (slice_integral.hpp).
          o[c] = float(weighting == Weighting::cosine ? chain.length * chain.sum : chain.sum);
          if (bent) {
            // Open from the tangent plane up, less the chain's bands weighted by rho (hbao's slab bent
            // normal); the chain's sum is for the unit in-slice normal.
            const SliceVec open = open_direction(frame, frame.tangent, 0.5 * kPi);
            o[2 + 2 * c] = float(open.h - chain.length * chain.direction.h);
            o[3 + 2 * c] = float(open.v - chain.length * chain.direction.v);
          }
        }
      }
      // Merges are judged from the lowest of the sample and its receivers (a point hidden seen from a
      // height is hidden from every point above it, not below).
      const SlicePoint view = triangles ? SlicePoint{p.s, z_low} : p;
      if (delayed) {
        // The points the next sample's receivers read: at least near_world behind it, in this block.
        const double reach = (n + 1 < line.count ? line.s(n + 1) : p.s + line.step) - near_world;
        const int end = W > 0 ? group[std::min(line.count, (n / W + 1) * W)] : int(points.size());
        for (; next < end && points[std::size_t(next)].s <= reach; ++next) {
          tests += chain_hull.prune(view, merge_rho, tol);
          chain_hull.push({points[std::size_t(next)].s, points[std::size_t(next)].z});
        }
        continue;
      }
      if (!use_brute) tests += chain_hull.prune(view, merge_rho, tol);
      if (line.is_terrain(n)) {
        if (use_brute)
          terrain.push_back(p);
        else
          chain_hull.push(p);
      }
    }
    *samples += std::uint64_t(line.count);
    *iterations += tests;
    work[0] += queries, work[1] += walked, work[2] += bands;
  }

  void operator()(const SweepLine& line, float* out) {
    if (options->tangent == LsaoTangent::receiver) return receiver_line(line, out);
    const OcclusionFunction& f = options->occlusion;
    const int C = bent ? 6 : 2;
    hull.clear();
    hull.reserve(std::size_t(line.count));
    terrain.clear();
    const bool use_brute = options->estimator != LsaoEstimator::hull;
    if (use_brute) terrain.reserve(std::size_t(line.count));
    for (int n = 0; n < line.count; ++n) {
      const SlicePoint p{line.s(n), double(line.z[n])};
      if (n >= line.first_receiver) {
        float* o = out + C * (n - line.first_receiver);
        if (options->texel_receivers) {
          const TexelPair taps = line.height_taps(n, *field);
          const double v = line.dir->v(line.line, n), frac = v - std::floor(v);
          for (int c = 0; c < 2; ++c) {
            // The texel's height carried to the line along its own tangent plane (minor-axis slope from its
            // normal): exact on planes, the texel's own detail elsewhere.
            const std::size_t ti = std::size_t(taps.texel[c]);
            const Vec3f nv = normal(ti);
            const double minor_slope = -(line.dir->x_major ? nv.y : nv.x) / nv.z * field->texel_size;
            const SlicePoint t{p.s, double(field->z[ti]) + (c == 0 ? frac : frac - 1.0) * minor_slope};
            SlicePoint occ{-1, 0};
            o[c] = float(use_brute ? brute(t) : hull.query(t, f, bent ? &occ : nullptr));
            if (bent) {
              const SliceFrame frame = slice_frame(nv.x * line.dir->dx + nv.y * line.dir->dy, nv.z);
              SliceVec v = open_direction(frame, frame.tangent, 0.5 * kPi);
              if (occ.s > 0) {
                const double r = f.rho(std::hypot(occ.s, occ.z));
                const SliceVec b = open_direction(frame, frame.tangent, std::atan2(occ.z, occ.s));
                v.h -= r * b.h, v.v -= r * b.v;
              }
              o[2 + 2 * c] = float(v.h), o[3 + 2 * c] = float(v.v);
            }
          }
          if (!use_brute) hull.receive(p, f);  // the sample's own receive maintains the hull (P3 Alg. 1)
        } else {
          o[0] = o[1] = float(use_brute ? brute(p) : hull.receive(p, f));
        }
      } else if (!use_brute) {
        hull.receive(p, f);  // warm-up samples prune like receivers
      }
      if (line.is_terrain(n)) {
        if (use_brute)
          terrain.push_back(p);
        else
          hull.push(p);
      }
    }
    *samples += std::uint64_t(line.count);
    *iterations += hull.iterations();
  }
};

}  // namespace

namespace {

// The sweep of lsao_sums (block < 0: every direction, summed by the farm's blocks, FloatBlocks) or of
// lsao_block_sums (direction block `block` only, summed from zero).
void lsao_sweep(const HeightField& field, const LsaoOptions& options, const RunControl& rc, LsaoStats* stats,
                int block, float* sum, float* bent_xyz) {
  const bool receiver = options.tangent == LsaoTangent::receiver;
  const bool texel_receivers = options.texel_receivers || receiver;
  const bool want_bent =
      bent_xyz && texel_receivers && (receiver || options.estimator == LsaoEstimator::hull);
  const std::size_t N = field.texel_count();
  std::fill_n(sum, N, 0.0f);
  if (bent_xyz) std::fill_n(bent_xyz, 3 * N, 0.0f);
  const int K = std::max(options.directions, 1);
  SweepSpec spec;
  spec.directions = K;
  if (block >= 0)  // the block's azimuths, as plan_direction gives them for k of K
    for (int k = direction_block_begin(block, K); k < direction_block_begin(block + 1, K); ++k)
      spec.azimuths.push_back(azimuth(k, K));
  const int k0 = block >= 0 ? direction_block_begin(block, K) : 0;
  const FloatBlocks blocks(K);
  // Block partial sums between a block's directions (whole bake, blocks of more than one direction).
  std::vector<float> partial(block < 0 && blocks.needs_partial() ? (want_bent ? 4 : 1) * N : 0);
  spec.channels = want_bent ? 6 : 2;
  spec.wrap_periods = std::max(options.wrap_periods, 1);
  const int swept = spec.azimuths.empty() ? K : int(spec.azimuths.size());
  std::vector<SweepDirection> dirs(static_cast<std::size_t>(swept));
  for (int k = 0; k < swept; ++k) dirs[std::size_t(k)] = plan_direction(field, spec, k);
  std::atomic<std::uint64_t> samples{0}, iterations{0}, work[3] = {0, 0, 0};
  const std::vector<Vec3f> normals =
      texel_receivers && lsao_holds_normals(field) ? compute_normals(field) : std::vector<Vec3f>();
  sweep_lines(
      field, spec, rc,
      [&] {
        LsaoWorker w;
        w.options = &options;
        w.field = &field;
        w.normals = &normals;
        w.samples = &samples;
        w.iterations = &iterations;
        w.work = work;
        w.bent = want_bent;
        return w;
      },
      [&](int k, int i, int j, const TexelTaps& t) {
        // The texel lies f above the line of tap lo (its channel 1) and 1 - f below the line of tap hi
        // (its channel 0); f = 0: it is lo's sample itself. Clamp borders keep one tap (texel_taps).
        const SweepDirection& d = dirs[std::size_t(k)];
        const double g = double(d.x_major ? j : i) - double(d.x_major ? i : j) * d.slope;
        const double f = g - std::floor(g);
        // ch0: the channel of the sample's lower texel, ch1: of its upper texel.
        auto blend = [&](int ch0, int ch1) -> double {
          if (f == 0) return t.lo[ch0];
          if (t.lo == t.hi) return t.hi[ch0];
          if (t.w_hi == 0) return t.lo[ch1];
          return (1 - f) * t.lo[ch1] + f * t.hi[ch0];
        };
        // Float sums, one rounding per direction (k ascending for every texel: deterministic); the whole
        // bake adds them by the farm's blocks (FloatBlocks), a block alone from zero.
        const std::size_t idx = field.index(i, j);
        const double value[4] = {blend(0, 1), want_bent ? blend(2, 4) * d.dx : 0.0,
                                 want_bent ? blend(2, 4) * d.dy : 0.0, want_bent ? blend(3, 5) : 0.0};
        float* out[4] = {sum + idx, want_bent ? bent_xyz + 3 * idx : nullptr,
                         want_bent ? bent_xyz + 3 * idx + 1 : nullptr,
                         want_bent ? bent_xyz + 3 * idx + 2 : nullptr};
        for (int c = 0; c < (want_bent ? 4 : 1); ++c) {
          if (block >= 0)
            *out[c] = float(double(*out[c]) + value[c]);
          else
            blocks.add(k0 + k, value[c], *out[c],
                       partial.empty() ? *out[c] : partial[(want_bent ? 4 : 1) * idx + c]);
        }
      });
  if (stats) {
    stats->samples = samples;
    stats->iterations = iterations;
    stats->queries = work[0], stats->walked = work[1], stats->bands = work[2];
  }
}

}  // namespace

void lsao_sums(const HeightField& field, const LsaoOptions& options, const RunControl& rc, LsaoStats* stats,
               float* sum, float* bent_xyz) {
  lsao_sweep(field, options, rc, stats, -1, sum, bent_xyz);
}

void lsao_block_sums(const HeightField& field, const LsaoOptions& options, int block, const RunControl& rc,
                     float* sum, float* bent_xyz) {
  lsao_sweep(field, options, rc, nullptr, block, sum, bent_xyz);
}

bool lsao_holds_normals(const FieldShape& field) {
  return double(field.width) * double(field.height) <= 8192.0 * 8192.0;
}

std::vector<double> lsao_mean_occlusion(const HeightField& field, const LsaoOptions& options,
                                        const RunControl& rc, LsaoStats* stats) {
  std::vector<float> sum(field.texel_count());
  lsao_sums(field, options, rc, stats, sum.data(), nullptr);
  const double inv = 1.0 / std::max(options.directions, 1);
  std::vector<double> mean(sum.size());
  for (std::size_t t = 0; t < sum.size(); ++t) mean[t] = double(sum[t]) * inv;
  return mean;
}

void lsao_layers(const HeightField& field, const LsaoOptions& options, const RunControl& rc, LsaoStats* stats,
                 float* light, float* bent_xyz) {
  lsao_sums(field, options, rc, stats, light, bent_xyz);
  lsao_finish(field, options, light, bent_xyz);
}

void lsao_finish(const HeightField& field, const LsaoOptions& options, float* light, float* bent_xyz) {
  const double inv = 1.0 / std::max(options.directions, 1);
  const std::size_t N = field.texel_count();
  for (std::size_t t = 0; t < N; ++t) light[t] = float(1.0 - std::clamp(double(light[t]) * inv, 0.0, 1.0));
  if (bent_xyz)
    for (std::size_t t = 0; t < N; ++t) {
      float* b = bent_xyz + 3 * t;
      const Vec3 v{b[0], b[1], b[2]};
      const Vec3f n = length(v) > 1e-12 ? Vec3f::from(normalize(v))
                                        : normal_at(field, int(t % field.width), int(t / field.width));
      b[0] = n.x, b[1] = n.y, b[2] = n.z;
    }
}

std::vector<float> lsao_obscurance(const HeightField& field, const LsaoOptions& options, const RunControl& rc,
                                   LsaoStats* stats, std::vector<Vec3f>* bent_normal) {
  std::vector<float> out(field.texel_count()), bent(bent_normal ? 3 * field.texel_count() : 0);
  lsao_layers(field, options, rc, stats, out.data(), bent_normal ? bent.data() : nullptr);
  if (bent_normal) {
    bent_normal->resize(field.texel_count());
    for (std::size_t t = 0; t < bent_normal->size(); ++t)
      (*bent_normal)[t] = {bent[3 * t], bent[3 * t + 1], bent[3 * t + 2]};
  }
  return out;
}

LsaoOptions read_lsao_options(Params& in) {
  LsaoOptions o;
  o.occlusion.rho = read_falloff(in);
  o.occlusion.weighting = read_weighting(in, true) == Weighting::uniform ? ObscuranceWeighting::uniform
                                                                         : ObscuranceWeighting::cosine;
  // "normal" (default): each texel's own tangent, the visible chain's bands; a number: P3's fixed tangent sin
  // t.
  const std::optional<double> tangent =
      in.has("tangent")
          ? in.word_or_number("tangent", "normal", -1.0, 0.0,
                              "must be \"normal\" or a number in [-1, 0] (sin of P3's fixed tangent)")
          : std::nullopt;
  if (!tangent) {
    o.tangent = LsaoTangent::receiver;
    in.resolve("tangent", "normal");
  } else {
    o.tangent = LsaoTangent::fixed;
    o.occlusion.sin_t = *tangent;
    in.resolve("tangent", o.occlusion.sin_t);
  }
  // The receiver tangent's surface: the triangulated one by default (the crossings between the lines'
  // samples, segments, and a near field marched from each texel); "bilinear": the line samples alone.
  for (const char* key : {"surface", "near_radius"})
    if (in.has(key) && o.tangent != LsaoTangent::receiver) in.fail(key, "applies only to tangent \"normal\"");
  if (o.tangent == LsaoTangent::receiver) {
    const bool triangles = in.choice("surface", "triangles", {"bilinear", "triangles"}) == "triangles";
    o.surface = triangles ? LsaoSurface::triangles : LsaoSurface::bilinear;
    o.near_radius = in.number("near_radius", triangles ? kLsaoNearRadius : 0.0, 0, 64);
  }
  o.directions = in.integer("directions", 16, 1, 4096);
  in.layers({"obscurance", "bent_normal"}, {"obscurance", "bent_normal"});
  return o;
}

LayerSet bake_lsao(const Scene& scene, const MethodConfig& config, const RunControl& rc) {
  const LsaoOptions& o = config.get<LsaoOptions>();
  const std::vector<std::string>& layers = config.layers;
  // The sums are the layers: accumulated in float and finished in place, handed on without a copy.
  std::vector<float> light(scene.field.texel_count());
  std::vector<float> bent(wants(layers, "bent_normal") ? 3 * scene.field.texel_count() : 0);
  lsao_layers(scene.field, o, rc, nullptr, light.data(), bent.empty() ? nullptr : bent.data());
  return obscurance_layers_xyz(scene.field.width, scene.field.height, layers, std::move(light),
                               std::move(bent));
}

namespace {

// Farm blocks: "sum" and, with bent_normal, "bent" (lsao_block_sums; merged by float addition).
LayerSet lsao_bake_block(const Scene& scene, const MethodConfig& config, int block, const RunControl& rc) {
  const LsaoOptions& o = config.get<LsaoOptions>();
  const std::vector<std::string>& layers = config.layers;
  BlockSums out = block_sum_layers(scene.field.width, scene.field.height, wants(layers, "bent_normal"));
  lsao_block_sums(scene.field, o, block, rc, out.sum, out.bent);
  return std::move(out.set);
}

LayerSet lsao_finish_blocks(const Scene& scene, const MethodConfig& config, LayerSet&& sums,
                            const RunControl&) {
  const LsaoOptions& o = config.get<LsaoOptions>();
  const std::vector<std::string>& layers = config.layers;
  std::vector<float> light, bent;
  take_block_sums(std::move(sums), wants(layers, "bent_normal"), &light, &bent);
  lsao_finish(scene.field, o, light.data(), bent.empty() ? nullptr : bent.data());
  return obscurance_layers_xyz(scene.field.width, scene.field.height, layers, std::move(light),
                               std::move(bent));
}

}  // namespace

MethodInfo lsao_method() {
  MethodInfo m;
  m.name = "lsao";
  m.reads_normals = false;  // its own, only for texel receivers
  m.reads_albedo = false;
  m.summary =
      "line-sweep ambient obscurance (Timonen 2013): one hull of occluders per sweep line and direction";
  m.read = [](Params& in, const MethodContext&) {
    const LsaoOptions o = read_lsao_options(in);
    MethodConfig config = method_config(o, o.directions);
    config.obscurance = written_falloff(in, o.occlusion.rho);
    config.cosine_weighted = o.occlusion.weighting == ObscuranceWeighting::cosine;
    return config;
  };
  m.bake = bake_lsao;
  // The sums are its layers (float, finished in place; the bent normals interleaved): beyond them the
  // obscurance's 4 bytes a texel when the job asks for bent_normal alone, the normals (12) up to 8192^2
  // texels (lsao_holds_normals), and the sweep's line buffers
  // (bounded by SweepSpec::buffers.max_bytes; sweep_buffer_bytes of lsao's spec).
  m.memory_knob = "its layers (bent_normal: 12 bytes a texel)";
  m.working_bytes = [](const MethodConfig& config, const MethodContext& c) {
    const std::vector<std::string>& layers = config.layers;
    const bool bent = wants(layers, "bent_normal");
    const double texels = double(c.field.width) * double(c.field.height);
    SweepSpec spec;
    spec.directions = std::max(1, config.get<LsaoOptions>().directions);
    spec.channels = bent ? 6 : 2;
    HeightField field;  // the sweep's plan needs only the shape
    static_cast<FieldShape&>(field) = c.field;
    // The farm's block partial sums (FloatBlocks) when a block holds more than one direction.
    const double partial = FloatBlocks(spec.directions).needs_partial() ? (bent ? 16.0 : 4.0) : 0.0;
    return ((wants(layers, "obscurance") ? 0.0 : 4.0) + (lsao_holds_normals(c.field) ? 12.0 : 0.0) +
            partial) *
               texels +
           double(sweep_buffer_bytes(field, spec));
  };
  m.division = WorkDivision::directions;
  m.division_note = "partial sums over disjoint direction sets (each direction's sweep is independent)";
  m.bake_block = lsao_bake_block;
  m.finish_blocks = lsao_finish_blocks;
  return m;
}

}  // namespace hfbake
