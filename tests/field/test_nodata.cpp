#include <gtest/gtest.h>

#include <cmath>

#include "field/nodata.hpp"
#include "field/procedural.hpp"

namespace hfbake {
namespace {

TEST(Nodata, ScanFindsNanInfAndNodataValue) {
  HeightField f;
  f.width = 4;
  f.height = 3;
  f.z.assign(12, 1.0f);
  f.z[f.index(2, 1)] = NAN;
  f.z[f.index(3, 2)] = INFINITY;
  f.z[f.index(0, 2)] = -9999.0f;
  NodataScan s = scan_nodata(f, std::nullopt);
  EXPECT_EQ(s.count, 2u);
  EXPECT_EQ(s.first_i, 2);
  EXPECT_EQ(s.first_j, 1);
  s = scan_nodata(f, -9999.0f);
  EXPECT_EQ(s.count, 3u);
}

TEST(Nodata, FillReproducesAPlaneInsideHoles) {
  // Holes in a plane: every fill value is a mean of plane samples around it; on a plane the 8-neighbour
  // mean of a symmetric ring is exact, and in general stays within the hole rim's height range.
  ProceduralSpec s;
  s.kind = ProceduralKind::slope;
  s.width = s.height = 40;
  s.angle_deg = 20;
  HeightField f = make_procedural(s, 1.0, Wrap::clamp);
  const HeightField truth = f;
  for (int j = 10; j < 14; ++j)
    for (int i = 20; i < 26; ++i) f.z[f.index(i, j)] = NAN;
  f.z[f.index(0, 0)] = NAN;  // a corner hole
  ASSERT_TRUE(fill_nodata(f, std::nullopt));
  EXPECT_EQ(scan_nodata(f, std::nullopt).count, 0u);
  for (int j = 8; j < 16; ++j)
    for (int i = 18; i < 28; ++i) EXPECT_NEAR(f.z[f.index(i, j)], truth.z[truth.index(i, j)], 2.0);
  // A texel surrounded by valid ones gets exactly their mean: the plane value (symmetric ring).
  HeightField g = truth;
  g.z[g.index(30, 30)] = NAN;
  ASSERT_TRUE(fill_nodata(g, std::nullopt));
  EXPECT_NEAR(g.z[g.index(30, 30)], truth.z[truth.index(30, 30)], 1e-4);
}

TEST(Nodata, AllMissingCannotBeFilled) {
  HeightField f;
  f.width = f.height = 3;
  f.z.assign(9, NAN);
  EXPECT_FALSE(fill_nodata(f, std::nullopt));
}

}  // namespace
}  // namespace hfbake
