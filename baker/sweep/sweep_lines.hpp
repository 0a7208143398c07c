// The line-sweep driver shared by the horizon methods (P1 hull stack, P2 hull tree, LSAO obscurance hull):
// for each azimuth phi_k = 2 pi k / K, parallel straight lines cover the whole field; each line's samples
// are handed, in order, to a per-line visitor, which writes one result (C floats) per receiver sample; the
// results are then brought back to the texel centers by a documented two-tap rule and handed to a per-texel
// visitor. Lines run in parallel (oneTBB); results are bit-identical for any thread count.
//
// ---- Geometry (texel coordinates: texel (i, j) is at (x, y) = (i, j); world = texel * texel_size) -----
// Direction k looks towards d_k = (cos phi_k, sin phi_k). Its "major axis" is x when |cos| >= |sin|, else y;
// u denotes the major coordinate and v the minor one (x-major: u = x, v = y; y-major: u = y, v = x).
// * Lines: line l is the set of points v = l + u * slope with slope = d_minor / d_major (|slope| <= 1),
//   i.e. lines one texel apart along the minor axis (|cos| texel apart perpendicular to themselves).
// * Samples: one per integer u (one per texel column for x-major directions), so consecutive samples are
//   step = texel_size * sqrt(1 + slope^2) apart (1 .. sqrt(2) texels; exactly 1 on the axes).
//   Every sample lies on a texel column (row), so its height is the bilinear height of the field there,
//   which reduces to a 1D linear interpolation between the two texels (u, floor v) and (u, floor v + 1)
//   (exactly HeightField::bilinear at that point; in clamp mode rows outside the field are clamped).
//   Such a point lies on a cell edge, where the reference's triangulated surface (two triangles per quad,
//   split along (i+1, j)-(i, j+1)) has the same height; the surface's kinks between columns (where a line
//   crosses a row or a quad's diagonal) are not samples, so a hull over the samples can miss a caster there
//   (P1's line worker adds them from the field, and its texels march them nearby:
//   methods/p1/horizon_sweep.hpp).
// * Walk order: a line is walked towards phi_k + pi: sample n - 1 lies in direction phi_k from sample n.
//   So the samples a visitor has already seen when it reaches sample n are exactly the terrain that sample
//   n sees when it looks towards azimuth phi_k (the horizon direction k of docs/contract.md).
// * Receivers, and how results reach texel centers (exact rule): a sample at (u, v) with
//   f = v - floor(v) sends its result to texel (u, floor v) with weight 1 - f and to texel (u, floor v + 1)
//   with weight f -- the transpose of its height interpolation. Equivalently, texel (u, v0) receives
//     value = (1 - g) * result(line l0, column u) + g * result(line l0 + 1, column u),
//     g = (v0 - u * slope) - l0,  l0 = floor(v0 - u * slope),
//   the linear interpolation between the two lines that pass on either side of the texel center, along
//   the texel's own column. Weights sum to 1. When u * slope is an integer (axis directions for every
//   texel, diagonals too: slope = +-1 is snapped exactly) g = 0 and the texel IS a sample: no interpolation.
//   Otherwise the texel center lies less than one minor step (1 texel) from the samples it blends (see
//   clamp below for the border rows); the error this adds is measured in tests/p1 (a march from the
//   texel centers themselves: P1Measure.MappingErrorAgainstTexelCenterMarch).
// * clamp: the field ends at its border. A line's samples inside the field, v in [0, n_minor - 1], form
//   one contiguous run [inside_begin, inside_end); only those are terrain (occluders) and receivers. A texel
//   on the first or last row (column) of the minor axis whose other line runs off the field takes its
//   inside tap alone (weight 1, a sample less than one texel away): no result of a point off the field
//   ever reaches a texel. Samples off the field are still handed to the visitor (their heights are the
//   clamped border heights); their results are unused. All n_major columns are samples of every line
//   (first_receiver = 0, no warm-up), except on thin fields (below).
// * clamp, thin fields (trimmed lines): when a direction's lines cross the field in runs far shorter than
//   n_major (|slope| > 0 and (n_minor + 2) / |slope| + 4 <= n_major / 4: every x-major direction of a
//   5000 x 2 field but the axis), lines() * n_major samples would grow with the square of the long side while
//   only the runs matter. Each line then keeps SweepDirection::span consecutive columns around its run, the
//   columns where v lies in [-1.5, n_minor + 0.5] (every terrain sample, and every receiver a texel tap
//   reads, v in (-1, n_minor]); the worker sees that piece as the whole line (line_direction: count = span,
//   its own u_start), and SweepLine::s keeps the full line's distances, so results are the same bits as
//   untrimmed lines for workers that use s(n) and the positions (tests/sweep). Work and result buffers
//   are then linear in the texels: about 2 n_major (n_minor + 2) samples per direction.
// * repeat: the field tiles. Lines l in [0, n_minor) suffice (line l + n_minor has the same heights); each
//   line first walks a warm-up of wrap_periods * n_major samples (terrain only, no receivers), then the
//   n_major receiver samples. Bound: a receiver sees at least wrap_periods * n_major * step of tiled
//   terrain behind it (whole periods along the major axis), so an occluder that the infinite tiling has
//   beyond that would change the horizon's tangent by at most (z_max - z_min) / (wrap_periods * n_major *
//   texel_size); with wrap_periods = 1 the result equals the center tile of a 3 x 3 clamp tiling up to
//   occluders more than one period away and the mapping error (the line lattice is anchored at texel
//   (0, 0) of each field, so texels blend different sample pairs). The last receiver of a line and the first
//   of the next period are neighbours on the torus, so the two edges of a repeat bake match when tiled.
//
// ---- Usage -----------------------------------------------------------------------------------------
//   SweepSpec spec;  spec.directions = 64;  spec.channels = 1;
//   std::vector<float> sum(field.texel_count());
//   sweep_lines(field, spec, rc,
//     [&] { return MyLineWorker{};  },                     // one worker per thread: owns its scratch
//     [&](int k, int i, int j, const TexelTaps& t) {       // per texel and direction, k ascending
//       sum[field.index(i, j)] += t.value(0);               //   (texels of a tile are visited by one task)
//     });
//   struct MyLineWorker {                                     // called concurrently on different lines
//     std::vector<int> stack;                                 // scratch: reserve once, never in the loop
//     void operator()(const SweepLine& line, float* out) {    // out: line.receivers() * channels floats
//       for (int n = 0; n < line.count; ++n) {
//         const float z = line.z[n];                          // height (world) of sample n
//         double s = line.s(n);                               // world distance along the walk
//         if (n >= line.first_receiver) out[(n - line.first_receiver) * C + c] = ...;
//         if (line.is_terrain(n)) ... push as occluder ...
//       }
//     }
//   };
// The per-texel visitor is called once per (texel, direction), tiles in parallel, and for one texel in
// ascending k: per-texel accumulation in its own storage is deterministic. sweep_lines_tiled gives the same
// results per 32 x 32 tile as arrays (SweepTile), for per-texel work that should vectorise (P1 lighting).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/page_buffer.hpp"
#include "core/run_control.hpp"
#include "field/height_field.hpp"

namespace hfbake {

struct SweepSpec {
  int directions = 64;           // K; direction k has azimuth 2 pi k / K
  std::vector<double> azimuths;  // if not empty: explicit azimuths (radians) instead; directions is ignored
  int channels = 1;              // floats each line visitor writes per receiver sample
  int wrap_periods = 1;          // repeat mode: warm-up length in whole periods of the major axis (>= 1)
  // The lines themselves.
  struct Sampling {
    // Off: the lines are not sampled (SweepLine::z is null, inside_begin = 0, inside_end = count) and no
    // transposed copy of the field is made, for line visitors that read the field themselves (P1's far
    // field builds its own profiles with the row and diagonal crossings).
    bool heights = true;
    bool trim_thin = true;  // clamp, thin fields: trimmed lines (off: every line walks every column)
  } sampling;
  // What sweep_lines_tiled fills in each SweepTile (off: the field is null).
  struct TileFields {
    bool nearest = true;  // SweepTile::nearest
    bool taps = false;    // SweepTile::lo, hi, w_hi (both taps apart)
    bool values = true;   // SweepTile::value
    bool strip = false;   // SweepTile::strip (see strip_line)
  } tile;
  // The driver's buffers (see Memory).
  struct Buffers {
    int batch = 4;  // directions swept before each gather pass while their whole buffers fit
    std::size_t max_bytes = std::size_t(256) << 20;  // bound on the driver's buffers
    bool zero = true;  // zero the result buffers first (off: the worker writes every receiver's C floats)
  } buffers;
};

// The lines of one direction (plain data; see the header comment for the geometry).
struct SweepDirection {
  int k = 0;
  double phi = 0;         // radians
  double dx = 1, dy = 0;  // unit vector towards phi (the direction the horizon looks)
  bool x_major = true;
  int su = -1;       // walk sign along the major axis (walk goes towards phi + pi)
  double slope = 0;  // v = line + u * slope
  int n_major = 0, n_minor = 0;
  bool repeat = false;
  int line_begin = 0, line_end = 0;  // line indices [line_begin, line_end)
  int u_start = 0;                   // major coordinate of sample 0
  int count = 0;                     // samples per line (warm-up + receivers)
  int first_receiver = 0;            // samples [first_receiver, count) are receivers: one per column u
  int span = 0;     // clamp, thin fields: samples each line keeps (line_direction); 0: every column (count)
  double step = 1;  // world distance between consecutive samples
  double texel_size = 1;

  int lines() const { return line_end - line_begin; }
  // Result slots per line (receivers of the longest line): the stride of a line's results.
  int stride() const { return span > 0 ? span : n_major; }
  int receivers() const { return count - first_receiver; }
  // Major coordinate of sample n, and the minor coordinate of line l there.
  int u(int n) const { return u_start + n * su; }
  double v(int line, int n) const { return line + double(u(n)) * slope; }
  // Index among the receivers of the sample at major coordinate u (0 <= u < n_major).
  int receiver_index(int u) const { return su > 0 ? u : n_major - 1 - u; }
};

// Builds direction k of spec (azimuth 2 pi k / K, or spec.azimuths[k]) for field (exposed for tests and for
// visitors that precompute per direction).
SweepDirection plan_direction(const HeightField& field, const SweepSpec& spec, int k);

// Line `line` of dir as its worker sees it: dir itself, or for a trimmed direction (span > 0) a copy whose
// count is span and whose u_start is the line's first kept column (the kept columns lie in [0, n_major)).
SweepDirection line_direction(const SweepDirection& dir, int line);
// u_start of line_direction(dir, line) (dir.u_start when the direction is not trimmed).
int line_u_start(const SweepDirection& dir, int line);
// Where the result of column u of line `line` sits among the line's dir.stride() result slots.
inline int line_slot(const SweepDirection& dir, int line, int u) {
  if (dir.span == 0) return dir.receiver_index(u);
  return dir.receiver_index(u) - dir.receiver_index(line_u_start(dir, line));
}

// Two texels and their weights (texel index into the row-major field, or -1 for a texel outside a clamp
// field; weights sum to 1).
struct TexelPair {
  std::ptrdiff_t texel[2] = {-1, -1};
  float weight[2] = {0, 0};
};

// One line as its visitor sees it. Arrays are valid only during the visitor call.
struct SweepLine {
  const SweepDirection* dir = nullptr;
  int line = 0;            // line index l (v = l + u * slope)
  int count = 0;           // samples, in walk order
  int first_receiver = 0;  // samples [first_receiver, count) are receivers (out[n - first_receiver])
  int inside_begin = 0, inside_end = 0;  // terrain samples (clamp: on the field; repeat: all)
  const float* z = nullptr;              // world height of every sample, count entries
  double step = 1;                       // world distance between consecutive samples

  int receivers() const { return count - first_receiver; }
  bool is_terrain(int n) const { return n >= inside_begin && n < inside_end; }
  int s_offset = 0;  // trimmed lines: the full line's index of sample 0 (s keeps the full line's distances)
  // World distance of sample n from the full line's sample 0 along the walk.
  double s(int n) const { return (n + s_offset) * step; }
  // Texel coordinates of sample n (x = column, y = row; repeat mode: not wrapped).
  double x(int n) const { return dir->x_major ? double(dir->u(n)) : dir->v(line, n); }
  double y(int n) const { return dir->x_major ? dir->v(line, n) : double(dir->u(n)); }
  Vec3 position(int n) const { return {x(n) * dir->texel_size, y(n) * dir->texel_size, double(z[n])}; }
  // The texels sample n's height was interpolated from (clamped / wrapped into the field), with their
  // weights: use them to interpolate any per-texel attribute (normal, albedo, emission) at the sample.
  TexelPair height_taps(int n, const HeightField& field) const;
  // The texels receiver sample n's result reaches, with their weights (-1: outside a clamp field). Every
  // texel's weights over all samples of its direction sum to 1 (two samples on two adjacent lines).
  TexelPair receiver_texels(int n, const HeightField& field) const;
};

// What the per-texel visitor gets for one (texel, direction): the two samples it blends.
struct TexelTaps {
  const float* lo = nullptr;     // result of line l0 at the texel's column (channels floats)
  const float* hi = nullptr;     // result of line l0 + 1
  const float* strip = nullptr;  // result of line l0 + 1 always, also at a lone border tap (strip_line)
  float w_hi = 0;                // weight of hi (0 <= w_hi < 1); lo has 1 - w_hi
  float value(int c) const { return w_hi == 0 ? lo[c] : lo[c] * (1 - w_hi) + hi[c] * w_hi; }
  const float* nearest() const { return w_hi > 0.5f ? hi : lo; }
};

// Fills z[0..dir.count) with the heights of line `line`; returns the inside run in *inside_begin/end.
// `transposed` (optional): the field's heights transposed (width rows of height floats), read instead of
// the field for y-major directions so consecutive samples are adjacent in memory. Same values either way.
void sample_line(const HeightField& field, const SweepDirection& dir, int line, float* z, int* inside_begin,
                 int* inside_end, const float* transposed = nullptr);

// Line `line` of direction `dir`, sampled into z[0..dir.count) (z must hold dir.count floats and outlive the
// returned line): what tests use to walk one line by hand. The driver hands each line visitor
// sampled_line(field, line_direction(dir, line), line, ...): the same line, trimmed on thin fields.
// unsampled_line: the same line without its heights (z null, every sample counted inside).
inline SweepLine unsampled_line(const SweepDirection& dir, int line) {
  SweepLine l;
  l.dir = &dir;
  l.line = line;
  l.count = dir.count;
  l.first_receiver = dir.first_receiver;
  l.step = dir.step;
  // A trimmed line's direction (line_direction) starts later along the walk than the full line.
  if (dir.span > 0) l.s_offset = dir.su > 0 ? dir.u_start : dir.n_major - 1 - dir.u_start;
  l.inside_begin = 0, l.inside_end = dir.count;
  return l;
}
inline SweepLine sampled_line(const HeightField& field, const SweepDirection& dir, int line, float* z,
                              const float* transposed = nullptr) {
  SweepLine l = unsampled_line(dir, line);
  l.z = z;
  sample_line(field, dir, line, z, &l.inside_begin, &l.inside_end, transposed);
  return l;
}

// The clamp-border tap rule: a texel on minor-axis index v, a fraction frac of the way between the samples
// of two lines, keeps one tap alone when it lies on the first or last row (column) of a clamp field: its
// other tap is off the field and no receiver. Which tap it keeps: the inside one (texel_taps).
inline bool lone_border_tap(const SweepDirection& dir, int v, float frac) {
  return !dir.repeat && frac > 0 && dir.n_minor > 1 && (v == 0 || v == dir.n_minor - 1);
}

// Strips: the texels whose centres lie between line l - 1 and line l (v_{l-1}(u) <= v0 < v_l(u) on their
// column u, i.e. floor(v0 - u * slope) = l - 1) form strip l; each column has exactly one texel of each
// strip, and every texel's ray towards phi_k stays inside its strip. A line visitor that computes per strip
// (on line l, the texels of strip l: P1's far field) writes them as line l's receivers; TexelTaps::strip and
// SweepTile::strip hand each texel its strip's result. Unlike the two taps, a strip never needs a border
// rule: every texel of a clamp field has both its lines among the direction's lines (plan_direction), even
// where one of them runs off the field. strip_line: the line index l of texel (u, v0)'s strip (unwrapped).
inline int strip_line(const SweepDirection& dir, int u, int v0) {
  return floor_int(double(v0) - double(u) * dir.slope) + 1;
}

namespace detail {

// texel_taps with the results of relative line p = l - line_begin (0 .. lines() - 1) at line_base(p).
template <class LineBase>
TexelTaps texel_taps_at(const SweepDirection& dir, LineBase&& line_base, int channels, int i, int j) {
  const int u = dir.x_major ? i : j, v0 = dir.x_major ? j : i;
  const double g = double(v0) - double(u) * dir.slope;
  const double fl = double(floor_int(g));
  int la = int(fl) - dir.line_begin, lb;
  TexelTaps t;
  t.w_hi = float(g - fl);
  if (dir.repeat) {
    la %= dir.n_minor;
    if (la < 0) la += dir.n_minor;
    lb = la + 1 == dir.n_minor ? 0 : la + 1;
  } else {
    la = std::clamp(la, 0, dir.lines() - 2);
    lb = la + 1;
  }
  if (dir.span == 0) {
    const std::size_t r = std::size_t(dir.receiver_index(u)) * std::size_t(channels);
    t.lo = line_base(la) + r;
    t.hi = line_base(lb) + r;
  } else {  // trimmed lines: each line's results start at its first kept column
    t.lo = line_base(la) + std::size_t(line_slot(dir, la + dir.line_begin, u)) * std::size_t(channels);
    t.hi = line_base(lb) + std::size_t(line_slot(dir, lb + dir.line_begin, u)) * std::size_t(channels);
  }
  t.strip = t.hi;  // line l0 + 1 (la + 1, wrapped in repeat mode): never clamped on the field
  // clamp: a tap off the field is no receiver; the border texel takes its other (inside) tap alone.
  if (lone_border_tap(dir, v0, t.w_hi)) {
    if (v0 == 0) t.lo = t.hi;
    t.w_hi = 0;
  }
  return t;
}

}  // namespace detail

// The texel taps of texel (i, j) for direction dir in a result buffer laid out as
// buffer[((l - line_begin) * stride() + line_slot(dir, l, u)) * channels + c] (untrimmed: the slot is
// receiver_index(u) and the stride n_major).
inline TexelTaps texel_taps(const SweepDirection& dir, const float* buffer, int channels, int i, int j) {
  const std::size_t line = std::size_t(dir.stride()) * std::size_t(channels);
  return detail::texel_taps_at(
      dir, [&](int p) { return buffer + std::size_t(p) * line; }, channels, i, j);
}

// The same with each line's results anywhere: lines[l - line_begin] points at line l's stride() * channels
// floats (laid out as in a buffer row; what the driver hands its gathers).
inline TexelTaps texel_taps(const SweepDirection& dir, const float* const* lines, int channels, int i,
                            int j) {
  return detail::texel_taps_at(
      dir, [&](int p) { return lines[p]; }, channels, i, j);
}

// The lines a tile's taps read: texel_taps of every texel (i, j) in [i0, i1) x [j0, j1) reads only lines
// (relative indices l - line_begin) in [*lo, *hi], and reads both ends (exact: floor(v0 - u * slope) is
// monotone in u and v0 in floating point too, so the tile's corners give its extremes). Repeat: the set
// wraps when *lo > *hi (lines [*lo, n_minor) and [0, *hi]: the tile blends line n_minor - 1 with line 0);
// *lo = 0, *hi = n_minor - 1 when the tile needs every line.
void sweep_tile_lines(const SweepDirection& dir, int i0, int i1, int j0, int j1, int* lo, int* hi);

// ---- Memory ---------------------------------------------------------------------------------------------
// The driver keeps each direction's line results until the tiles that read them are gathered. Directions go
// in batches of up to spec.buffers.batch whose whole result buffers (lines() * stride() * channels floats
// each) fit the budget (buffers.max_bytes less the transposed copy below): all their lines, then every 32 x
// 32 tile for each direction of the batch in ascending k. A direction whose whole buffer does not fit streams
// alone: its lines are computed in chunks (in parallel within a chunk) into a ring of `window` lines; after
// each chunk, the tiles whose lines (sweep_tile_lines) are all computed are gathered, in order of their
// last line, and lines that no tile still needs are overwritten. Repeat: the first `head` lines, which the
// tiles across the seam (line n_minor - 1 next to line 0) read, are kept apart until those tiles are
// gathered, last. head + window lines fit the budget whenever one tile's span of lines (about 34 + 32
// |slope|) does; below that, one chunk is one line and the window is that span. y-major lines read a
// transposed copy of the field (4 bytes a texel) only when it takes at most a quarter of buffers.max_bytes;
// otherwise they read the field in place (the same heights). The visitors get the same values whichever way.

// Peak bytes the driver allocates for field and spec: result buffers (whole, or ring and head), the
// transposed copy, each direction's line table and tile order, and per thread (this arena's
// tbb::this_task_arena::max_concurrency()) one line's heights and sweep_lines_tiled's tile scratch. It runs
// the driver's own plan, so the result buffers (the bulk) are exact; for fields whose direction buffers
// exceed buffers.max_bytes it stays near it, independent of the field's height. Excludes what
// workers and visitors allocate.
std::size_t sweep_buffer_bytes(const HeightField& field, const SweepSpec& spec);

// One tile of gathered results for the tiled gather (sweep_lines_tiled): texels [i0, i0 + width) x
// [j0, j0 + height) for direction k, structure-of-arrays per channel so per-texel loops vectorise:
//   value[(c * height + y) * width + x]    the interpolated result (TexelTaps::value) of texel (i0+x, j0+y)
//   nearest[(c * height + y) * width + x]  the result of its larger-weight tap (TexelTaps::nearest)
struct SweepTile {
  int k = 0;
  int i0 = 0, j0 = 0, width = 0, height = 0;
  int channels = 1;
  const float* value = nullptr;
  const float* nearest = nullptr;
  // With SweepSpec::tile.taps: the two taps apart (same layout) and the weight of hi per texel
  // (w_hi[y * width + x]); value = lo * (1 - w_hi) + hi * w_hi. For visitors that correct each tap
  // before blending (P1 evaluates each tap's horizon caster from the texel's own height).
  const float* lo = nullptr;
  const float* hi = nullptr;
  const float* w_hi = nullptr;
  const float* off_lo = nullptr;  // signed offset (texels) along the minor axis from the texel to lo's sample
  const float* off_hi = nullptr;  // ... and to hi's sample (each [y * width + x])
  // With SweepSpec::tile.strip: the result of the texel's strip (TexelTaps::strip, strip_line), same layout.
  const float* strip = nullptr;
};

namespace detail {

constexpr int kSweepTile = 32;  // the gather's tiles: kSweepTile x kSweepTile texels

// The driver's plan (see Memory): batches of directions and whether they stream.
struct SweepBatch {
  int k0 = 0, nb = 1;   // directions [k0, k0 + nb)
  bool stream = false;  // one direction through a window (nb = 1); else whole buffers
};
struct SweepPlan {
  std::vector<SweepBatch> batches;
  bool transposed = false;        // y-major lines read a transposed copy of the field
  std::size_t buffer_budget = 0;  // bytes left for result buffers
};
SweepPlan plan_sweep(const HeightField& field, const SweepSpec& spec,
                     const std::vector<SweepDirection>& dirs);

// One streaming direction's schedule: lines [0, head) in their own store, the others in a ring of window
// lines (line p in slot (p - head) % window); lines computed chunk at a time; after lines [c0, c1), the
// tiles order[first[c0] .. first[c1]) are gathered (tile index tj * tiles_x + ti).
struct SweepStream {
  int head = 0, window = 1, chunk = 1;
  std::vector<std::uint32_t> order;
  std::vector<std::uint32_t> first;  // lines() + 1 entries: tiles in order whose last line is < p
};
SweepStream plan_stream(const HeightField& field, const SweepDirection& dir, std::size_t budget_bytes,
                        int channels, bool with_order);

// The strip results (TexelTaps::strip) of the texels [i0, i1) x [j0, j1) into out[(c * height + y) * width +
// x].
inline void gather_strips(const SweepDirection& dir, const float* const* lines, int C, int i0, int i1, int j0,
                          int j1, float* out) {
  const std::size_t plane = std::size_t(i1 - i0) * std::size_t(j1 - j0);
  for (int j = j0; j < j1; ++j)
    for (int i = i0; i < i1; ++i) {
      const int u = dir.x_major ? i : j, v0 = dir.x_major ? j : i;
      int p = strip_line(dir, u, v0) - 1 - dir.line_begin;  // as texel_taps_at's la, then la + 1
      if (dir.repeat) {
        p %= dir.n_minor;
        if (p < 0) p += dir.n_minor;
        p = p + 1 == dir.n_minor ? 0 : p + 1;
      } else {
        p = std::clamp(p, 0, dir.lines() - 2) + 1;
      }
      const float* src = lines[p] + std::size_t(line_slot(dir, p + dir.line_begin, u)) * std::size_t(C);
      const std::size_t at = std::size_t(j - j0) * std::size_t(i1 - i0) + std::size_t(i - i0);
      for (int c = 0; c < C; ++c) out[c * plane + at] = src[c];
    }
}

// Lines of each batch (whole, or streamed), then tile_fn(k0, nb, dirs, lines, i0, i1, j0, j1) for every
// 32 x 32 tile once per batch (tiles in parallel), where lines[b][l - line_begin] holds line l of direction
// k0 + b.
template <class MakeWorker, class TileFn>
void sweep_lines_core(const HeightField& field, const SweepSpec& spec, const RunControl& rc,
                      MakeWorker&& make_worker, TileFn&& tile_fn) {
  const int K = spec.azimuths.empty() ? spec.directions : int(spec.azimuths.size()), C = spec.channels;
  if (K <= 0 || C <= 0 || field.width <= 0 || field.height <= 0) return;
  std::vector<SweepDirection> dirs(K);
  int max_count = 0;
  for (int k = 0; k < K; ++k) {
    dirs[k] = plan_direction(field, spec, k);
    max_count = std::max(max_count, dirs[k].count);
  }
  const SweepPlan plan = plan_sweep(field, spec, dirs);

  // y-major lines read a transposed copy when it is small: consecutive samples are then adjacent in memory.
  std::vector<float> transposed;
  if (plan.transposed) {
    transposed.resize(field.texel_count());
    tbb::parallel_for(0, field.width, [&](int i) {
      for (int j = 0; j < field.height; ++j)
        transposed[std::size_t(i) * field.height + j] = field.z[field.index(i, j)];
    });
  }
  const float* tz = transposed.empty() ? nullptr : transposed.data();

  using Worker = decltype(make_worker());
  tbb::enumerable_thread_specific<Worker> workers(make_worker);
  tbb::enumerable_thread_specific<std::vector<float>> heights([&] { return std::vector<float>(max_count); });

  // Result storage, grown to the largest batch's need; lines[b][p]: where relative line p of direction
  // k0 + b lives.
  PageBuffer<float> storage;  // huge pages where the kernel gives them: fewer first-touch faults
  std::size_t storage_floats = 0;
  auto reserve = [&](std::size_t floats) {
    if (floats <= storage_floats) return;
    storage.reset();
    storage = make_page_buffer<float>(floats);
    storage_floats = floats;
  };
  std::vector<std::vector<float*>> lines(std::size_t(std::max(1, spec.buffers.batch)));
  std::vector<const float* const*> tables(lines.size());

  // Relative lines [from[b], to[b]) of directions k0 + b, in parallel, each into lines[b][p].
  auto run_lines = [&](int k0, int nb, const int* from, const int* to) {
    std::vector<int> first(nb + 1, 0);
    for (int b = 0; b < nb; ++b) first[b + 1] = first[b] + (to[b] - from[b]);
    if (first[nb] == 0) return;
    tbb::parallel_for(tbb::blocked_range<int>(0, first[nb], 4), [&](const tbb::blocked_range<int>& r) {
      rc.check();
      Worker& worker = workers.local();
      float* z = spec.sampling.heights ? heights.local().data() : nullptr;
      int b = int(std::upper_bound(first.begin(), first.end(), r.begin()) - first.begin()) - 1;
      for (int flat = r.begin(); flat < r.end(); ++flat) {
        while (flat >= first[b + 1]) ++b;
        const SweepDirection& dir = dirs[k0 + b];
        const int p = from[b] + (flat - first[b]);
        const int l = dir.line_begin + p;
        SweepDirection trimmed;
        const SweepDirection* ld = &dir;
        if (dir.span > 0) trimmed = line_direction(dir, l), ld = &trimmed;
        const SweepLine line =
            spec.sampling.heights ? sampled_line(field, *ld, l, z, tz) : unsampled_line(*ld, l);
        float* out = lines[b][p];
        if (spec.buffers.zero) std::fill_n(out, std::size_t(dir.stride()) * std::size_t(C), 0.0f);
        worker(static_cast<const SweepLine&>(line), out);
      }
    });
  };
  const int tiles_x = (field.width + kSweepTile - 1) / kSweepTile;
  const int tiles_y = (field.height + kSweepTile - 1) / kSweepTile;
  auto gather = [&](int k0, int nb, int ti, int tj) {
    tile_fn(k0, nb, dirs.data() + k0, tables.data(), ti * kSweepTile,
            std::min(field.width, (ti + 1) * kSweepTile), tj * kSweepTile,
            std::min(field.height, (tj + 1) * kSweepTile));
  };

  for (const SweepBatch& batch : plan.batches) {
    const int k0 = batch.k0, nb = batch.nb;
    if (!batch.stream) {
      // Whole buffers: every line of the batch, then every tile once for the batch's directions.
      std::size_t total = 0;
      for (int b = 0; b < nb; ++b)
        total += std::size_t(dirs[k0 + b].lines()) * std::size_t(dirs[k0 + b].stride()) * std::size_t(C);
      reserve(total);
      std::vector<int> from(nb, 0), to(nb);
      std::size_t at = 0;
      for (int b = 0; b < nb; ++b) {
        const SweepDirection& d = dirs[k0 + b];
        const std::size_t line_floats = std::size_t(d.stride()) * std::size_t(C);
        lines[b].resize(std::size_t(d.lines()));
        for (int p = 0; p < d.lines(); ++p) lines[b][p] = storage.get() + at + std::size_t(p) * line_floats;
        tables[b] = lines[b].data();
        at += std::size_t(d.lines()) * line_floats;
        to[b] = d.lines();
      }
      run_lines(k0, nb, from.data(), to.data());
      rc.check();
      // Gather: tiles of texels in parallel; within a texel, directions in ascending k.
      tbb::parallel_for(tbb::blocked_range2d<int>(0, tiles_y, 1, 0, tiles_x, 1),
                        [&](const tbb::blocked_range2d<int>& r) {
                          for (int tj = r.rows().begin(); tj < r.rows().end(); ++tj)
                            for (int ti = r.cols().begin(); ti < r.cols().end(); ++ti) gather(k0, nb, ti, tj);
                        });
      rc.report(double(k0 + nb) / K);
      continue;
    }
    // Streaming: chunks of lines into the head and the ring; after each, the tiles that became complete.
    const SweepDirection& d = dirs[k0];
    const SweepStream s = plan_stream(field, d, plan.buffer_budget, C, true);
    const std::size_t line_floats = std::size_t(d.stride()) * std::size_t(C);
    reserve(std::size_t(s.head + s.window) * line_floats);
    float* head = storage.get();
    float* ring = head + std::size_t(s.head) * line_floats;
    const int L = d.lines();
    lines[0].assign(std::size_t(L), nullptr);
    tables[0] = lines[0].data();
    for (int c0 = 0; c0 < L; c0 += s.chunk) {
      const int c1 = std::min(L, c0 + s.chunk);
      for (int p = c0; p < c1; ++p)
        lines[0][p] = p < s.head ? head + std::size_t(p) * line_floats
                                 : ring + std::size_t((p - s.head) % s.window) * line_floats;
      run_lines(k0, 1, &c0, &c1);
      rc.check();
      const std::uint32_t t0 = s.first[c0], t1 = s.first[c1];
      if (t1 > t0)
        tbb::parallel_for(tbb::blocked_range<std::uint32_t>(t0, t1, 1),
                          [&](const tbb::blocked_range<std::uint32_t>& r) {
                            for (std::uint32_t t = r.begin(); t < r.end(); ++t)
                              gather(k0, 1, int(s.order[t] % std::uint32_t(tiles_x)),
                                     int(s.order[t] / std::uint32_t(tiles_x)));
                          });
      rc.report((double(k0) + double(c1) / L) / K);
    }
  }
}

}  // namespace detail

// Runs the sweep. make_worker() -> a callable worker(const SweepLine&, float* out) (one per thread,
// created lazily; keep its scratch inside it). texel_visitor(k, i, j, const TexelTaps&) is called for
// every texel and direction. Calls rc.check() per line chunk and rc.report() per batch of directions.
template <class MakeWorker, class TexelVisitor>
void sweep_lines(const HeightField& field, const SweepSpec& spec, const RunControl& rc,
                 MakeWorker&& make_worker, TexelVisitor&& texel_visitor) {
  const int C = spec.channels;
  detail::sweep_lines_core(field, spec, rc, make_worker,
                           [&](int k0, int nb, const SweepDirection* dirs, const float* const* const* lines,
                               int i0, int i1, int j0, int j1) {
                             for (int j = j0; j < j1; ++j)
                               for (int i = i0; i < i1; ++i)
                                 for (int b = 0; b < nb; ++b)
                                   texel_visitor(k0 + b, i, j, texel_taps(dirs[b], lines[b], C, i, j));
                           });
}

// The same sweep with a tiled gather: tile_visitor(const SweepTile&) gets each 32 x 32 tile's gathered
// results as arrays, once per direction of the batch in ascending k (tiles in parallel). For visitors
// whose per-texel work vectorises; same results as sweep_lines.
template <class MakeWorker, class TileVisitor>
void sweep_lines_tiled(const HeightField& field, const SweepSpec& spec, const RunControl& rc,
                       MakeWorker&& make_worker, TileVisitor&& tile_visitor) {
  const int C = spec.channels;
  tbb::enumerable_thread_specific<std::vector<float>> scratch(
      [&] { return std::vector<float>(std::size_t(5 * C + 3) * 32 * 32); });
  auto gather_tile = [&](int k0, int nb, const SweepDirection* dirs, const float* const* const* lines, int i0,
                         int i1, int j0, int j1) {
    std::vector<float>& tmp = scratch.local();
    SweepTile tile;
    tile.i0 = i0, tile.j0 = j0, tile.width = i1 - i0, tile.height = j1 - j0, tile.channels = C;
    const std::size_t plane = std::size_t(tile.width) * tile.height;
    float* value = tmp.data();
    float* nearest = spec.tile.nearest ? tmp.data() + plane * C : nullptr;
    float* lo = spec.tile.taps ? tmp.data() + 2 * plane * C : nullptr;
    float* hi = spec.tile.taps ? tmp.data() + 3 * plane * C : nullptr;
    float* w_hi = spec.tile.taps ? tmp.data() + 4 * plane * C : nullptr;
    float* off_lo = spec.tile.taps ? w_hi + plane : nullptr;
    float* off_hi = spec.tile.taps ? w_hi + 2 * plane : nullptr;
    tile.off_lo = off_lo, tile.off_hi = off_hi;
    tile.value = spec.tile.values ? value : nullptr;
    tile.nearest = nearest;
    tile.lo = lo, tile.hi = hi, tile.w_hi = w_hi;
    float* strip = spec.tile.strip ? tmp.data() + (4 * C + 3) * plane : nullptr;
    tile.strip = strip;
    for (int b = 0; b < nb; ++b) {
      if (strip && !spec.tile.values && !nearest && !lo) {
        // Strips alone: one result per texel (its strip's line), without the taps' rules.
        detail::gather_strips(dirs[b], lines[b], C, i0, i1, j0, j1, strip);
        tile.k = k0 + b;
        tile_visitor(static_cast<const SweepTile&>(tile));
        continue;
      }
      for (int j = j0; j < j1; ++j)
        for (int i = i0; i < i1; ++i) {
          const TexelTaps t = texel_taps(dirs[b], lines[b], C, i, j);
          const std::size_t at = std::size_t(j - j0) * tile.width + (i - i0);
          if (spec.tile.values)
            for (int c = 0; c < C; ++c) value[c * plane + at] = t.value(c);
          if (strip)
            for (int c = 0; c < C; ++c) strip[c * plane + at] = t.strip[c];
          if (nearest) {
            const float* n = t.nearest();
            for (int c = 0; c < C; ++c) nearest[c * plane + at] = n[c];
          }
          if (lo) {
            for (int c = 0; c < C; ++c) lo[c * plane + at] = t.lo[c], hi[c * plane + at] = t.hi[c];
            w_hi[at] = t.w_hi;
            const SweepDirection& d = dirs[b];
            const int u = d.x_major ? i : j, v0 = d.x_major ? j : i;
            const double g = double(v0) - double(u) * d.slope;
            const float frac = float(g - double(floor_int(g)));
            // lo's sample lies frac below the texel on the minor axis, hi's 1 - frac above; a clamp border
            // texel whose lo ran off the field uses hi in both taps (texel_taps).
            const bool lo_is_hi = v0 == 0 && lone_border_tap(d, v0, frac);
            off_lo[at] = lo_is_hi ? 1 - frac : -frac;
            off_hi[at] = 1 - frac;
          }
        }
      tile.k = k0 + b;
      tile_visitor(static_cast<const SweepTile&>(tile));
    }
  };
  detail::sweep_lines_core(field, spec, rc, make_worker, gather_tile);
}

}  // namespace hfbake
