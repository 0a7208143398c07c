// P1's horizons by a lane search: every texel's exact horizon over its own ray on the reference's
// triangulated surface (two triangles per quad, split along (i+1, j)-(i, j+1)), kLanes (32) texels at a
// time.
//
// Translation invariance: the ray from any texel centre towards phi crosses the columns, rows and
// diagonals of the triangulation at the same offsets from that texel (near_field_stencil lists them, with
// their corner texels and weights), so texels (u, v), ..., (u, v + 31) adjacent on the minor axis (the axis
// the direction moves less along) read their crossings from 32 adjacent texels each. A field copy with the
// minor axis contiguous (LaneLayout) turns every crossing into two 32-lane loads, a lerp and a slope: the
// group's rays are searched in lockstep, the steepest crossing of each is the exact horizon.
//
// What makes it cheap is what is not evaluated. The rays are cut into blocks of 4 columns along the walk.
// A unit strip of intercepts (the lines v - g u in [k, k + 1)) holds every ray of one lane of a group, and
// per column the highest texel any crossing of such a ray can use (the texels within [e_lo, e_hi] of the
// rays' lines, LaneDirection; the maximum of one or two LaneLayout::window values): from those, per
// strip of kLanes lanes, the highest over each block, over 4, 16 and 64 blocks, and over all further
// columns, one value per lane (one load of the group's lanes). The texel's own block and the four after it
// are evaluated whole (close to the texel a bound seldom rules a block out); further on, a block is evaluated
// only when some lane's bound, seen from that lane at the block's nearest crossing, could be steeper than the
// lane's best slope (plus the tolerance): a bound is never below any crossing's slope as evaluated
// (LaneLayout's window), so skipping keeps the result exact, the largest of all its crossings' slopes bit for
// bit, and the walk stops when nothing further can beat any lane. The bounds are of the heights less a
// trend (the field's plane, LaneLayout, and the strip's residual slope along its rays, lane_kernel.inc): a
// slanted bound, which stays tight far along rays over terrain with a regional slope. The blocks of the
// previous group's casters (one column behind on the same strip, whose casters are most often this group's)
// are evaluated first, so the best slopes are high early and prune the most. With a tolerance tau > 0, a
// block or the rest is skipped unless it can beat the best slope by more than tau: every slope is within tau
// of (and never above) the exact one.
//
// A group is wide because most of its work is shared by its lanes (the strips' bounds, the tests, the loop),
// while a block is evaluated for all of them when any one needs it: on a 1024² fractal, groups of 32 lanes
// evaluate about 3.5 crossings a texel-direction, groups of 8 would evaluate about 9 (docs/performance.md).
//
// The arithmetic is the same per lane on every instruction set (adds, multiplies, maxima and compares, no
// fused multiply-add), and every instruction set groups the same 32 lanes, so the SSE2, AVX2 and AVX-512
// kernels (lane_kernel.inc) give the same bits.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/page_buffer.hpp"
#include "core/run_control.hpp"
#include "field/height_field.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake::p1 {

inline constexpr int kLanes = 32;
inline constexpr int kLanePad = 64;         // texels of padding on each side of the minor axis
inline constexpr float kOffField = -1e30f;  // the padding's height: never the steepest
inline constexpr int kLaneWindow = 3;       // minor-axis texels of LaneLayout::window's maxima

// The field with its minor axis contiguous: x_major (directions moving more along x) stores
// [x * stride + kLanePad + y], else [y * stride + kLanePad + x]; kLanePad texels of kOffField on both sides.
// The heights are held less an offset wherever every difference stays exact (build_rows): a search's
// slopes are differences of heights, the same either way.
// window[at] is the highest of z[at .. at + kLaneWindow - 1] (the same major index) less the field's
// least-squares plane there (raised by more than the roundings): a search's bounds are of the heights less a
// trend, which stays close to the slopes they bound far along a ray over terrain with a regional slope.
struct LaneLayout {
  bool x_major = true;
  int nmajor = 0, nminor = 0;
  std::ptrdiff_t stride = 0;
  std::size_t size = 0;  // floats in z and in window: nmajor * stride
  float zabs = 0;        // the largest |z| held (less the offset)
  // The field's least-squares plane: tilt0 + tilt_major * u + tilt_minor * v at major index u, minor index v
  // (heights per texel index); plane_abs its largest |value| on the field.
  double tilt0 = 0, tilt_major = 0, tilt_minor = 0;
  float plane_abs = 0;
  // On 2 MiB pages where the kernel gives them (core/page_buffer.hpp): a group's crossings read one
  // row of the layout per column, nmajor rows a stride apart.
  PageBuffer<float> z, window;
  std::size_t capacity = 0;  // floats z and window each hold (at least size)
  // The texels searched, major [recv_u0, recv_u1) and minor [recv_v0, recv_v1), and where their results
  // go: texel (i, j) of the layout's field at (j - out_j0) * out_width + i - out_i0. build: every texel, at
  // the field's own index; a repeat field's tiling (build_tiled) narrows them to the field inside it.
  int recv_u0 = 0, recv_u1 = 0, recv_v0 = 0, recv_v1 = 0;
  int out_i0 = 0, out_j0 = 0, out_width = 0;

  void build(const HeightField& f, bool x_major);
  // A repeat field's rays searched as a clamp field's: the layout of f's tiling (tiled_shape's, its heights
  // read from f as they are laid out, never held whole), whose texels of f are searched, at f's own index.
  void build_tiled(const HeightField& f, bool x_major, int periods);
  std::size_t bytes() const { return 2 * capacity * sizeof(float); }
};

// One crossing of the ray from a texel with the triangulation: height (1 - w) z[a] + w z[b] at the index
// offsets a, b (of the LaneLayout), seen at horizontal world distance d = 1 / inv_s and lowered by the
// Earth's curvature by drop d^2 (drop = c d, terrain/earth.hpp): its slope is (z - z0) inv_s - drop.
struct LaneCrossing {
  std::ptrdiff_t a, b;  // 64 bits: a large field's offsets exceed 2^31 (46341^2 texels)
  float w, inv_s, drop;
};

// A direction's crossings in the lane layout, ordered by distance; first_at[n] is the first crossing reading
// no column nearer than n texels along the major axis (n = 0 .. nmajor + 1), first_at[nmajor + 2 + n] the
// first reading one beyond n.
struct LaneDirection {
  bool x_major = true;
  int su = 1;    // the ray's step along the major axis (+1 or -1)
  double g = 0;  // minor change per +1 of the major index along a ray's line
  std::vector<LaneCrossing> crossings;
  std::vector<float> major;  // each crossing's major distance (texels)
  std::vector<std::int32_t> first_at;
  bool curved = false;  // some crossing's drop is not 0
  // The search may end where nothing ahead of a texel is higher than it (lane_kernel.inc, beats_to_end);
  // build sets it where every crossing's drop is at least 0 (a curvature of at least 0).
  bool end_below = true;
  // World distance per unit of the major index along the rays (a crossing at major distance n lies n * run
  // away), from the farthest crossing; 0 without crossings.
  double run = 0;
  // Where the texels the crossings read lie across a ray's line: for a ray of intercept c (the line
  // v - g u = c) and a texel (U, V) one of its crossings reads, V - (c + g U) is in [e_lo, e_hi].
  double e_lo = 0, e_hi = 0;
  // The texels the rays of the unit strip of intercepts [k, k + 1) (k an integer) read at major index u:
  // minor indices k + reach_lo[u] .. k + reach_hi[u] (from e_lo and e_hi, with a margin for rounding).
  std::vector<std::int32_t> reach_lo, reach_hi;

  // curvature: c of the lowering c d^2 of a point at horizontal world distance d (terrain/earth.hpp
  // EarthCurvature; 0: a flat Earth).
  void build(const HeightField& f, const LaneLayout& layout, double dx, double dy, double curvature = 0);
};

// A search's statistics (for measurements): groups of kLanes texels, blocks evaluated, crossings evaluated.
struct LaneStats {
  std::uint64_t groups = 0, blocks = 0, crossings = 0;
};

// Per-thread scratch of the strips' bounds and the hinted blocks.
struct LaneScratch {
  std::vector<float> block, coarse, suffix;
  std::vector<float> raw_suffix;   // per walk block: the highest height from it to the end (lane_kernel.inc)
  std::vector<float> trend;        // per walk column: the strip's trend times the distance (lane_kernel.inc)
  std::vector<std::int32_t> mark;  // per walk block: the group that tried it as a hint
  int level_at[4] = {};            // where each coarse level's rows start in `coarse`, and where they end
  int nmajor = -1;                 // the layout's columns the arrays are sized for

  // Sizes the arrays for a layout of nmajor columns. lane_search calls it before a kernel runs: the
  // kernels never grow a vector, whose code emitted out of line in a kernel's file, compiled for AVX-512,
  // could be the copy the linker keeps for every caller (P1.IsaKernelsOwnTheirCode).
  void size_for(int nmajor);
};

// The lane search of a field with rectangular texels (dx x dy) runs each ray along its texel-space
// direction: lane_plan is plan_direction's direction k of spec with (dx, dy) the normalised (cos phi / dx,
// sin phi / dy) (plan_direction's own on square texels), and build_lane_direction builds its crossings on
// unit texels, each crossing's inv_s divided by the direction's world length (a texel-space distance s lies
// s * length world units away) and its drop recomputed (curvature: LaneDirection::build's).
SweepDirection lane_plan(const HeightField& f, const SweepSpec& spec, int k);
void build_lane_direction(LaneDirection& d, const HeightField& f, const LaneLayout& layout,
                          const SweepDirection& sd, double curvature);

// Number of strips (each holds at most one group of kLanes texels per major index) of a direction.
int lane_strip_count(const LaneLayout& layout, const LaneDirection& d);
// The strips [*s0, *s1) that hold the layout's searched texels (recv_*).
void lane_strip_range(const LaneLayout& layout, const LaneDirection& d, int* s0, int* s1);
// The intercept (v - g u) below every strip's: strip s holds the texels whose intercepts lie in
// [origin + kLanes s, origin + kLanes (s + 1)).
inline double lane_intercept_origin(const LaneLayout& L, const LaneDirection& d) {
  return std::min(0.0, -d.g * double(L.nmajor - 1));
}

// A repeat field's rays on the lanes. A repeat field's ray runs through the tiling to where its sweep line
// starts (the sweep's warm-up, sweep/sweep_lines.hpp): `periods` (P1Params::wrap_periods) whole periods
// beyond the texel's own along the major axis. The same rays on a clamp field: the tiling with `periods`
// periods on either side of f along the major axis and, across it, as far as a ray drifts over that span (at
// most periods + 1 periods of the major axis, |g| <= 1), whose border ends each ray where its line starts.
// tiled_shape is its shape (no heights: LaneLayout::build_tiled lays them out), tiled_texels counts it, and
// lane_tiles says whether a bake searches f so (clamp fields always; repeat ones while the tiling stays
// within kTiledTexels: 8 bytes a texel of it, 2 GiB).
inline constexpr double kTiledTexels = double(std::size_t(1) << 28);
HeightField tiled_shape(const HeightField& f, bool x_major, int periods);
double tiled_texels(int width, int height, bool x_major, int periods);
bool lane_tiles(int width, int height, Wrap wrap, int periods);
// The larger of the two axes' lane layouts of a width x height field (build, or build_tiled on a repeat
// field), bytes: what a search holds beside its slopes.
double lane_layout_bytes(int width, int height, Wrap wrap, int periods);

// The instruction set a search runs on (the same bits on each): best = lane_isa(). sse2 < avx2 < avx512.
enum class LaneIsa { best, sse2, avx2, avx512 };
// Whether this processor (and its operating system) runs `isa`'s kernel; sse2 always.
bool lane_isa_available(LaneIsa isa);
// What LaneIsa::best runs: the widest the processor has (AVX-512F, AVX2, SSE2), capped by the environment
// variable HFBAKE_ISA (core/instruction_set.hpp: the most a search may use; docs/cluster.md). Throws
// std::invalid_argument naming the variable on any other value.
LaneIsa lane_isa();

// Searches the groups of strips [s0, s1): for every texel (i, j) of them the layout searches (recv_*),
// slope[(j - out_j0) * out_width + i - out_i0] = the steepest slope (rise / run) of any crossing of its ray
// (-inf: none on the field) and which[...] that crossing's index in d.crossings (-1: none); which null: the
// slopes alone (the same ones, a little sooner). A clamp field's own layout indexes them as the field
// does; a repeat field's tiling (LaneLayout::build_tiled), as the repeat field does.
void lane_search(const LaneLayout& layout, const LaneDirection& d, int s0, int s1, float tolerance,
                 LaneScratch& scratch, float* slope, std::int32_t* which, LaneStats* stats = nullptr,
                 LaneIsa isa = LaneIsa::best);
// The AVX2 kernel (lane_horizons_avx2.cpp); call lane_search instead.
void lane_search_avx2(const LaneLayout& layout, const LaneDirection& d, int s0, int s1, float tolerance,
                      LaneScratch& scratch, float* slope, std::int32_t* which, LaneStats* stats);
// The AVX-512F kernel (lane_horizons_avx512.cpp); call lane_search instead.
void lane_search_avx512(const LaneLayout& layout, const LaneDirection& d, int s0, int s1, float tolerance,
                        LaneScratch& scratch, float* slope, std::int32_t* which, LaneStats* stats);

// What lane_directions keeps from one call to the next on the same field (a bake's direction blocks): the
// last lane layout it built, so a block whose first axis is the previous block's last does not build it
// again, and the per-texel slopes and casters. Memory only: no result depends on it.
struct LaneReuse {
  int axis = -1;  // the layout's (0: x-major, 1: y-major), -1: none built
  LaneLayout layout;
  HeightField shape;  // a repeat field's tiling (tiled_shape)
  std::vector<float> slope;
  std::vector<std::int32_t> which;
};

// Every texel's horizon in the directions ks of spec (lane_plan's rays), clamp fields (and repeat fields
// through their tiling, wrap_periods its periods: tiled_shape): the directions of
// one axis at a time (the x-major ones first, each group in the order of ks), so one LaneLayout is held at
// a time; after each direction's search, done(sd, d, slope, which) with lane_search's slope and which of
// every texel (which: null unless casters). rc.check() before each direction. reuse: kept between calls
// on the same field (or null).
template <class Done>
void lane_directions(const HeightField& f, const SweepSpec& spec, const std::vector<int>& ks,
                     double curvature, float tolerance, bool casters, const RunControl& rc, Done&& done,
                     LaneReuse* reuse = nullptr, int wrap_periods = 1) {
  const std::size_t N = f.texel_count();
  LaneReuse own;
  LaneReuse& r = reuse ? *reuse : own;
  r.slope.resize(N), r.which.resize(casters ? N : 0);
  float* slope = r.slope.data();
  std::int32_t* which = casters ? r.which.data() : nullptr;
  tbb::enumerable_thread_specific<LaneScratch> scratch;
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<SweepDirection> dirs;
    for (int k : ks) {
      const SweepDirection sd = lane_plan(f, spec, k);
      if ((std::fabs(sd.dx) >= std::fabs(sd.dy)) == (axis == 0)) dirs.push_back(sd);
    }
    if (dirs.empty()) continue;
    if (r.axis != axis) {
      // Built into the other axis' buffers (LaneLayout::build), not beside them.
      if (f.wrap == Wrap::repeat) {
        r.layout.build_tiled(f, axis == 0, wrap_periods);
        r.shape = tiled_shape(f, axis == 0, wrap_periods);
      } else {
        r.layout.build(f, axis == 0);
      }
      r.axis = axis;
    }
    const LaneLayout& layout = r.layout;
    const HeightField& shape = f.wrap == Wrap::repeat ? r.shape : f;
    for (const SweepDirection& sd : dirs) {
      rc.check();
      LaneDirection d;
      build_lane_direction(d, shape, layout, sd, curvature);
      int s0 = 0, s1 = 0;
      lane_strip_range(layout, d, &s0, &s1);
      tbb::parallel_for(tbb::blocked_range<int>(s0, s1, 2), [&](const tbb::blocked_range<int>& r) {
        lane_search(layout, d, r.begin(), r.end(), tolerance, scratch.local(), slope, which);
      });
      done(sd, d, static_cast<const float*>(slope), static_cast<const std::int32_t*>(which));
    }
  }
}

}  // namespace hfbake::p1
