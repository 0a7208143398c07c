// How a raster too large for memory is baked in spatial tiles (docs/large-fields.md): each tile's interior
// is a window of the raster, baked from a copy of the heights grown by a halo on every side (clipped at the
// raster's border) and written back without the halo. A method whose every texel reads heights within a
// distance R of itself (MethodInfo::reach) gives, on a tile whose halo covers R, the texels of the whole
// bake; the halo adds the two texels the normals' and the facets' stencils read beyond a sample.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

namespace hfbake {

// A window of the raster: columns [x0, x0 + width), rows [y0, y0 + height).
struct RasterWindow {
  int x0 = 0, y0 = 0, width = 0, height = 0;
};

struct Tile {
  RasterWindow interior;  // what the tile writes
  RasterWindow read;      // what it bakes from: the interior grown by the halo, clipped to the raster
};

struct TilePlan {
  int width = 0, height = 0;  // the raster's
  int tile = 0;               // the interiors' side (those on the last column and row may be narrower)
  int halo = 0;               // texels read beyond an interior on each side
  int columns = 0, rows = 0;  // tiles across and down
  std::size_t kept_bytes =
      0;                    // held beside every tile while tiling (far fields' coarse copies of the raster)
  std::vector<Tile> tiles;  // row-major: tile (c, r) is tiles[r * columns + c]
};

// The halo that covers a reach of `reach` world units on texels of `texel_size`: ceil(reach / texel) + 2
// (the normals' and the facets' stencils); nullopt when the reach is not finite or beyond 2^20 texels.
std::optional<int> halo_texels(double reach, double texel_size);

// Interiors of side `tile` (>= 1) from the top-left corner, each read with `halo` (>= 0) texels around it.
TilePlan plan_tiles(int width, int height, int tile, int halo);

// The largest interior side, a multiple of `step` (or the raster's longer side when that is smaller), whose
// read window (side + 2 halo, square) `peak_bytes` says fits in `budget`; nullopt when not even `step` does.
// `peak_bytes(w, h)`: a bake's peak memory for a w x h field.
std::optional<int> tile_side_for_budget(int width, int height, int halo, std::size_t budget, int step,
                                        const std::function<std::size_t(int, int)>& peak_bytes);

}  // namespace hfbake
