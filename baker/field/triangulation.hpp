// The height field's triangulation, the surface the reference traces and the sweeps sample (contract:
// "two triangles per quad, split along the diagonal from texel (i+1, j) to (i, j+1)", the split Embree's grid
// and quad geometry use). Every rule about which triangle a point lies on, its weights and its normal lives
// here; the methods, the reference and HeightField::triangle_height read it.
//
// Quad (i, j) spans texels (i, j) .. (i+1, j+1); a point in it has fractions (fx, fy) in [0, 1]^2.
//   facet 0, the lower triangle, fx + fy <= 1: (i, j), (i+1, j), (i, j+1)
//   facet 1, the upper triangle, fx + fy >  1: (i+1, j+1), (i, j+1), (i+1, j)
// Both have their right angle at their first corner. Texel-centred naming (P1, P2): facet 0 of texel (i, j)
// is the lower triangle of quad (i, j), facet 1 of texel (i, j) the upper triangle of quad (i-1, j-1), so
// each texel owns the two triangles with their right angle at it.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/vec.hpp"

namespace hfbake {

struct HeightField;

// Corner offsets (di, dj) from texel (i, j) of each facet of quad (i, j), in the order above (the order
// the reference's triangle mesh lists them: Embree's quad (v0 v1 v3) and (v2 v3 v1)).
inline constexpr int kFacetCorner[2][3][2] = {{{0, 0}, {1, 0}, {0, 1}}, {{1, 1}, {0, 1}, {1, 0}}};

// The facet of the quad that the point with fractions (fx, fy) lies on: 0 (lower) or 1 (upper). Points on
// the diagonal belong to the lower facet. T is the caller's precision (the test is evaluated in it).
template <class T>
inline int facet_of(T fx, T fy) {
  return fx + fy <= 1 ? 0 : 1;
}

// The height of the triangulated surface at fractions (tx, ty) of a quad whose corner heights at(di, dj)
// returns (di, dj in {0, 1}); only the three corners of the point's facet are read.
template <class T, class CornerHeight>
inline T facet_height(T tx, T ty, CornerHeight at) {
  if (facet_of(tx, ty) == 0) {
    const T h00 = at(0, 0);
    return h00 + (at(1, 0) - h00) * tx + (at(0, 1) - h00) * ty;
  }
  const T h11 = at(1, 1);
  return h11 + (at(0, 1) - h11) * (1 - tx) + (at(1, 0) - h11) * (1 - ty);
}

// Barycentric weights of the point with fractions (fx, fy) in its facet: weight w[c] belongs to the corner
// (i + di[c], j + dj[c]). Lower facet: (i, j), (i+1, j), (i, j+1); upper facet: (i+1, j), (i+1, j+1),
// (i, j+1) (the order a weighted sum over the corners runs in).
struct FacetWeights {
  int facet = 0;
  int di[3] = {0, 0, 0}, dj[3] = {0, 0, 0};
  double w[3] = {0, 0, 0};
};
// The corners (di, dj) of each facet in facet_weights' order.
inline constexpr int kWeightCorner[2][3][2] = {{{0, 0}, {1, 0}, {0, 1}}, {{1, 0}, {1, 1}, {0, 1}}};
// The weights of the point with fractions (fx, fy) at facet q's corners (kWeightCorner), the point taken as
// lying on facet q (a point beside it gets the facet's plane extended).
inline void facet_corner_weights(int q, double fx, double fy, double w[3]) {
  if (q == 0)
    w[0] = 1 - fx - fy, w[1] = fx, w[2] = fy;
  else
    w[0] = 1 - fy, w[1] = fx + fy - 1, w[2] = 1 - fx;
}
inline FacetWeights facet_weights(double fx, double fy) {
  FacetWeights r;
  r.facet = facet_of(fx, fy);
  for (int c = 0; c < 3; ++c) r.di[c] = kWeightCorner[r.facet][c][0], r.dj[c] = kWeightCorner[r.facet][c][1];
  facet_corner_weights(r.facet, fx, fy, r.w);
  return r;
}

// The horizontal distance from the point with fractions (fx, fy) of a quad of sides sx x sy to the nearest
// edge of the triangulation: the quad's four sides and its split diagonal.
inline double facet_edge_distance(double fx, double fy, double sx, double sy) {
  return std::min({fx * sx, (1 - fx) * sx, fy * sy, (1 - fy) * sy,
                   std::fabs(fx + fy - 1) * sx * sy / std::hypot(sx, sy)});
}

// The facet under the point (x, y) in texel coordinates (not wrapped), named texel-centred: facet q of
// texel (i, j) (see the top of this file).
struct FacetRef {
  int i = 0, j = 0, q = 0;
  bool operator==(const FacetRef&) const = default;
};
inline FacetRef facet_under(double x, double y) {
  const int i = floor_int(x), j = floor_int(y);
  const int q = facet_of((x - i), (y - j));
  return {i + q, j + q, q};
}

// The unit normals of texel (i, j)'s two facets (texel-centred): [0] the triangle (i, j), (i+1, j),
// (i, j+1) from forward differences, [1] the triangle (i, j), (i-1, j), (i, j-1) from backward differences.
// Neighbours are read with HeightField::at: at a clamp border the missing neighbour is the texel itself.
void facet_normals(const HeightField& field, int i, int j, Vec3f out[2]);

// The six facets that meet at texel (i, j), its corner facets, texel-centred: c = 0 and 1 the texel's own
// facets 0 and 1, c = 2 facet 0 of (i-1, j), c = 3 facet 0 of (i, j-1), c = 4 facet 1 of (i+1, j), c = 5
// facet 1 of (i, j+1). Light that varies over a facet is carried by its three corners' values (the value
// at each corner, as albedo and emission are), interpolated as the reference interpolates them.
inline constexpr int kCornerFacets = 6;
struct CornerFacet {
  int di, dj, q;  // the facet: facet q of texel (i + di, j + dj)
};
inline constexpr CornerFacet kCornerFacet[kCornerFacets] = {{0, 0, 0},  {0, 0, 1}, {-1, 0, 0},
                                                            {0, -1, 0}, {1, 0, 1}, {0, 1, 1}};
// The corner facet c of texel (i, j) that is facet q of texel (i + di, j + dj); -1 when that facet does not
// meet the texel.
inline int corner_facet_index(int di, int dj, int q) {
  for (int c = 0; c < kCornerFacets; ++c)
    if (kCornerFacet[c].di == di && kCornerFacet[c].dj == dj && kCornerFacet[c].q == q) return c;
  return -1;
}
// For corner k of facet_weights' list (FacetWeights::di[k], dj[k] from the quad's origin): which corner
// facet of that corner's texel the point's facet is. Lower facet: (i, j) 0, (i+1, j) 2, (i, j+1) 3; upper
// facet: (i+1, j) 5, (i+1, j+1) 1, (i, j+1) 4.
inline constexpr int kWeightCornerFacet[2][3] = {{0, 2, 3}, {5, 1, 4}};
// The unit normals of texel (i, j)'s corner facets, in kCornerFacet's order; [0] and [1] are
// facet_normals' (the same values). Neighbours are read as facet_normals reads them.
void corner_facet_normals(const HeightField& field, int i, int j, Vec3f out[kCornerFacets]);

}  // namespace hfbake
