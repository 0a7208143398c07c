// relief's quantities against independent truth: closed forms on planes and on a step (the triangulation
// represents both exactly), and on the 1 m lidar DEM a brute-force ray sampling written here from the
// reference's triangulation (docs/contract.md: the split from (i+1, j) to (i, j+1)) with 512 samples per
// texel of distance.
#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>

#include "methods/relief/relief.hpp"

namespace {
using namespace hfbake;
namespace fs = std::filesystem;
constexpr double kDeg = kPi / 180;

HeightField plane(int w, int h, double gx, double gy, double texel = 1) {
  HeightField f;
  f.width = w;
  f.height = h;
  f.texel_size = texel;
  f.z.resize(std::size_t(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) f.z[f.index(i, j)] = float(gx * i * texel + gy * j * texel);
  return f;
}

const Layer& layer(const LayerSet& s, const char* name) {
  const Layer* l = s.find(name);
  EXPECT_NE(l, nullptr) << name;
  return *l;
}

ReliefSettings settings(int K, double radius, bool compass = false) {
  ReliefSettings s;
  s.directions = K;
  s.search_radius = radius;
  s.compass = compass;
  s.layers = {"svf", "openness_positive", "openness_negative", "horizon_deg"};
  return s;
}

TEST(Relief, FlatFieldIsOpenAndLevel) {
  const LayerSet out = bake_relief(plane(21, 21, 0, 0), settings(16, 5), {});
  for (float v : layer(out, "svf").data) EXPECT_EQ(v, 1.0f);
  for (float v : layer(out, "openness_positive").data) EXPECT_EQ(v, 90.0f);
  for (float v : layer(out, "openness_negative").data) EXPECT_EQ(v, 90.0f);
  for (float v : layer(out, "horizon_deg").data) EXPECT_EQ(v, 0.0f);
}

// A plane z = g . (x, y): along (dx, dy) every point lies at elevation atan(g . d), whatever the radius.
TEST(Relief, PlanesMatchTheirClosedForm) {
  const double gx = 0.3, gy = -0.55, texel = 2.5;
  const int K = 12;
  const HeightField f = plane(41, 41, gx, gy, texel);
  for (bool compass : {false, true}) {
    const LayerSet out = bake_relief(f, settings(K, 7 * texel, compass), {});
    double svf = 0, up = 0;
    std::vector<double> beta(K);
    for (int k = 0; k < K; ++k) {
      const double a = 2 * kPi * k / K;
      // Independent statement of the directions: hfbake phi from +x to +y; compass A from north = -y.
      const double dx = compass ? std::sin(a) : std::cos(a), dy = compass ? -std::cos(a) : std::sin(a);
      beta[k] = std::atan(gx * dx + gy * dy);
      svf += std::sin(std::max(beta[k], 0.0));
      up += beta[k];
    }
    svf = 1 - svf / K;
    up /= K;
    const std::size_t t = f.index(20, 20);
    EXPECT_NEAR(layer(out, "svf").data[t], svf, 1e-6);
    EXPECT_NEAR(layer(out, "openness_positive").data[t], 90 - up / kDeg, 1e-4);
    EXPECT_NEAR(layer(out, "openness_negative").data[t], 90 + up / kDeg, 1e-4);
    for (int k = 0; k < K; ++k) EXPECT_NEAR(layer(out, "horizon_deg").data[t * K + k], beta[k] / kDeg, 1e-4);
  }
}

// A wall of height H rising at column 20 (the triangulated surface ramps up between columns 19 and 20).
// Seen from column 15 looking +x: the top edge at distance 5 is the horizon when the radius reaches it;
// with radius 4.5 the highest point within reach is the ramp's middle, H / 2 at distance 4.5.
TEST(Relief, SearchRadiusLimitsTheHorizon) {
  HeightField f = plane(40, 9, 0, 0);
  const double H = 3;
  for (int j = 0; j < 9; ++j)
    for (int i = 20; i < 40; ++i) f.z[f.index(i, j)] = float(H);
  const std::size_t t = f.index(15, 4);
  const LayerSet far = bake_relief(f, settings(4, 12), {});
  EXPECT_NEAR(layer(far, "horizon_deg").data[t * 4 + 0], std::atan(H / 5) / kDeg, 1e-4);
  EXPECT_NEAR(layer(far, "horizon_deg").data[t * 4 + 1], 0, 1e-6);  // +y: flat
  const LayerSet near = bake_relief(f, settings(4, 4.5), {});
  EXPECT_NEAR(layer(near, "horizon_deg").data[t * 4 + 0], std::atan(H / 2 / 4.5) / kDeg, 1e-4);
  const LayerSet none = bake_relief(f, settings(4, 3.9), {});
  EXPECT_NEAR(layer(none, "horizon_deg").data[t * 4 + 0], 0, 1e-6);
  // Negative openness at the wall's foot: looking +x every point is above, the lowest elevation is the
  // farthest top point's, atan(H / 12); the other three directions are level.
  EXPECT_NEAR(layer(far, "openness_negative").data[f.index(19, 4)], 90 + std::atan(H / 12) / kDeg / 4, 1e-4);
  EXPECT_NEAR(layer(far, "openness_negative").data[f.index(2, 4)], 90, 1e-6);
  // Compass, north-up: channel 1 looks east = +x.
  const LayerSet compass = bake_relief(f, settings(4, 12, true), {});
  EXPECT_NEAR(layer(compass, "horizon_deg").data[t * 4 + 1], std::atan(H / 5) / kDeg, 1e-4);
  EXPECT_NEAR(layer(compass, "horizon_deg").data[t * 4 + 0], 0, 1e-6);
}

// Repeat fields tile: a texel at the left edge sees the wall of the previous period.
TEST(Relief, RepeatFieldsSeeAcrossTheSeam) {
  HeightField f = plane(20, 5, 0, 0);
  f.wrap = Wrap::repeat;
  for (int j = 0; j < 5; ++j) f.z[f.index(17, j)] = 2;
  const LayerSet out = bake_relief(f, settings(4, 6), {});
  // From (1, 2) looking -x (k = 2): column 17 of the previous tile is 4 texels away.
  EXPECT_NEAR(layer(out, "horizon_deg").data[f.index(1, 2) * 4 + 2], std::atan(2.0 / 4) / kDeg, 1e-4);
}

// --- the lidar DEM against dense sampling -------------------------------------------------------------

// The triangulated surface of docs/contract.md at continuous texel coordinates, written out here: quad (i,
// j), the lower triangle (i, j), (i+1, j), (i, j+1) when fx + fy <= 1, else the upper (i+1, j+1), (i, j+1),
// (i+1, j).
double surface(const std::vector<float>& z, int w, double x, double y) {
  const int i = int(std::floor(x)), j = int(std::floor(y));
  const double fx = x - i, fy = y - j;
  auto h = [&](int a, int b) { return double(z[std::size_t(b) * w + a]); };
  if (fx + fy <= 1) return h(i, j) * (1 - fx - fy) + h(i + 1, j) * fx + h(i, j + 1) * fy;
  return h(i + 1, j + 1) * (fx + fy - 1) + h(i, j + 1) * (1 - fx) + h(i + 1, j) * (1 - fy);
}

TEST(Relief, LidarDemAgreesWithDenseRaySampling) {
  const fs::path dem = fs::path(HFBAKE_SHARED_DATA_DIR) / "TM1_564_146.tif";
  if (!fs::exists(dem)) GTEST_SKIP() << "no real DEM at " << dem << " (the shared data folder is absent)";
  GDALAllRegister();
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(dem.c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(ds) << dem;
  const int w = ds->GetRasterXSize(), h = ds->GetRasterYSize();
  double gt[6];
  ds->GetGeoTransform(gt);
  HeightField f;
  f.width = w;
  f.height = h;
  f.texel_size = gt[1];
  f.z.resize(std::size_t(w) * h);
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, w, h, f.z.data(), w, h, GDT_Float32, 0, 0, nullptr),
            CE_None);
  // A 1 m DEM: RVT's defaults, 16 directions within 10 px, in compass terms (north-up raster).
  const int K = 16;
  const double R = 10 * f.texel_size;
  // Interior texels only (the search never reaches the border): a 24 x 24 block and 300 scattered texels.
  std::vector<std::pair<int, int>> texels;
  for (int j = 500; j < 524; ++j)
    for (int i = 300; i < 324; ++i) texels.emplace_back(i, j);
  std::uint64_t s = 12345;
  for (int n = 0; n < 300; ++n) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    texels.emplace_back(12 + int((s >> 33) % std::uint64_t(w - 24)),
                        12 + int((s >> 13) % std::uint64_t(h - 24)));
  }
  // The whole DEM, as a user would bake it.
  const LayerSet out = bake_relief(f, settings(K, R, true), {});
  const int M = 10 * 512;  // samples per ray: 1/512 texel apart, the last exactly at R
  double worst_h = 0, worst_pos = 0, worst_neg = 0, worst_svf = 0;
  for (const auto& [i, j] : texels) {
    const double z0 = f.z[f.index(i, j)];
    double svf = 0, up_sum = 0, down_sum = 0;
    for (int k = 0; k < K; ++k) {
      const double a = 2 * kPi * k / K, dx = std::sin(a), dy = -std::cos(a);
      double up = -1e300, down = 1e300;
      for (int m = 1; m <= M; ++m) {
        const double d = R * m / M, x = i + d / f.texel_size * dx, y = j + d / f.texel_size * dy;
        const double slope = (surface(f.z, w, x, y) - z0) / d;
        up = std::max(up, slope);
        down = std::min(down, slope);
      }
      const double bu = std::atan(up), bd = std::atan(down);
      svf += std::sin(std::max(bu, 0.0));
      up_sum += bu;
      down_sum += bd;
      worst_h = std::max(worst_h, std::abs(out.find("horizon_deg")->data[f.index(i, j) * K + k] - bu / kDeg));
    }
    const std::size_t t = f.index(i, j);
    worst_svf = std::max(worst_svf, std::abs(out.find("svf")->data[t] - (1 - svf / K)));
    worst_pos =
        std::max(worst_pos, std::abs(out.find("openness_positive")->data[t] - (90 - up_sum / K / kDeg)));
    worst_neg =
        std::max(worst_neg, std::abs(out.find("openness_negative")->data[t] - (90 + down_sum / K / kDeg)));
  }
  // The bounds; the march is exact, so the differences are the sampling's (printed).
  EXPECT_LT(worst_h, 0.5);
  EXPECT_LT(worst_pos, 0.5);
  EXPECT_LT(worst_neg, 0.5);
  EXPECT_LT(worst_svf, 0.002);
  std::printf(
      "max |difference| over %zu texels: horizon %.4f deg, openness + %.4f deg, - %.4f deg, svf %.6f\n",
      texels.size(), worst_h, worst_pos, worst_neg, worst_svf);
}

}  // namespace
