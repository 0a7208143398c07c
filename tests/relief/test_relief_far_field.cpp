// relief's far field (radius_horizon.hpp FarField) against the exact march out to the whole search radius
// (radius_horizon without a far field, itself checked against closed forms and a dense sampling in
// test_relief.cpp): on families of fields, clamp and repeat, square and rectangular texels, several
// distances and cell sizes, with and without the Earth's curvature, every ray's up is at least the exact
// one and at most the exact one plus the bound docs/gis.md states, (h + G L) / D + c L; the ray's own
// slack brackets the exact value; the bake's svf and openness move only the way and as far as the bound
// allows. The coarse copy itself against a brute-force max/min over each cell's texels.
#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "core/error.hpp"
#include "field/coarse_heights.hpp"
#include "field/procedural.hpp"
#include "job/params.hpp"
#include "methods/relief/relief.hpp"

namespace {
using namespace hfbake;
namespace fs = std::filesystem;
constexpr double kEps = 1e-9;

HeightField field_of(ProceduralKind kind, int w, int h, Wrap wrap, double dy = 0) {
  ProceduralSpec spec;
  spec.kind = kind;
  spec.width = w;
  spec.height = h;
  spec.seed = 7;
  HeightField f = make_procedural(spec, 1.0, wrap);
  f.texel_size_y = dy;
  return f;
}

// The largest height range of a cell, written from the definition: texels cx C .. (cx + 1) C (wrapped on
// repeat fields, clipped on clamp fields) and the same rows.
double largest_cell_range(const HeightField& f, int C) {
  double worst = 0;
  const bool rep = f.wrap == Wrap::repeat;
  const int nx = rep ? f.width / C : std::max(1, (f.width - 2) / C + 1);
  const int ny = rep ? f.height / C : std::max(1, (f.height - 2) / C + 1);
  for (int cy = 0; cy < ny; ++cy)
    for (int cx = 0; cx < nx; ++cx) {
      double lo = 1e300, hi = -1e300;
      for (int y = cy * C; y <= (cy + 1) * C; ++y)
        for (int x = cx * C; x <= (cx + 1) * C; ++x) {
          if (!rep && (x >= f.width || y >= f.height)) continue;
          const double z = f.at(x, y);
          lo = std::min(lo, z);
          hi = std::max(hi, z);
        }
      worst = std::max(worst, hi - lo);
    }
  return worst;
}

struct Worst {
  double up = 0, down = 0, bound_used = 0;  // largest errors, and the largest error / bound
};

// Every checked ray of `f`: exact <= far <= exact + bound for up, the mirror for down, the slack
// bracketing the exact value.
void check_rays(const HeightField& f, double R, double D, int C, double c, int K, int step, Worst& w) {
  const CoarseHeights g = coarse_heights(f, C);
  const FarField far{&g, D};
  const double h = largest_cell_range(f, C), L = C * std::hypot(f.dx(), f.dy());
  for (int j = 0; j < f.height; j += step)
    for (int i = 0; i < f.width; i += step)
      for (int k = 0; k < K; ++k) {
        const double a = 2 * kPi * (k + 0.37) / K, ux = std::cos(a), uy = std::sin(a);
        const HorizonPair e = radius_horizon(f, i, j, ux, uy, R, c);
        const HorizonPair r = radius_horizon(f, i, j, ux, uy, R, c, far);
        ASSERT_EQ(e.any, r.any);
        if (!e.any) continue;
        const double G = std::max({0.0, e.up + c * R, -e.down});
        const double bound = (h + G * L) / D + c * L;
        SCOPED_TRACE(::testing::Message() << "texel " << i << "," << j << " k " << k);
        ASSERT_GE(r.up, e.up - kEps);
        ASSERT_LE(r.up, e.up + bound + kEps);
        ASSERT_LE(r.down, e.down + kEps);
        ASSERT_GE(r.down, e.down - bound - kEps);
        // The slack brackets the exact value and is itself within the bound.
        ASSERT_LE(r.up - r.up_slack, e.up + kEps);
        ASSERT_GE(r.down + r.down_slack, e.down - kEps);
        ASSERT_LE(std::max(r.up_slack, r.down_slack), bound + kEps);
        w.up = std::max(w.up, r.up - e.up);
        w.down = std::max(w.down, e.down - r.down);
        if (bound > 0) w.bound_used = std::max(w.bound_used, std::max(r.up - e.up, e.down - r.down) / bound);
      }
}

TEST(ReliefFarField, CoarseCellsHoldTheirTexelsExtremes) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat})
    for (auto [w, h, C] : {std::tuple{33, 20, 8}, std::tuple{40, 24, 8}, std::tuple{17, 16, 4},
                           std::tuple{12, 12, 12}, std::tuple{9, 5, 1}}) {
      if (wrap == Wrap::repeat && (w % C || h % C)) continue;
      const HeightField f = field_of(ProceduralKind::rough, w, h, wrap);
      const CoarseHeights g = coarse_heights(f, C);
      const bool rep = wrap == Wrap::repeat;
      SCOPED_TRACE(::testing::Message() << w << "x" << h << " C " << C << (rep ? " repeat" : " clamp"));
      ASSERT_EQ(g.columns, rep ? w / C : std::max(1, (w - 2) / C + 1));
      ASSERT_EQ(g.rows, rep ? h / C : std::max(1, (h - 2) / C + 1));
      for (int cy = 0; cy < g.rows; ++cy)
        for (int cx = 0; cx < g.columns; ++cx) {
          float lo = INFINITY, hi = -INFINITY;
          for (int y = cy * C; y <= (cy + 1) * C; ++y)
            for (int x = cx * C; x <= (cx + 1) * C; ++x) {
              if (!rep && (x >= w || y >= h)) continue;
              lo = std::min(lo, f.at(x, y));
              hi = std::max(hi, f.at(x, y));
            }
          EXPECT_EQ(g.high[g.index(cx, cy)], hi) << cx << "," << cy;
          EXPECT_EQ(g.low[g.index(cx, cy)], lo) << cx << "," << cy;
        }
      // Rows added in runs of any length give the same copy.
      CoarseHeights parts = empty_coarse(w, h, C, wrap);
      for (int y = 0; y < h; y += 3)
        add_coarse_rows(parts, f.z.data() + std::size_t(y) * w, y, std::min(3, h - y));
      EXPECT_EQ(parts.high, g.high);
      EXPECT_EQ(parts.low, g.low);
    }
}

// The bound on families of fields, clamp and repeat, several D and C, curvature off and on.
TEST(ReliefFarField, HorizonsStayWithinTheBoundOfTheExactMarch) {
  const int K = 12;
  for (ProceduralKind kind : {ProceduralKind::fractal, ProceduralKind::rough, ProceduralKind::terraces,
                              ProceduralKind::sines, ProceduralKind::craters})
    for (Wrap wrap : {Wrap::clamp, Wrap::repeat})
      for (double dy : {0.0, 1.7}) {
        const HeightField f = field_of(kind, 96, 64, wrap, dy);
        for (auto [D, C] : {std::pair{6.0, 4}, std::pair{6.0, 8}, std::pair{15.0, 8}, std::pair{15.0, 16}})
          for (double c : {0.0, 2e-3}) {
            SCOPED_TRACE(::testing::Message()
                         << procedural_kind_name(kind) << (wrap == Wrap::repeat ? " repeat" : " clamp")
                         << " dy " << dy << " D " << D << " C " << C << " c " << c);
            Worst w;
            check_rays(f, 45, D, C, c, K, 7, w);
            if (HasFatalFailure()) return;
            EXPECT_LE(w.bound_used, 1.0);
          }
      }
}

// A plateau of height H from column 40 on a flat field (the triangulation ramps between columns 39 and
// 40), coarse cells of 8 texels, far field beyond 10: the walk's values in closed form.
TEST(ReliefFarField, PlateauEdgeInClosedForm) {
  const double H = 6;
  HeightField f;
  f.width = 90;
  f.height = 40;
  f.z.resize(std::size_t(f.width) * f.height);
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) f.z[f.index(i, j)] = i >= 40 ? float(H) : 0.0f;
  const CoarseHeights g = coarse_heights(f, 8);
  const FarField far{&g, 10};
  // From (10, 20) towards +x: the exact horizon is the plateau's edge at 30; the far field takes cell
  // [32, 40] (which holds the edge's texels) from its near side at 22. The largest lower bound is cell
  // [40, 48]'s, all at H, from its far side at 38.
  const HorizonPair up_e = radius_horizon(f, 10, 20, 1, 0, 60),
                    up_f = radius_horizon(f, 10, 20, 1, 0, 60, 0, far);
  EXPECT_DOUBLE_EQ(up_e.up, H / 30);
  EXPECT_DOUBLE_EQ(up_f.up, H / 22);
  EXPECT_DOUBLE_EQ(up_f.up_slack, H / 22 - H / 38);
  EXPECT_DOUBLE_EQ(up_f.down, 0);
  // From (70, 20) towards -x, on the plateau: nothing rises (up 0 both ways); the lowest point is the foot
  // of the edge at 31, the far field's the cell [32, 40] entered at 30.
  const HorizonPair dn_e = radius_horizon(f, 70, 20, -1, 0, 60),
                    dn_f = radius_horizon(f, 70, 20, -1, 0, 60, 0, far);
  EXPECT_DOUBLE_EQ(dn_e.up, 0);
  EXPECT_DOUBLE_EQ(dn_f.up, 0);
  EXPECT_DOUBLE_EQ(dn_e.down, -H / 31);
  EXPECT_DOUBLE_EQ(dn_f.down, -H / 30);
  // Towards +x to the clamp border 19 texels away, beyond 10: the far walk ends there too.
  const HorizonPair b_e = radius_horizon(f, 70, 20, 1, 0, 60),
                    b_f = radius_horizon(f, 70, 20, 1, 0, 60, 0, far);
  EXPECT_EQ(b_e.up, 0);
  EXPECT_EQ(b_f.up, 0);
  EXPECT_EQ(b_f.down, 0);
}

const Layer& layer(const LayerSet& s, const char* name) {
  const Layer* l = s.find(name);
  EXPECT_NE(l, nullptr) << name;
  return *l;
}

double attribute(const LayerSet& s, const std::string& name) {
  for (const auto& [k, v] : s.attributes)
    if (k == name) return std::stod(v);
  ADD_FAILURE() << name;
  return 0;
}

// The bake's layers move only the way the far field moves the horizons, within the bound it records.
TEST(ReliefFarField, BakedLayersStayWithinTheRecordedBound) {
  for (ProceduralKind kind : {ProceduralKind::fractal, ProceduralKind::craters, ProceduralKind::terraces})
    for (double c : {0.0, 2e-3}) {
      const HeightField f = field_of(kind, 72, 72, Wrap::clamp);
      ReliefSettings s;
      s.directions = 8;
      s.search_radius = 40;
      s.layers = {"svf", "openness_positive", "openness_negative", "horizon_deg"};
      const LayerSet exact = bake_relief(f, s, {}, c);
      s.far_field = FarFieldSpec{8, 8};
      const LayerSet far = bake_relief(f, s, {}, c);
      const double bound = attribute(far, "hfbake:relief:far_field_bound");
      const double deg = std::atan(bound) * 180 / kPi;
      EXPECT_GT(bound, 0);
      const auto &se = layer(exact, "svf").data, &sf = layer(far, "svf").data;
      const auto &pe = layer(exact, "openness_positive").data, &pf = layer(far, "openness_positive").data;
      const auto &ne = layer(exact, "openness_negative").data, &nf = layer(far, "openness_negative").data;
      const auto &he = layer(exact, "horizon_deg").data, &hf = layer(far, "horizon_deg").data;
      for (std::size_t t = 0; t < se.size(); ++t) {
        ASSERT_LE(sf[t], se[t] + 1e-6);
        ASSERT_GE(sf[t], se[t] - bound - 1e-6);
        ASSERT_LE(pf[t], pe[t] + 1e-4);
        ASSERT_GE(pf[t], pe[t] - deg - 1e-4);
        ASSERT_LE(nf[t], ne[t] + 1e-4);
        ASSERT_GE(nf[t], ne[t] - deg - 1e-4);
      }
      for (std::size_t t = 0; t < he.size(); ++t) {
        ASSERT_GE(hf[t], he[t] - 1e-4);
        ASSERT_LE(hf[t], he[t] + deg + 1e-4);
      }
    }
}

// The reader: defaults, and one-line refusals naming far_field's key.
TEST(ReliefFarField, ReaderDefaultsAndRefusals) {
  FieldShape shape;
  shape.width = shape.height = 512;
  shape.texel_size = 2;
  auto read = [&](const nlohmann::json& j, const FieldShape& fs) {
    Params p(j, "job.json", "/bake/0");
    return read_relief_settings(p, fs);
  };
  const ReliefSettings d = read({{"search_radius", 1000}, {"far_field", nlohmann::json::object()}}, shape);
  ASSERT_TRUE(d.far_field);
  EXPECT_EQ(d.far_field->beyond, 200);  // 100 texels
  EXPECT_EQ(d.far_field->cell, 8);
  EXPECT_FALSE(read({{"search_radius", 1000}}, shape).far_field);
  auto where = [&](const nlohmann::json& j, const FieldShape& fs) {
    try {
      read(j, fs);
    } catch (const InputError& e) {
      return e.where();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(where({{"far_field", {{"beyond", 30}}}}, shape), "/bake/0/far_field/beyond");  // radius 20
  EXPECT_EQ(where({{"search_radius", 100}, {"far_field", {{"beyond", 1}}}}, shape),
            "/bake/0/far_field/beyond");
  EXPECT_EQ(where({{"search_radius", 100}, {"far_field", {{"beyond", 10}, {"cell", 0}}}}, shape),
            "/bake/0/far_field/cell");
  EXPECT_EQ(where({{"search_radius", 100}, {"far_field", 3}}, shape), "/bake/0/far_field");
  FieldShape rep = shape;
  rep.wrap = Wrap::repeat;
  rep.width = 500;
  EXPECT_EQ(where({{"search_radius", 100}, {"far_field", {{"beyond", 10}, {"cell", 8}}}}, rep),
            "/bake/0/far_field/cell");
  EXPECT_EQ(where({{"search_radius", 100}, {"far_field", {{"beyond", 10}, {"cell", 4}}}}, rep), "accepted");
}

// The 1 m lidar tile: scattered receivers, K = 16, a 400 m radius, curvature off and on.
TEST(ReliefFarField, LidarTileWithinTheBound) {
  const fs::path dem = fs::path(HFBAKE_SHARED_DATA_DIR) / "TM1_564_146.tif";
  if (!fs::exists(dem)) GTEST_SKIP() << dem << " is absent (HFBAKE_SHARED_DATA_DIR)";
  GDALAllRegister();
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(dem.c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(ds) << dem;
  HeightField f;
  f.width = ds->GetRasterXSize();
  f.height = ds->GetRasterYSize();
  double gt[6];
  ds->GetGeoTransform(gt);
  f.texel_size = gt[1];
  f.z.resize(std::size_t(f.width) * f.height);
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, f.width, f.height, f.z.data(), f.width, f.height,
                                           GDT_Float32, 0, 0, nullptr),
            CE_None);
  const int K = 16;
  const double R = 400, c = (1 - 0.13) / (2 * 6371000.0);
  for (auto [D, C] : {std::pair{50.0, 8}, std::pair{100.0, 8}, std::pair{100.0, 16}})
    for (double curv : {0.0, c}) {
      SCOPED_TRACE(::testing::Message() << "D " << D << " C " << C << " c " << curv);
      Worst w;
      check_rays(f, R, D, C, curv, K, 37, w);
      if (HasFatalFailure()) return;
      std::printf("lidar D %g C %d c %g: largest error up %.5f down %.5f (tangent), %.0f %% of the bound\n",
                  D, C, curv, w.up, w.down, 100 * w.bound_used);
    }
}

}  // namespace
