// One indirect bounce over the whole field on the shared line-sweep driver (sweep/sweep_lines.hpp):
// for every direction, every line runs the convex hull tree (or the naive march) and gathers, per
// receiver sample, the exit radiance of its visible stretches (indirect_gather.hpp); the driver brings
// the per-sample results to the texels and they are summed over the K directions.
#pragma once

#include <cstdint>
#include <vector>

#include "core/run_control.hpp"
#include "core/vec.hpp"
#include "field/height_field.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake {

enum class P2Visibility { tree, naive };

struct P2SweepStats {
  std::uint64_t receivers = 0;         // terrain receiver samples x directions (the paper's points)
  std::uint64_t iterations = 0;        // convexity checks (tree) or samples marched (naive)
  std::uint64_t naive_iterations = 0;  // what the naive march would have done: sum of samples behind
  std::uint64_t horizons = 0;          // root children of the tree summed over receivers (P2's m)
  std::uint64_t run_starts = 0;        // starts of visible runs (horizons minus redundant leaves)
  std::uint64_t pushed = 0;            // samples pushed into trees (receivers and repeat warm-up)
  std::uint64_t horizons_pushed = 0;   // root children after every push (P2 §6: iterations <= 2 m + n)
};

struct IndirectSweepSpec {
  int directions = 64;
  // The directions swept: [k_begin, k_end) of the K (k_end < 0: all K). sweep_indirect sweeps every
  // direction block (core/direction_blocks.hpp) this way; sweep_indirect_sums one of them.
  int k_begin = 0, k_end = -1;
  P2Visibility visibility = P2Visibility::tree;
  bool gather = true;    // false: visibility only (benchmarks, statistics); the result is all zero
  int wrap_periods = 1;  // repeat mode warm-up (SweepSpec::wrap_periods)
  // Supersampling along lines (P2 §10.2, Figure 15's S): S - 1 extra terrain samples between consecutive
  // line samples, at the field's bilinear heights and the exit radiance's bilinear values (facet senders:
  // the triangulated surface's heights and the facets' radiance); receivers stay the driver's samples. S = 1:
  // the driver's samples only (then the horizon that splits each texel's lobe between P1's sky and this
  // terrain is exactly P1's; with S > 1 it is the finer line's, so the split can differ from P1's by the
  // sub-sample horizon change).
  int supersampling = 1;
  // Exact line profiles (facet senders only): between consecutive line samples the lines also carry a
  // sample at every row and quad-diagonal crossing of the triangulation (edge_crossings), at the
  // triangulated surface's height, so each line's terrain is the reference's surface along it exactly
  // (with S > 1, the sub-samples as well); receivers stay the driver's samples. false: the terrain between
  // two samples (or sub-samples) is their straight segment, missing the surface's row and diagonal kinks.
  bool exact_profile = true;
  // P1's horizons at the texels of the directions swept (P1Result::horizon with horizon_by_direction: sin e,
  // [(k - k_begin) * texels + texel]).
  // When given, they split each texel's lobe between P1's sky and this terrain, so the two halves meet
  // exactly whatever way P1 brings its horizons to the texels; when null, the line samples' blended elevation
  // is used.
  const float* p1_sin_horizon = nullptr;
  // Facet senders: the exit radiance of every texel's two facets, [2 * texel + q] (facet_normals' order),
  // each its three corners' mean (corner_exit below). When given, the terrain a receiver sees radiates per
  // facet of the reference's triangulated surface, as the reference shades its hits, instead of per texel
  // with the smoothed normal: each line segment's radiance is its length-weighted mean over the facets it
  // crosses (with a linear trend for partly visible segments). The facets' normals are recomputed from the
  // heights where needed (facet_normals, field/triangulation.hpp), not held.
  const std::vector<Rgb>* exit_facets = nullptr;
  // Required with exit_facets: the exit radiance of the six facets that meet at every texel, at the texel
  // ([kCornerFacets * texel + c], field/triangulation.hpp), of which exit_facets holds each facet's mean.
  // The exact near field radiates with them: the crease below a texel's first crossing is its own corner
  // facet's light at the texel, and each visible piece the light at the middle of its visible part,
  // interpolated from its facet's corners (as the reference interpolates albedo and emission, and as the
  // light on rough ground varies over a facet). The sums at the corner facets' normals (facet_acc) are the
  // next bounce's.
  const std::vector<Rgb>* corner_exit = nullptr;
  // Exact near field (facet senders and P1's horizons only; 0: off, the method as published): every
  // texel gathers the terrain within near_radius texels itself, from its centre over the triangulated
  // surface (every column, row and diagonal crossing of P1's near-field stencil, each piece radiating
  // its facet's light), up to the steepest of those crossings; the lines' receivers gather only the
  // samples at least that far behind them (the hull tree lags), and their mean radiance fills the texel's
  // lobe from there up to P1's horizon. Receivers sit on the lines, up to half a texel from the texel
  // centres, and the nearest terrain subtends the largest angles: this removes that mapping error
  // where it is largest (tests/p2/measure_p2_centre).
  double near_radius = 0;
};

// Bytes one thread's line worker holds for a line of `count` samples (the memory estimate): per fine sample
// (count * S, exact profiles count * (S + 3): at most a row and two diagonal crossings a step) its heights,
// positions, radiance, the hull tree and the gather's scratch.
std::size_t indirect_line_scratch_bytes(int count, int supersampling, bool exact_profile);

// A RunControl reporting progress into [a, a + span) of the caller's.
RunControl p2_sub_range(const RunControl& rc, double a, double span);

// The line sweep sweep_indirect_sums runs (for estimates: sweep_buffer_bytes of it).
SweepSpec indirect_sweep_spec(const IndirectSweepSpec& spec);

// The double sums over directions [spec.k_begin, spec.k_end) (one direction block), each from zero, k
// ascending: E_indirect / pi per texel, acc[3 * texel + c], and with facet_acc (facet senders only) at the
// corner facets' normals, [(kCornerFacets * texel + q) * 3 + c]. stats: the sweep's counts.
void sweep_indirect_sums(const HeightField& field, const std::vector<Vec3f>& normals,
                         const std::vector<Rgb>& exit, const IndirectSweepSpec& spec, const RunControl& rc,
                         P2SweepStats* stats, std::vector<double>& acc, std::vector<double>* facet_acc);
// A bounce's total over the direction blocks (core/direction_blocks.hpp): each block's double sums split
// once into SplitDouble (hi, lo) float pairs, [2 * value + {0, 1}], and added by add_split in block order
// (`total` empty: the first block) -- what the farm's merge does with the blocks baked elsewhere
// (farm/merge_blocks.cpp, "#2f" layers), so both give the same bits.
void add_indirect_block(std::vector<float>& total, const std::vector<double>& block);
// The total's values as RGB (count RGB values: 6 floats each).
std::vector<Rgb> indirect_of_total(const float* total, std::size_t count);
void add_sweep_stats(P2SweepStats& total, const P2SweepStats& s);

// E_indirect / pi per texel (row-major) from the exit radiance `exit` per texel, for one bounce: every
// direction block by sweep_indirect_sums, added by add_indirect_block. normals: compute_normals(field).
// stats (optional) is filled with the totals of the sweep.
// facet_result (optional, facet senders only): E_indirect / pi at the corner facets' normals,
// [kCornerFacets * texel + c] (each texel's gathered terrain radiance over the part of the facet's lobe
// below P1's horizons): the corners' exit radiance of the next bounce.
std::vector<Rgb> sweep_indirect(const HeightField& field, const std::vector<Vec3f>& normals,
                                const std::vector<Rgb>& exit, const IndirectSweepSpec& spec,
                                const RunControl& rc, P2SweepStats* stats = nullptr,
                                std::vector<Rgb>* facet_result = nullptr);

// The mean and linear trend (SegmentRadiance) of facet radiance `facet_exit` ([2 * texel + q]) along the
// straight segment from (x0, y0) to (x1, y1) in texel coordinates: split where it crosses a column, a row
// or a quad diagonal (the reference's split, (i+1, j)-(i, j+1)), each piece weighted by its length.
void facet_segment_radiance(const HeightField& field, const Rgb* facet_exit, double x0, double y0, double x1,
                            double y1, Rgb* mean, Rgb* slope);

}  // namespace hfbake
