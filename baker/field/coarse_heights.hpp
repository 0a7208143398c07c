// A coarsened copy of a height field: square cells of C x C texels, each holding the highest and the lowest
// height of the texels on and inside its border (the max/min pyramid level of HORAYZON's distant-terrain
// simplification, Steger et al. 2022). Cell (cx, cy) covers texel coordinates [cx C, (cx + 1) C] x
// [cy C, (cy + 1) C] and holds the texels with cx C <= x <= (cx + 1) C and cy C <= y <= (cy + 1) C, so
// neighbouring cells share their border texels and the triangulated surface (field/triangulation.hpp:
// each facet's heights are a convex combination of its corners') lies between the cell's low and high
// everywhere on that square. Clamp fields: ceil((n - 1) / C) cells along an axis of n texels (at least one),
// the last one clipped at the border; repeat fields: n / C cells, C dividing n, the last one holding the
// texels of column (row) 0 as its far border. Built from the heights a run of rows at a time, so a raster
// larger than memory is coarsened by windowed reads (docs/large-fields.md).
#pragma once

#include <cstddef>
#include <vector>

#include "field/height_field.hpp"

namespace hfbake {

struct CoarseHeights {
  int cell = 1;               // C: texels along a cell's side
  int width = 0, height = 0;  // the field's texels
  Wrap wrap = Wrap::clamp;
  int columns = 0, rows = 0;     // cells
  std::vector<float> high, low;  // per cell, row-major (columns x rows)

  std::size_t index(int cx, int cy) const { return std::size_t(cy) * std::size_t(columns) + std::size_t(cx); }
};

// The number of cells along an axis of n texels (see above).
int coarse_cells(int n, int cell, Wrap wrap);

// Bytes a coarse copy of a width x height field holds.
double coarse_bytes(int width, int height, int cell);

// A copy with no heights yet (high -inf, low +inf): add_coarse_rows fills it. On repeat fields `cell`
// must divide width and height (the reader checks it).
CoarseHeights empty_coarse(int width, int height, int cell, Wrap wrap);

// Adds rows [y0, y0 + n) of the field, `z` holding them row-major, `width` texels each.
void add_coarse_rows(CoarseHeights& g, const float* z, int y0, int n);

// The coarse copy of a whole field.
CoarseHeights coarse_heights(const HeightField& field, int cell);

}  // namespace hfbake
