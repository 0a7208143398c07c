// The tile plan: every texel of the raster is in exactly one interior for any size, tile and halo; each
// read window is the interior grown by the halo, clipped to the raster; the halo covers a reach; the
// budget's tile side is the largest multiple of the step that fits (checked against a linear search).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "farm/tile_plan.hpp"

namespace hfbake {
namespace {

TEST(TilePlan, InteriorsCoverTheRasterOnceAndReadsAddTheHalo) {
  for (const int width : {1, 7, 64, 129, 300})
    for (const int height : {1, 5, 64, 200})
      for (const int tile : {1, 16, 33, 64, 512})
        for (const int halo : {0, 3, 40}) {
          const TilePlan plan = plan_tiles(width, height, tile, halo);
          ASSERT_EQ(plan.tiles.size(), std::size_t(plan.columns) * std::size_t(plan.rows));
          std::vector<int> count(std::size_t(width) * std::size_t(height), 0);
          for (const Tile& t : plan.tiles) {
            const RasterWindow& in = t.interior;
            ASSERT_GE(in.width, 1);
            ASSERT_GE(in.height, 1);
            ASSERT_LE(in.width, tile);
            for (int j = in.y0; j < in.y0 + in.height; ++j)
              for (int i = in.x0; i < in.x0 + in.width; ++i)
                ++count[std::size_t(j) * std::size_t(width) + std::size_t(i)];
            const RasterWindow& r = t.read;
            EXPECT_EQ(r.x0, std::max(0, in.x0 - halo));
            EXPECT_EQ(r.y0, std::max(0, in.y0 - halo));
            EXPECT_EQ(r.x0 + r.width, std::min(width, in.x0 + in.width + halo));
            EXPECT_EQ(r.y0 + r.height, std::min(height, in.y0 + in.height + halo));
          }
          for (const int c : count) ASSERT_EQ(c, 1) << width << "x" << height << " tile " << tile;
        }
}

TEST(TilePlan, HaloCoversTheReachAndTheStencils) {
  EXPECT_EQ(halo_texels(0, 1), 2);
  EXPECT_EQ(halo_texels(10, 1), 12);
  EXPECT_EQ(halo_texels(10.5, 1), 13);
  EXPECT_EQ(halo_texels(10, 2), 7);
  EXPECT_EQ(halo_texels(INFINITY, 1), std::nullopt);
  EXPECT_EQ(halo_texels(NAN, 1), std::nullopt);
  EXPECT_EQ(halo_texels(1e9, 1), std::nullopt);
}

TEST(TilePlan, BudgetGivesTheLargestSideThatFits) {
  // A peak of 100 + 3 bytes a texel, searched by hand over every multiple of the step.
  auto peak = [](int w, int h) { return std::size_t(100) + 3 * std::size_t(w) * std::size_t(h); };
  for (const int width : {50, 1000, 3000})
    for (const int halo : {0, 12})
      for (const std::size_t budget :
           {std::size_t(50), std::size_t(100000), std::size_t(3000000), std::size_t(1) << 40}) {
        const std::optional<int> side = tile_side_for_budget(width, width / 2 + 1, halo, budget, 64, peak);
        std::optional<int> truth;
        auto fits = [&](int s) {
          return peak(std::min(width, s + 2 * halo), std::min(width / 2 + 1, s + 2 * halo)) <= budget;
        };
        if (fits(width))
          truth = width;
        else
          for (int s = 64; s < width && fits(s); s += 64) truth = s;
        EXPECT_EQ(side, truth) << width << " halo " << halo << " budget " << budget;
      }
}

}  // namespace
}  // namespace hfbake
