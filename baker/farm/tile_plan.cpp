#include "farm/tile_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace hfbake {

std::optional<int> halo_texels(double reach, double texel_size) {
  if (!(reach >= 0) || !(texel_size > 0)) return std::nullopt;
  const double texels = std::ceil(reach / texel_size);
  if (!(texels <= double(1 << 20))) return std::nullopt;
  return int(texels) + 2;
}

TilePlan plan_tiles(int width, int height, int tile, int halo) {
  if (width < 1 || height < 1 || tile < 1 || halo < 0) throw std::logic_error("plan_tiles: bad arguments");
  TilePlan plan;
  plan.width = width;
  plan.height = height;
  plan.tile = tile;
  plan.halo = halo;
  plan.columns = int((std::int64_t(width) + tile - 1) / tile);
  plan.rows = int((std::int64_t(height) + tile - 1) / tile);
  plan.tiles.reserve(std::size_t(plan.columns) * std::size_t(plan.rows));
  for (int r = 0; r < plan.rows; ++r)
    for (int c = 0; c < plan.columns; ++c) {
      Tile t;
      t.interior.x0 = c * tile;
      t.interior.y0 = r * tile;
      t.interior.width = std::min(tile, width - t.interior.x0);
      t.interior.height = std::min(tile, height - t.interior.y0);
      const int x0 = std::max(0, t.interior.x0 - halo), y0 = std::max(0, t.interior.y0 - halo);
      const int x1 =
          int(std::min<std::int64_t>(width, std::int64_t(t.interior.x0) + t.interior.width + halo));
      const int y1 =
          int(std::min<std::int64_t>(height, std::int64_t(t.interior.y0) + t.interior.height + halo));
      t.read = {x0, y0, x1 - x0, y1 - y0};
      plan.tiles.push_back(t);
    }
  return plan;
}

std::optional<int> tile_side_for_budget(int width, int height, int halo, std::size_t budget, int step,
                                        const std::function<std::size_t(int, int)>& peak_bytes) {
  const int longest = std::max(width, height);
  auto fits = [&](int side) {
    const int w = int(std::min<std::int64_t>(width, std::int64_t(side) + 2 * std::int64_t(halo)));
    const int h = int(std::min<std::int64_t>(height, std::int64_t(side) + 2 * std::int64_t(halo)));
    return peak_bytes(w, h) <= budget;
  };
  if (fits(longest)) return longest;
  if (step < 1 || !fits(std::min(step, longest))) return std::nullopt;
  // The peak grows with the side: bisect on multiples of step.
  int lo = 1, hi = (longest + step - 1) / step;  // fits(lo * step), !fits(hi * step)
  while (hi - lo > 1) {
    const int mid = lo + (hi - lo) / 2;
    (fits(mid * step) ? lo : hi) = mid;
  }
  return lo * step;
}

}  // namespace hfbake
