// The height field: world-unit heights on a regular grid, the input of every method.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/vec.hpp"
#include "field/triangulation.hpp"

namespace hfbake {

enum class Wrap { clamp, repeat };

// What a field is without its heights: enough to check a method's parameters before anything is loaded
// (methods/method_table.hpp).
struct FieldShape {
  int width = 0, height = 0;
  double texel_size = 1.0;    // world units between texel centres along x (columns)
  double texel_size_y = 0.0;  // along y (rows); 0: texel_size (square texels)
  Wrap wrap = Wrap::clamp;

  // The texel's sides in world units: a geographic DEM's texels are rectangles (docs/gis.md "Geographic
  // DEMs"); every other field's are squares. Only the methods whose table entry says rectangular_texels,
  // and the reference, accept rectangles.
  double dx() const { return texel_size; }
  double dy() const { return texel_size_y > 0 ? texel_size_y : texel_size; }
  bool square_texels() const { return texel_size_y <= 0 || texel_size_y == texel_size; }
};

// Texel (i, j) has its center at world (i * dx(), j * dy(), z[j * width + i]).
// Heights are world units (height_scale and height_offset already applied). i: column, j: row.
struct HeightField : FieldShape {
  std::vector<float> z;

  std::size_t texel_count() const { return std::size_t(width) * std::size_t(height); }
  std::size_t index(int i, int j) const { return std::size_t(j) * std::size_t(width) + std::size_t(i); }

  // Wraps (repeat) or clamps (clamp) integer texel coordinates into the grid.
  int wrap_i(int i) const { return wrap == Wrap::repeat ? ((i % width) + width) % width : clampi(i, width); }
  int wrap_j(int j) const {
    return wrap == Wrap::repeat ? ((j % height) + height) % height : clampi(j, height);
  }
  float at(int i, int j) const { return z[index(wrap_i(i), wrap_j(j))]; }

  // Bilinear height at continuous texel coordinates (x, y) (x = i at texel centers).
  // Outside the grid: clamp mode extends the border heights, repeat mode tiles.
  float bilinear(double x, double y) const {
    const double fx = std::floor(x), fy = std::floor(y);
    const int i = int(fx), j = int(fy);
    const float tx = float(x - fx), ty = float(y - fy);
    const float h00 = at(i, j), h10 = at(i + 1, j), h01 = at(i, j + 1), h11 = at(i + 1, j + 1);
    return (h00 * (1 - tx) + h10 * tx) * (1 - ty) + (h01 * (1 - tx) + h11 * tx) * ty;
  }

  // Height of the triangulated surface the reference traces (field/triangulation.hpp) at continuous texel
  // coordinates; outside the grid like bilinear (clamped or tiled).
  float triangle_height(double x, double y) const {
    const double fx = std::floor(x), fy = std::floor(y);
    const int i = int(fx), j = int(fy);
    const float tx = float(x - fx), ty = float(y - fy);
    return facet_height(tx, ty, [&](int di, int dj) { return at(i + di, j + dj); });
  }

  Vec3 position(int i, int j) const { return {i * dx(), j * dy(), double(z[index(i, j)])}; }

 private:
  static int clampi(int v, int n) { return v < 0 ? 0 : (v >= n ? n - 1 : v); }
};

// Per-texel unit normals as P1 computes them: the sum of the unnormalised normals of the four quads
// around the texel (honouring texel size and wrap), normalised. Row-major like HeightField::z.
std::vector<Vec3f> compute_normals(const HeightField& field);
// The same normal of one texel (compute_normals is this at every texel): for methods that recompute
// normals from the heights instead of holding 12 bytes per texel (P1).
Vec3f normal_at(const HeightField& field, int i, int j);

}  // namespace hfbake
