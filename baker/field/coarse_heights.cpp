#include "field/coarse_heights.hpp"

#include <algorithm>
#include <limits>

namespace hfbake {

namespace {

// The cells along an axis that hold texel x: x / C, and x / C - 1 when x lies on their shared border
// (wrapped on repeat fields, clipped to [0, cells) on clamp fields). Returns how many (1 or 2).
int cells_of(int x, int cell, int cells, Wrap wrap, int out[2]) {
  int n = 0;
  const int c = x / cell;
  auto put = [&](int k) {
    if (wrap == Wrap::repeat)
      out[n++] = (k % cells + cells) % cells;
    else if (k >= 0 && k < cells)
      out[n++] = k;
  };
  put(c);
  if (x % cell == 0) put(c - 1);
  if (n == 2 && out[0] == out[1]) n = 1;
  return n;
}

}  // namespace

int coarse_cells(int n, int cell, Wrap wrap) {
  if (wrap == Wrap::repeat) return std::max(1, n / cell);
  return std::max(1, (n - 1 + cell - 1) / cell);
}

double coarse_bytes(int width, int height, int cell) {
  return double(coarse_cells(width, cell, Wrap::clamp)) * double(coarse_cells(height, cell, Wrap::clamp)) *
         2 * sizeof(float);
}

CoarseHeights empty_coarse(int width, int height, int cell, Wrap wrap) {
  CoarseHeights g;
  g.cell = cell;
  g.width = width;
  g.height = height;
  g.wrap = wrap;
  g.columns = coarse_cells(width, cell, wrap);
  g.rows = coarse_cells(height, cell, wrap);
  const std::size_t n = std::size_t(g.columns) * std::size_t(g.rows);
  g.high.assign(n, -std::numeric_limits<float>::infinity());
  g.low.assign(n, std::numeric_limits<float>::infinity());
  return g;
}

void add_coarse_rows(CoarseHeights& g, const float* z, int y0, int n) {
  // One row's extremes per cell column first (cell c: texels c C .. (c + 1) C, the far border wrapping to
  // column 0 on a repeat field's last cell), then into the one or two cell rows that hold the row.
  std::vector<float> hi(std::size_t(g.columns)), lo(std::size_t(g.columns));
  for (int r = 0; r < n; ++r) {
    const float* row = z + std::size_t(r) * std::size_t(g.width);
    for (int c = 0; c < g.columns; ++c) {
      const int x0 = c * g.cell, x1 = std::min((c + 1) * g.cell, g.width - 1);
      float h = row[x0], l = row[x0];
      for (int x = x0 + 1; x <= x1; ++x) h = std::max(h, row[x]), l = std::min(l, row[x]);
      if (g.wrap == Wrap::repeat && (c + 1) * g.cell == g.width)
        h = std::max(h, row[0]), l = std::min(l, row[0]);
      hi[std::size_t(c)] = h, lo[std::size_t(c)] = l;
    }
    int cy[2];
    const int m = cells_of(y0 + r, g.cell, g.rows, g.wrap, cy);
    for (int a = 0; a < m; ++a)
      for (int c = 0; c < g.columns; ++c) {
        const std::size_t k = g.index(c, cy[a]);
        g.high[k] = std::max(g.high[k], hi[std::size_t(c)]);
        g.low[k] = std::min(g.low[k], lo[std::size_t(c)]);
      }
  }
}

CoarseHeights coarse_heights(const HeightField& field, int cell) {
  CoarseHeights g = empty_coarse(field.width, field.height, cell, field.wrap);
  add_coarse_rows(g, field.z.data(), 0, field.height);
  return g;
}

}  // namespace hfbake
