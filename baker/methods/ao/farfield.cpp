#include "methods/ao/farfield.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <type_traits>

#include "core/azimuth.hpp"
#include "core/direction_blocks.hpp"
#include "methods/ao/bake_ao.hpp"
#include "methods/ao/farfield_slab_table.hpp"
#include "methods/ao/obscurance_params.hpp"
#include "methods/ao/slice_integral.hpp"
#include "methods/ao/triangle_profile.hpp"

namespace hfbake {
namespace {

constexpr float kNone = -std::numeric_limits<float>::infinity();

// One direction's lines and interval pyramid with prefix sums across lines.
struct DirectionScan {
  double dx = 1, dy = 0;  // D (occluders lie towards D)
  double s0 = 0, t0 = 0;  // along / across coordinate (texels) of sample 0 of line 0
  int lines = 0, samples = 0, b0 = 8, levels = 1;
  std::vector<int> level_count;       // intervals per level
  std::vector<std::size_t> level_at;  // offset of level n's first interval column
  std::size_t columns = 0;            // total intervals over all levels
  // Prefix sums over lines: entry (l, c) = sum over lines < l, (lines + 1) x columns.
  std::vector<double> sum0, sum1;
  std::vector<int> count;
};

bool inside(const HeightField& f, double x, double y) {
  constexpr double eps = 1e-7;
  return x >= -eps && y >= -eps && x <= f.width - 1 + eps && y <= f.height - 1 + eps;
}

void plan(const HeightField& f, const FarfieldOptions& o, int k, DirectionScan& d) {
  const double phi = azimuth(k, o.directions);
  d.dx = std::cos(phi), d.dy = std::sin(phi);
  // Snap the axis and diagonal directions exactly.
  for (double* c : {&d.dx, &d.dy})
    if (std::fabs(*c) < 1e-12) *c = 0;
  double smin = 1e300, smax = -1e300, tmin = 1e300, tmax = -1e300;
  for (int c = 0; c < 4; ++c) {
    const double x = (c & 1) ? f.width - 1 : 0, y = (c & 2) ? f.height - 1 : 0;
    const double s = x * d.dx + y * d.dy, t = -x * d.dy + y * d.dx;
    smin = std::min(smin, s), smax = std::max(smax, s), tmin = std::min(tmin, t), tmax = std::max(tmax, t);
  }
  double s_extra = 0, t_extra = 0;
  if (f.wrap == Wrap::repeat) {
    // Tiled terrain in front of every receiver, out to where rho is negligible (at most one period).
    const double support = o.rho.support(1e-5) / f.texel_size;
    s_extra = std::ceil(std::min(support, double(std::max(f.width, f.height))));
    // Sideways as far as the sector reaches within the support (no farther than the support itself: with
    // K <= 3 the half-sector is 60-180 degrees and its tangent grows without bound; K = 2 asked 1e16).
    if (o.sector_average) t_extra = std::ceil(std::min(s_extra * std::tan(kPi / o.directions), s_extra)) + 1;
  }
  d.b0 = o.interval;
  // The traversal reads an interval of level n only at a distance below the falloff's support with
  // b0 2^n <= growth x that distance: levels beyond that are never read, and are not built.
  const double longest = o.growth * o.rho.support(1e-5) / f.texel_size;
  d.s0 = std::floor(smin);
  d.t0 = std::floor(tmin) - t_extra;
  d.samples = int(std::ceil(smax) - d.s0 + 1 + s_extra);
  d.lines = int(std::ceil(tmax) + t_extra - d.t0 + 1);
  d.level_count.clear();
  d.level_at.clear();
  d.columns = 0;
  for (int n = (d.samples + d.b0 - 1) / d.b0, len = d.b0;; n = (n + 1) / 2, len *= 2) {
    d.level_at.push_back(d.columns);
    d.level_count.push_back(n);
    d.columns += std::size_t(n);
    if (n == 1 || !(2.0 * len <= longest * (1 + 1e-9))) break;
  }
  d.levels = int(d.level_count.size());
}

float height_at(const HeightField& f, double x, double y) {
  if (f.wrap == Wrap::clamp && !inside(f, x, y)) return kNone;
  return f.bilinear(x, y);
}

// Lines whose raw maxima are held at once while the prefix sums are built (about 16 MiB of them).
int scan_chunk_lines(const DirectionScan& d) {
  return int(std::clamp<std::size_t>((std::size_t(16) << 20) / (8 * std::max<std::size_t>(d.columns, 1)), 16,
                                     std::size_t(std::max(d.lines, 16))));
}

// Bytes scan() holds for d: the prefix sums (two doubles and a count per line and interval column) and one
// chunk of raw maxima.
std::size_t scan_bytes(const DirectionScan& d) {
  return std::size_t(d.lines + 1) * d.columns * (2 * sizeof(double) + sizeof(int)) +
         std::size_t(scan_chunk_lines(d)) * d.columns * 2 * sizeof(float);
}

// Scan, pyramid and prefix sums of one direction. The raw maxima of a chunk of lines at a time (in
// parallel), then their running sums per column (in parallel over columns, lines in order): the same sums
// as over all lines at once.
void scan(const HeightField& f, DirectionScan& d, const RunControl& rc) {
  const std::size_t cols = d.columns;
  const int chunk = scan_chunk_lines(d);
  std::vector<float> raw0(std::size_t(chunk) * cols), raw1(std::size_t(chunk) * cols);
  // Freed first: a larger direction's sums never coexist with the previous one's.
  std::vector<double>().swap(d.sum0);
  std::vector<double>().swap(d.sum1);
  std::vector<int>().swap(d.count);
  d.sum0.assign(std::size_t(d.lines + 1) * cols, 0.0);
  d.sum1.assign(std::size_t(d.lines + 1) * cols, 0.0);
  d.count.assign(std::size_t(d.lines + 1) * cols, 0);
  const double ts = f.texel_size;
  for (int l0 = 0; l0 < d.lines; l0 += chunk) {
    const int l1 = std::min(d.lines, l0 + chunk);
    std::fill(raw0.begin(), raw0.end(), kNone);
    std::fill(raw1.begin(), raw1.end(), kNone);
    tbb::parallel_for(tbb::blocked_range<int>(l0, l1, 8), [&](const tbb::blocked_range<int>& r) {
      rc.check();
      for (int l = r.begin(); l < r.end(); ++l) {
        float* m0 = &raw0[std::size_t(l - l0) * cols];
        float* m1 = &raw1[std::size_t(l - l0) * cols];
        const double t = d.t0 + l;
        for (int m = 0; m < d.samples; ++m) {
          const double s = d.s0 + m;
          const float z = height_at(f, s * d.dx - t * d.dy, s * d.dy + t * d.dx);
          if (z == kNone) continue;
          const int j = m / d.b0;
          m0[j] = std::max(m0[j], z);
          m1[j] = std::max(m1[j], float(double(z) - m * ts));
        }
        for (int n = 1; n < d.levels; ++n) {
          const std::size_t child = d.level_at[n - 1], parent = d.level_at[n];
          const int nc = d.level_count[n - 1];
          for (int j = 0; j < d.level_count[n]; ++j) {
            const std::size_t a = child + 2 * j, b = 2 * j + 1 < nc ? a + 1 : a;
            m0[parent + j] = std::max(m0[a], m0[b]);
            m1[parent + j] = std::max(m1[a], m1[b]);
          }
        }
      }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cols, 64),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t c = r.begin(); c < r.end(); ++c) {
                          const std::size_t o0 = std::size_t(l0) * cols + c;
                          double a = d.sum0[o0], b = d.sum1[o0];
                          int n = d.count[o0];
                          for (int l = l0; l < l1; ++l) {
                            const float v0 = raw0[std::size_t(l - l0) * cols + c],
                                        v1 = raw1[std::size_t(l - l0) * cols + c];
                            if (v0 != kNone) a += v0, b += v1, ++n;
                            const std::size_t o = std::size_t(l + 1) * cols + c;
                            d.sum0[o] = a, d.sum1[o] = b, d.count[o] = n;
                          }
                        }
                      });
  }
}

// Horizon and accumulated occluded band of one (half) sector.
struct SectorState {
  double horizon = -kHalfPi;  // elevation of the highest slab so far
  double slope = -INFINITY;   // its tan: the cull test needs no atan2 (x > 0)
  double occluded = 0;
  SliceVec dir;  // bent normal: minus the rho- and cosine-weighted direction integral of the occluded bands
};

// frame: the slice frame when the bent normal is wanted, else null.
inline void add_slab(const SlabTable& table, SectorState& st, double x, double dz, double nt, double nz,
                     double tangent, const Falloff& rho, const SliceFrame* frame) {
  if (dz <= st.slope * x) return;  // not above the horizon so far: hidden
  const double e = std::atan2(dz, x);
  st.slope = dz / x;
  if (e <= st.horizon) return;
  st.occluded += table.band(st.horizon, e, x, nt, nz, tangent);
  if (frame) {
    const SliceVec b = band_direction(rho, *frame, st.horizon, e, x);
    st.dir.h -= b.h, st.dir.v -= b.v;
  }
  st.horizon = e;
}

}  // namespace

namespace {

// The occluded measure sum_k sum_slabs band per texel, summed in Acc (float for the layers: one rounding per
// direction, k ascending; double for the few texels of farfield_occlusion_at) into occluded[texel] (zeroed
// first); only the texels in `only` when it is not null, then into occluded[item]. bent_xyz (optional, whole
// field only): per texel, the sum over directions of the cosine-weighted open direction (unnormalised),
// [3 * texel + c].
template <class Acc>
void farfield_occluded(const HeightField& field, const std::vector<Vec3f>& normals,
                       const FarfieldOptions& options, const RunControl& rc,
                       const std::vector<std::size_t>* only, FarfieldStats* stats, Acc* occluded,
                       float* bent_xyz = nullptr, int block = -1) {
  FarfieldOptions o = options;
  o.directions = std::max(o.directions, 1);
  o.interval = std::max(o.interval, 1);
  if (o.near_field < 0) o.near_field = 1.5 * o.interval;
  if (!o.sector_average) o.split = false;
  const int W = field.width, H = field.height, K = o.directions;
  const double ts = field.texel_size;
  const bool bent = bent_xyz != nullptr;
  std::fill_n(occluded, only ? only->size() : field.texel_count(), Acc(0));
  if (bent) std::fill_n(bent_xyz, 3 * field.texel_count(), 0.0f);
  const SlabTable table(o.rho);
  const double support = o.rho.support(1e-5) / ts;  // texels beyond which rho < 1e-5
  std::atomic<std::uint64_t> near_count{0}, far_count{0};
  // The farm's direction blocks (core/direction_blocks.hpp): the float layers sum every direction by blocks
  // (FloatBlocks), or block `block` alone from zero; the double sums of farfield_occlusion_at in one run.
  constexpr bool by_blocks = std::is_same_v<Acc, float>;
  const FloatBlocks blocks(K);
  const int k0 = block >= 0 ? direction_block_begin(block, K) : 0;
  const int k1 = block >= 0 ? direction_block_begin(block + 1, K) : K;
  const int C = bent ? 4 : 1;
  std::vector<float> partial(by_blocks && block < 0 && blocks.needs_partial() ? C * field.texel_count() : 0);
  auto add = [&](int k, std::size_t idx, double v, Acc& total, int c) {
    if constexpr (by_blocks) {
      if (block >= 0)
        total = float(double(total) + v);
      else
        blocks.add(k, v, total, partial.empty() ? total : partial[C * idx + std::size_t(c)]);
    } else {
      total = Acc(double(total) + v);
    }
  };
  DirectionScan d;
  for (int k = k0; k < k1; ++k) {
    plan(field, o, k, d);
    scan(field, d, rc);
    const double sector_tan = std::tan(kPi / K);
    const std::size_t cols = d.columns;
    const std::size_t items = only ? only->size() : std::size_t(H);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, items, only ? 1 : 4),
        [&](const tbb::blocked_range<std::size_t>& r) {
          rc.check();
          std::uint64_t nn = 0, nf = 0;
          for (std::size_t item = r.begin(); item < r.end(); ++item) {
            const int i_begin = only ? int((*only)[item] % W) : 0, i_end = only ? i_begin + 1 : W;
            const int j = only ? int((*only)[item] / W) : int(item);
            for (int i = i_begin; i < i_end; ++i) {
              const std::size_t idx = field.index(i, j);
              const Vec3f n = normals.empty() ? normal_at(field, i, j) : normals[idx];
              const double nt = n.x * d.dx + n.y * d.dy, nz = n.z;
              const double tangent = std::atan2(-nt, nz);
              const SliceFrame frame_value = slice_frame(nt, nz);
              const SliceFrame* frame = bent ? &frame_value : nullptr;
              const double zr = field.z[idx];
              const double sr = i * d.dx + j * d.dy - d.s0;  // receiver along / across, texels from sample 0
              const double tr = -i * d.dy + j * d.dx - d.t0;
              // Near field: exact march from the receiver, every sample its own slab.
              SectorState near;
              // The first aligned interval at least near_field texels away (the exact march stops at the
              // scan's end and where rho has vanished, like the far field).
              const double near_end = std::min({sr + o.near_field, double(d.samples), sr + support + 1});
              const int m_far = int(std::ceil(near_end / d.b0)) * d.b0;
              bool open_end = false;  // clamp: the ray left the field
              if (o.triangles) {
                // Every vertex of the triangulated surface's profile, each band hit on its segment.
                const double want = m_far - sr - 1e-9, t_end = profile_end(field, i, j, d.dx, d.dy, want);
                open_end = t_end < want;
                SliceVec prev{0, 0};
                if (t_end > 1e-9)
                  triangle_profile(field, i, j, d.dx, d.dy, t_end, [&](double t, double z) {
                    const SliceVec p{t * ts, z - zr};
                    ++nn;
                    if (p.v > near.slope * p.h) {
                      const double e = std::atan2(p.v, p.h);
                      near.slope = p.v / p.h;
                      if (e > near.horizon) {
                        near.occluded += segment_band_occlusion(o.rho, Weighting::cosine, frame_value,
                                                                near.horizon, e, prev, p);
                        if (frame) {
                          const SliceVec b =
                              segment_band_direction(o.rho, frame_value, near.horizon, e, prev, p);
                          near.dir.h -= b.h, near.dir.v -= b.v;
                        }
                        near.horizon = e;
                      }
                    }
                    prev = p;
                  });
              } else {
                for (int q = 1; sr + q < m_far; ++q) {
                  const double x = i + q * d.dx, y = j + q * d.dy;
                  if (field.wrap == Wrap::clamp && !inside(field, x, y)) {
                    open_end = true;
                    break;
                  }
                  add_slab(table, near, q * ts, field.bilinear(x, y) - zr, nt, nz, tangent, o.rho, frame);
                  ++nn;
                }
              }
              const int halves = o.split ? 2 : 1;
              double sum = 0;
              SliceVec dir_sum;
              for (int h = 0; h < halves && !open_end; ++h) {
                SectorState st = near;
                for (int m = m_far; m < d.samples;) {
                  const double dist = m - sr;  // texels from the receiver to the interval's start
                  if (dist >= support) break;
                  int n = 0;
                  while (n + 1 < d.levels && m % (d.b0 << (n + 1)) == 0 &&
                         double(d.b0 << (n + 1)) <= o.growth * dist)
                    ++n;
                  const int len = d.b0 << n, jj = m / len;
                  if (jj >= d.level_count[n]) break;
                  const std::size_t c = d.level_at[n] + std::size_t(jj);
                  int la, lb;
                  if (!o.sector_average) {
                    la = lb = int(std::lround(tr));
                  } else {
                    const double w = (dist + 0.5 * len) * sector_tan;
                    const double lo = o.split ? (h == 0 ? tr - w : tr) : tr - w;
                    const double hi = o.split ? (h == 0 ? tr : tr + w) : tr + w;
                    la = int(std::ceil(lo)), lb = int(std::floor(hi));
                    if (la > lb) la = lb = int(std::lround(0.5 * (lo + hi)));
                  }
                  la = std::max(la, 0), lb = std::min(lb, d.lines - 1);
                  m += len;
                  if (la > lb) continue;
                  const std::size_t a = std::size_t(la) * cols + c, b = std::size_t(lb + 1) * cols + c;
                  const int cnt = d.count[b] - d.count[a];
                  if (cnt == 0) continue;
                  const double m0 = (d.sum0[b] - d.sum0[a]) / cnt, m1 = (d.sum1[b] - d.sum1[a]) / cnt;
                  double x = (m0 - m1) - sr * ts;  // the virtual point (s*, z*) = (m0 - m1, m0)
                  ++nf;
                  if (x <= 0) continue;
                  if (lb > la) {
                    // Lines beside the receiver's own line meet an occluder at along-distance x but radial
                    // distance sqrt(x^2 + dt^2): use the sector's mean square offset (a circle stays a
                    // circle).
                    const double u0 = la - tr, nl = lb - la + 1;
                    const double mean_sq =
                        (nl * u0 * u0 + u0 * (nl - 1) * nl + (nl - 1) * nl * (2 * nl - 1) / 6) / nl;
                    x = std::sqrt(x * x + mean_sq * ts * ts);
                  }
                  add_slab(table, st, x, m0 - zr, nt, nz, tangent, o.rho, frame);
                }
                sum += st.occluded;
                dir_sum.h += st.dir.h, dir_sum.v += st.dir.v;
              }
              add(k, idx, open_end ? near.occluded : sum / halves, occluded[only ? item : idx], 0);
              if constexpr (by_blocks)
                if (bent) {
                  const SliceVec open = open_direction(frame_value, tangent, kHalfPi);
                  const SliceVec occ = open_end ? near.dir : SliceVec{dir_sum.h / halves, dir_sum.v / halves};
                  const double h = open.h + occ.h, v = open.v + occ.v;
                  float* b = bent_xyz + 3 * idx;
                  add(k, idx, h * d.dx, b[0], 1), add(k, idx, h * d.dy, b[1], 2), add(k, idx, v, b[2], 3);
                }
            }
          }
          near_count += nn;
          far_count += nf;
        });
    rc.report(double(k + 1 - k0) / (k1 - k0));
  }
  if (stats) {
    stats->near_samples = near_count;
    stats->virtual_points = far_count;
    stats->texel_directions = std::uint64_t(only ? only->size() : field.texel_count()) * (k1 - k0);
  }
}

}  // namespace

void farfield_layers(const HeightField& field, const std::vector<Vec3f>& normals,
                     const FarfieldOptions& options, const RunControl& rc, FarfieldStats* stats, float* light,
                     float* bent_xyz) {
  farfield_occluded(field, normals, options, rc, nullptr, stats, light, bent_xyz);
  farfield_finish(field, normals, options, light, bent_xyz);
}

void farfield_block_sums(const HeightField& field, const FarfieldOptions& options, int block,
                         const RunControl& rc, float* occluded, float* bent_xyz) {
  farfield_occluded(field, std::vector<Vec3f>(), options, rc, nullptr, nullptr, occluded, bent_xyz, block);
}

void farfield_finish(const HeightField& field, const std::vector<Vec3f>& normals,
                     const FarfieldOptions& options, float* light, float* bent_xyz) {
  const double scale = 2.0 / std::max(options.directions, 1);
  const std::size_t N = field.texel_count();
  for (std::size_t t = 0; t < N; ++t) light[t] = float(std::clamp(1.0 - double(light[t]) * scale, 0.0, 1.0));
  if (bent_xyz)
    for (std::size_t t = 0; t < N; ++t) {
      float* b = bent_xyz + 3 * t;
      const Vec3 v{b[0], b[1], b[2]};
      const Vec3f n = length(v) > 1e-12 ? Vec3f::from(normalize(v))
                      : normals.empty() ? normal_at(field, int(t % field.width), int(t / field.width))
                                        : normals[t];
      b[0] = n.x, b[1] = n.y, b[2] = n.z;
    }
}

std::vector<float> farfield_obscurance(const HeightField& field, const std::vector<Vec3f>& normals,
                                       const FarfieldOptions& options, const RunControl& rc,
                                       FarfieldStats* stats, std::vector<Vec3f>* bent_normal) {
  std::vector<float> out(field.texel_count()), bent(bent_normal ? 3 * field.texel_count() : 0);
  farfield_layers(field, normals, options, rc, stats, out.data(), bent_normal ? bent.data() : nullptr);
  if (bent_normal) {
    bent_normal->resize(field.texel_count());
    for (std::size_t t = 0; t < bent_normal->size(); ++t)
      (*bent_normal)[t] = {bent[3 * t], bent[3 * t + 1], bent[3 * t + 2]};
  }
  return out;
}

std::vector<double> farfield_occlusion_at(const HeightField& field, const std::vector<Vec3f>& normals,
                                          const FarfieldOptions& options,
                                          const std::vector<std::size_t>& texels, FarfieldStats* stats) {
  std::vector<double> out(texels.size());
  farfield_occluded(field, normals, options, RunControl{}, &texels, stats, out.data());
  const double scale = 2.0 / std::max(options.directions, 1);
  for (double& v : out) v *= scale;
  return out;
}

double farfield_working_bytes(const FieldShape& shape, const FarfieldOptions& options) {
  FarfieldOptions o = options;
  o.directions = std::max(o.directions, 1);
  o.interval = std::max(o.interval, 1);
  HeightField field;  // plan() needs only the shape
  static_cast<FieldShape&>(field) = shape;
  std::size_t peak = 0;
  DirectionScan d;
  for (int k = 0; k < o.directions; ++k) {
    plan(field, o, k, d);
    peak = std::max(peak, scan_bytes(d));
  }
  return double(peak);
}

FarfieldOptions read_farfield_options(Params& in) {
  FarfieldOptions o;
  o.rho = read_falloff(in);
  read_weighting(in, false);
  o.directions = in.integer("directions", 16, 1, 4096);
  o.interval = in.integer("interval", 8, 1, 256);
  o.near_field = in.number("near_field", -1, 0, 1e6);
  if (o.near_field < 0) {  // the default, 1.5 intervals (FarfieldOptions), recorded as the bake uses it
    o.near_field = 1.5 * o.interval;
    in.resolve("near_field", o.near_field);
  }
  o.sector_average = in.boolean("sector_average", true);
  o.split = in.boolean("split", true);
  o.growth = in.number("growth", 1.0, 0.125, 8.0);
  o.triangles = in.choice("surface", "triangles", {"bilinear", "triangles"}) == "triangles";
  in.layers({"obscurance", "bent_normal"}, {"obscurance", "bent_normal"});
  return o;
}

LayerSet bake_farfield(const Scene& scene, const MethodConfig& config, const RunControl& rc) {
  const FarfieldOptions& o = config.get<FarfieldOptions>();
  const std::vector<std::string>& layers = config.layers;
  // The sums are the layers: accumulated in float and finished in place, handed on without a copy.
  std::vector<float> light(scene.field.texel_count());
  std::vector<float> bent(wants(layers, "bent_normal") ? 3 * scene.field.texel_count() : 0);
  farfield_layers(scene.field, scene.normals, o, rc, nullptr, light.data(),
                  bent.empty() ? nullptr : bent.data());
  return obscurance_layers_xyz(scene.field.width, scene.field.height, layers, std::move(light),
                               std::move(bent));
}

namespace {

// Farm blocks: "sum" and, with bent_normal, "bent" (farfield_block_sums; merged by float addition).
LayerSet farfield_bake_block(const Scene& scene, const MethodConfig& config, int block,
                             const RunControl& rc) {
  const FarfieldOptions& o = config.get<FarfieldOptions>();
  const std::vector<std::string>& layers = config.layers;
  BlockSums out = block_sum_layers(scene.field.width, scene.field.height, wants(layers, "bent_normal"));
  farfield_block_sums(scene.field, o, block, rc, out.sum, out.bent);
  return std::move(out.set);
}

LayerSet farfield_finish_blocks(const Scene& scene, const MethodConfig& config, LayerSet&& sums,
                                const RunControl&) {
  const FarfieldOptions& o = config.get<FarfieldOptions>();
  const std::vector<std::string>& layers = config.layers;
  std::vector<float> light, bent;
  take_block_sums(std::move(sums), wants(layers, "bent_normal"), &light, &bent);
  farfield_finish(scene.field, scene.normals, o, light.data(), bent.empty() ? nullptr : bent.data());
  return obscurance_layers_xyz(scene.field.width, scene.field.height, layers, std::move(light),
                               std::move(bent));
}

}  // namespace

MethodInfo farfield_method() {
  MethodInfo m;
  m.name = "farfield";
  m.reads_normals = false;  // normal_at per texel
  m.reads_albedo = false;
  m.summary =
      "far-field ambient obscurance (Timonen 2013): an exact near field, prefiltered far-field slabs beyond "
      "it";
  m.read = [](Params& in, const MethodContext&) {
    const FarfieldOptions o = read_farfield_options(in);
    MethodConfig config = method_config(o, o.directions);
    config.obscurance = written_falloff(in, o.rho);
    return config;
  };
  m.bake = bake_farfield;
  // The sums are its layers (float, finished in place; the bent normals interleaved): beyond them only the
  // obscurance's 4 bytes a texel when the job asks for bent_normal alone, and the largest direction's scan
  // (farfield_working_bytes: its prefix sums over lines of the interval pyramid).
  m.memory_knob = "its layers (bent_normal: 12 bytes a texel) and its radius (the far field's scan)";
  m.working_bytes = [](const MethodConfig& config, const MethodContext& c) {
    const FarfieldOptions& o = config.get<FarfieldOptions>();
    const std::vector<std::string>& layers = config.layers;
    // The farm's block partial sums (FloatBlocks) when a block holds more than one direction.
    const double partial =
        FloatBlocks(o.directions).needs_partial() ? (wants(layers, "bent_normal") ? 16.0 : 4.0) : 0.0;
    return ((wants(layers, "obscurance") ? 0.0 : 4.0) + partial) * double(c.field.width) *
               double(c.field.height) +
           farfield_working_bytes(c.field, o);
  };
  m.division = WorkDivision::directions;
  m.division_note = "partial sums over disjoint direction sets";
  m.bake_block = farfield_bake_block;
  m.finish_blocks = farfield_finish_blocks;
  return m;
}

}  // namespace hfbake
