// P1's far field: each texel's exact horizon beyond the near radius, found on its own ray over the
// reference's triangulated surface, guided and bounded by a hull of its strip (sweep_lines.hpp, strip_line).
//
// The texels between line l - 1 and line l form strip l (one per column); each one's ray towards phi_k is
// parallel to the lines and stays inside the strip. On the triangulated surface (two triangles per quad,
// split along (i+1, j)-(i, j+1)) the strip's cross-section at a position x along the lines is a segment
// one texel long on the minor axis; the surface along it is piecewise linear, so its highest point B(x) is
// an end (on line l - 1 or line l, or on the field's border) or a kink (a row or a diagonal). Followed along
// x, those kinks' vertices are texels inside the strip, and the ends' vertices are the lines' own points:
// column samples, row and diagonal crossings, the border crossings. So the upper convex hull of
//   {points of line l - 1} u {points of line l} u {the strip's texels}        (all on the field)
// is the least concave majorant of B, and bounds the height of every texel's ray in the strip: h_T(x) <=
// B(x) <= Hull(x). The lines of a direction cross rows and diagonals at the same positions (the crossings
// depend on frac(u * slope) only), so the three point sets share one list of positions per direction
// (LinePattern) and the bound at each position is the largest of the three values there.
//
// Per texel T at position n (column u, row r, height z_T), with the hull holding the strip's points at
// least `reach` steps behind (the lagging hull of P1's far field; nearer points are the near field's):
// 1. the hull vertex q steepest from (n, z_T) (binary search): the peak of the bound's elevation;
// 2. T's ray is evaluated exactly (every column, row and diagonal crossing, heights of the triangulated
//    surface) at the column at or before q, then outwards one step (a band between two columns) at a time,
//    keeping the steepest point seen (dz, run);
// 3. each side stops when the hull's value at the frontier is not steeper than that point. The elevation
//    of a concave majorant seen from a point beyond it is unimodal in x (its superlevel sets
//    {x : Hull(x) + s x >= z_T + s n} are intervals), with its peak at q, so nothing beyond the frontier can
//    be steeper: the result is the exact steepest crossing of T's ray at distance >= reach, which the
//    exact march (tests/p1/p1_truth.hpp) finds. Axis and diagonal directions (slope 0, +-1) have every
//    texel on a line: T's ray is line l - 1, whose own lagging hull gives the caster exactly (step 1 only).
// The search is provably complete; its cost is the band count, which grows with how far the bound's peak
// lies above the ray's (the surface's relief across one texel). With a tolerance tau > 0 every "is beaten"
// test of steps 2 and 3 (and of the skip bounds) compares with the best slope plus tau instead, so the
// search stops as soon as nothing left can beat the best point by more than tau: the result is within tau
// of the exact slope, found by the same proof.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "field/height_field.hpp"
#include "methods/p1/horizon_sweep.hpp"
#include "methods/p1/hull_stack.hpp"
#include "sweep/sweep_lines.hpp"

namespace hfbake::p1 {

// Where every line of one direction meets the triangulation: entries (column samples and the row and
// diagonal crossings between them) in walk order, the same positions for every line l, each the point of
// an edge between two texels (a, b) at weight w of b. A texel's coordinates are its major coordinate
// (held as the array offset of that column or row: `major_*`) and its minor one, line index + d_*.
// Repeat mode: major coordinates and the d_* are wrapped into the field ([0, n) for d_a, [0, n] for d_b).
struct LinePattern {
  int k = -1;                  // the direction it was built for
  int u_start = 0, count = 0;  // ... and its line's first column and length (trimmed lines differ per line)
  std::vector<double> pos;     // steps from sample 0, increasing
  std::vector<std::int64_t> major_a, major_b;
  std::vector<std::int32_t> d_a, d_b;
  std::vector<float> w;
  std::vector<double> minor;          // minor coordinate of the point on line 0 (clamp: on-field test)
  std::vector<std::int32_t> first;    // count + 1: sample n's entry is first[n], its crossings follow
  std::vector<std::int32_t> strip_d;  // per sample: strip l's texel there has minor coordinate l + strip_d
  NearStencil near;                   // FarHorizonWorker::beat_near: the direction's near field

  void build(const HeightField& field, const SweepDirection& dir);
  std::size_t bytes() const;
};

// The sweep line visitor of P1's far field (see the header comment): on line l it writes, per receiver
// (column), strip l's texel's far caster [dz, run] (world units; run +inf: none, or the strip has no
// texel on the field there). compute_p1 reads them with SweepSpec::tile.strip.
struct FarHorizonWorker {
  const HeightField* field = nullptr;  // the field the sweep runs on
  double far_radius = 0;               // world units: the far field starts this far from the texel
  // Write a texel's far caster only where it is steeper than the texel's near field (near_slope over
  // near_field_stencil with radius near_radius_of(dir, far_radius / texel_size)), else none: the search
  // starts from the near field's slope and prunes everything below it. A texel's max(near, far) keeps its
  // bits: the start is lowered by 1e-6 (1 + m^2) in slope (about 1e-6 rad), more than fast_atan's error.
  bool beat_near = false;
  // The certified accuracy dial (P1Params::horizon_tolerance), a slope: the search stops once no unexamined
  // point can be steeper than the best one found by more than this. sin(atan(m)) is 1-Lipschitz in m, so
  // every texel's sin h is within the tolerance of (and never above) the exact one; 0: exact.
  double tolerance = 0;

  static constexpr int channels() { return 2; }
  void operator()(const SweepLine& line, float* out);

  // Statistics of the search (this worker's calls): texels searched and bands evaluated.
  std::uint64_t texels = 0, bands = 0;

  // Bytes one worker holds for a direction of `count` samples (the memory estimate).
  static std::size_t scratch_bytes(int count);

 private:
  LinePattern patterns_[2];
  int next_slot_ = 0;
  std::vector<float> prev_, cur_, bound_, texel_z_;  // line l - 1's and l's profiles, the strip's bound
  std::vector<int> texel_r_;                         // the strip's texel at each sample: minor coordinate
  std::vector<float> band_max_, block_max_;          // skip bounds: per band, per block of kBlock bands
  static constexpr int kBlock = 8;
  int last_k_ = -1, last_line_ = 0, last_u_start_ = 0;  // whose profile cur_ holds after a call
  // The heights the search works with are the field's less z_ref_ (the middle of its range, set at the
  // first call): their roundings are the relief's, not the heights' (a DEM 8000 m up rounds to 0.5 mm).
  float z_ref_ = 0;
  bool have_z_ref_ = false;
  HullStackF hull_;

  const LinePattern& pattern(const SweepDirection& dir);
  template <bool repeat>
  void search(const SweepLine& line, float* out);
  void profile(const LinePattern& pat, const SweepDirection& dir, int line, std::vector<float>& out) const;
};

}  // namespace hfbake::p1
