// The GDAL height reader and the Cloud-Optimised GeoTIFF writer, checked against GDAL's own command-line
// tools: `gdalinfo -json` of the real lidar DEM (../shared/data) and of what hfbake writes.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <vector>

#include "core/error.hpp"
#include "gdal_tool.hpp"
#include "io/georaster_input.hpp"
#include "io/geotiff_output.hpp"
#include "temp_folder.hpp"

namespace hfbake {
namespace {
namespace fs = std::filesystem;
using test::gdalinfo_json;
using test::TempFolder;

const fs::path kData = HFBAKE_SHARED_DATA_DIR;

#define REQUIRE_DATA_AND_TOOLS()                                                                   \
  do {                                                                                             \
    if (!fs::exists(kData / "TM1_564_146.tif"))                                                    \
      GTEST_SKIP() << "no real DEM in " << kData << " (the shared data folder is absent)";         \
    if (!test::have_gdal_tools()) GTEST_SKIP() << "gdalinfo not found (apt-get install gdal-bin)"; \
  } while (0)

bool same_crs(const std::string& wkt_a, const std::string& wkt_b) {
  OGRSpatialReference a, b;
  if (a.importFromWkt(wkt_a.c_str()) != OGRERR_NONE || b.importFromWkt(wkt_b.c_str()) != OGRERR_NONE)
    return false;
  return a.IsSame(&b) != 0;
}

TEST(GeoRaster, LidarDemHeaderMatchesGdalinfo) {
  REQUIRE_DATA_AND_TOOLS();
  for (const char* name : {"TM1_564_146.tif", "TM1_564_146_nodata.tif"}) {
    const fs::path file = kData / name;
    const nlohmann::json truth = gdalinfo_json(file);
    ASSERT_TRUE(truth.is_object()) << name;
    const std::optional<GeoRasterInfo> info = probe_georaster(file);
    ASSERT_TRUE(info) << name << ": not taken as a georeferenced raster";
    EXPECT_EQ(info->driver, "GTiff");
    EXPECT_EQ(info->width, truth["size"][0].get<int>());
    EXPECT_EQ(info->height, truth["size"][1].get<int>());
    ASSERT_TRUE(info->has_geotransform);
    for (int k = 0; k < 6; ++k) EXPECT_EQ(info->geotransform[k], truth["geoTransform"][k].get<double>()) << k;
    // The texel size hfbake takes by default: 1 m, as gdalinfo says.
    EXPECT_EQ(std::abs(info->geotransform[1]), 1.0);
    EXPECT_TRUE(same_crs(info->crs_wkt, truth["coordinateSystem"]["wkt"].get<std::string>()));
    EXPECT_FALSE(info->geographic);
    EXPECT_EQ(info->linear_unit, "metre");
    EXPECT_NE(info->crs_name.find("Slovene National Grid"), std::string::npos) << info->crs_name;
    ASSERT_EQ(info->nodata.size(), 1u);
    const nlohmann::json& band = truth["bands"][0];
    EXPECT_EQ(info->nodata[0].has_value(), band.contains("noDataValue")) << name;
  }
}

TEST(GeoRaster, BandValuesAreAsStored) {
  REQUIRE_DATA_AND_TOOLS();
  const Plane p = read_georaster_band(kData / "TM1_564_146.tif", 0, {"job.json", "/height/image"});
  ASSERT_EQ(p.width, 1000);
  ASSERT_EQ(p.height, 1000);
  // gdalinfo -stats computes its own min and max over the file.
  TempFolder tmp;
  fs::copy_file(kData / "TM1_564_146.tif", tmp / "dem.tif");
  const nlohmann::json truth = test::gdalinfo_json_with("-stats", tmp / "dem.tif");
  ASSERT_TRUE(truth.is_object());
  float lo = INFINITY, hi = -INFINITY;
  for (float z : p.values) lo = std::min(lo, z), hi = std::max(hi, z);
  EXPECT_FLOAT_EQ(lo, truth["bands"][0]["minimum"].get<float>());
  EXPECT_FLOAT_EQ(hi, truth["bands"][0]["maximum"].get<float>());
}

TEST(GeoRaster, ImagesWithoutGeoreferencingStayWithOpenImageIO) {
  TempFolder tmp;
  GDALAllRegister();
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  const char* const plain[] = {"PROFILE=BASELINE", nullptr};
  GDALDataset* ds =
      gtiff->Create((tmp / "plain.tif").c_str(), 4, 3, 1, GDT_Float32, const_cast<char**>(plain));
  ASSERT_TRUE(ds);
  GDALClose(ds);
  EXPECT_FALSE(probe_georaster(tmp / "plain.tif"));
  EXPECT_FALSE(probe_georaster(tmp / "missing.tif"));
  // An Arc/Info ASCII grid is GDAL's whatever it says about itself.
  std::ofstream(tmp / "g.asc") << "ncols 3\nnrows 2\nxllcorner 100\nyllcorner 200\ncellsize 5\n"
                                  "NODATA_value -9999\n1 2 3\n4 -9999 6\n";
  const std::optional<GeoRasterInfo> asc = probe_georaster(tmp / "g.asc");
  ASSERT_TRUE(asc);
  EXPECT_EQ(asc->driver, "AAIGrid");
  EXPECT_EQ(asc->geotransform[1], 5.0);
  EXPECT_EQ(asc->geotransform[5], -5.0);
  ASSERT_TRUE(asc->nodata[0]);
  EXPECT_EQ(*asc->nodata[0], -9999.0);
  const Plane p = read_georaster_band(tmp / "g.asc", 0, {"j", "/height/image"});
  EXPECT_EQ(p.values, (std::vector<float>{1, 2, 3, 4, -9999, 6}));
}

LayerSet test_layers(int w, int h) {
  LayerSet s;
  s.width = w;
  s.height = h;
  Layer& ao = s.add("ao", mono_channels());
  for (int t = 0; t < w * h; ++t) ao.data[t] = float(t % 97) / 97.0f;
  Layer& rgb = s.add("direct", rgb_channels());
  for (std::size_t t = 0; t < rgb.data.size(); ++t) rgb.data[t] = float(t % 13) / 13.0f;
  return s;
}

std::vector<float> read_band(const fs::path& file, int band) {
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER));
  if (!ds) return {};
  std::vector<float> v(std::size_t(ds->GetRasterXSize()) * ds->GetRasterYSize());
  if (ds->GetRasterBand(band)->RasterIO(GF_Read, 0, 0, ds->GetRasterXSize(), ds->GetRasterYSize(), v.data(),
                                        ds->GetRasterXSize(), ds->GetRasterYSize(), GDT_Float32, 0, 0,
                                        nullptr) != CE_None)
    return {};
  return v;
}

// Each band declares its layer's unit (GDAL's unit type, what QGIS and gdalinfo show): degrees for angles,
// the CRS's linear unit for distances (metres in a geographic raster's local frame, US survey feet in
// EPSG:2263), none for fractions and sines, nor for a distance without a CRS. Both writers.
TEST(GeoTiffOutput, BandsDeclareTheirLayersUnit) {
  TempFolder tmp;
  const int w = 6, h = 5;
  LayerSet layers;
  layers.width = w, layers.height = h;
  for (const char* name : {"horizon_deg", "horizon_distance", "svf", "openness_negative"})
    layers.add(name, std::string(name).rfind("horizon", 0) == 0 ? indexed_channels(2) : mono_channels());
  auto wkt_of = [](int epsg) {
    OGRSpatialReference srs;
    EXPECT_EQ(srs.importFromEPSG(epsg), OGRERR_NONE);
    char* text = nullptr;
    srs.exportToWkt(&text);
    const std::string wkt = text;
    CPLFree(text);
    return wkt;
  };
  auto units = [](const fs::path& file) {
    std::unique_ptr<GDALDataset> ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER));
    std::vector<std::string> u;
    if (!ds) return u;
    for (int b = 1; b <= ds->GetRasterCount(); ++b) u.emplace_back(ds->GetRasterBand(b)->GetUnitType());
    return u;
  };
  using V = std::vector<std::string>;
  for (const int epsg : {2263, 4326, 0}) {
    SCOPED_TRACE(epsg);
    Georeference geo;
    geo.from_file = epsg != 0;
    if (epsg) geo.crs_wkt = wkt_of(epsg);
    geo.geotransform = {10, 0.001, 0, 20, 0, -0.001};
    const std::string distance = epsg == 2263 ? "US survey foot" : epsg == 4326 ? "metre" : "";
    for (const Layer& l : layers.layers) write_geotiff(tmp / (l.name + ".tif"), layers, l, geo);
    EXPECT_EQ(units(tmp / "horizon_deg.tif"), (V{"degree", "degree"}));
    EXPECT_EQ(units(tmp / "horizon_distance.tif"), (V{distance, distance}));
    EXPECT_EQ(units(tmp / "svf.tif"), V{""});
    EXPECT_EQ(units(tmp / "openness_negative.tif"), V{"degree"});
    {
      TiledGeoTiff tiled(tmp / "work.tif", w, h, "horizon_distance", indexed_channels(2), geo, {});
      const std::vector<float> zero(std::size_t(w) * h * 2, 0.0f);
      tiled.write(0, 0, w, h, zero.data(), std::size_t(w));
      tiled.finish(tmp / "tiled.tif");
    }
    EXPECT_EQ(units(tmp / "tiled.tif"), (V{distance, distance}));
  }
}

TEST(GeoTiffOutput, CogWithTheInputsCrsGeotransformAndNodata) {
  REQUIRE_DATA_AND_TOOLS();
  const std::optional<GeoRasterInfo> dem = probe_georaster(kData / "TM1_564_146.tif");
  ASSERT_TRUE(dem);
  TempFolder tmp;
  const int w = 700, h = 600;  // larger than one 512 tile: overviews and several tiles
  const LayerSet layers = test_layers(w, h);
  Georeference geo;
  geo.from_file = true;
  geo.crs_wkt = dem->crs_wkt;
  geo.geotransform = dem->geotransform;
  geo.holes.assign(std::size_t(w) * h, 0);
  geo.holes[5] = geo.holes[123456] = 1;
  write_geotiff(tmp / "t.ao.tif", layers, layers.layers[0], geo, {{{"HFBAKE_METHOD", "p1"}}});
  write_geotiff(tmp / "t.direct.tif", layers, layers.layers[1], geo);

  const nlohmann::json input = gdalinfo_json(kData / "TM1_564_146.tif");
  for (const char* name : {"t.ao.tif", "t.direct.tif"}) {
    const nlohmann::json out = gdalinfo_json(tmp / name);
    ASSERT_TRUE(out.is_object()) << name;
    EXPECT_EQ(out["geoTransform"], input["geoTransform"]) << name;
    // The same CRS (the writer stores it by its EPSG code, so gdalinfo prints EPSG's canonical WKT, whose
    // axis names and usage block differ from the input's own GeoKeys-derived WKT).
    const std::string wkt = out["coordinateSystem"]["wkt"].get<std::string>();
    EXPECT_TRUE(same_crs(wkt, input["coordinateSystem"]["wkt"].get<std::string>())) << wkt;
    EXPECT_NE(wkt.find("ID[\"EPSG\",3794]]"), std::string::npos) << wkt;
    EXPECT_EQ(out["metadata"]["IMAGE_STRUCTURE"]["LAYOUT"], "COG") << out["metadata"].dump();
    EXPECT_EQ(out["metadata"]["IMAGE_STRUCTURE"]["COMPRESSION"], "DEFLATE");
    for (const auto& band : out["bands"]) {
      EXPECT_EQ(band["type"], "Float32");
      EXPECT_EQ(band["noDataValue"].get<double>(), -9999.0);
    }
  }
  const nlohmann::json ao = gdalinfo_json(tmp / "t.ao.tif");
  EXPECT_EQ(ao["bands"].size(), 1u);
  EXPECT_EQ(ao["bands"][0]["description"], "ao");
  EXPECT_EQ(ao["metadata"][""]["HFBAKE_METHOD"], "p1");
  const nlohmann::json direct = gdalinfo_json(tmp / "t.direct.tif");
  ASSERT_EQ(direct["bands"].size(), 3u);
  EXPECT_EQ(direct["bands"][2]["description"], "direct.B");

  // Values: bit-exact, NoData exactly at the holes.
  const std::vector<float> v = read_band(tmp / "t.ao.tif", 1);
  ASSERT_EQ(v.size(), std::size_t(w) * h);
  for (std::size_t t = 0; t < v.size(); ++t)
    ASSERT_EQ(v[t], geo.holes[t] ? -9999.0f : layers.layers[0].data[t]) << t;
  const std::vector<float> g = read_band(tmp / "t.direct.tif", 2);
  for (std::size_t t = 0; t < g.size(); ++t)
    ASSERT_EQ(g[t], geo.holes[t] ? -9999.0f : layers.layers[1].data[t * 3 + 1]) << t;
}

// Without holes GDAL reads the layer's own interleaved values (no copy): every band bit-exact, over several
// tiles and an overview.
TEST(GeoTiffOutput, WithoutHolesEveryBandIsTheLayersValues) {
  if (!test::have_gdal_tools()) GTEST_SKIP() << "gdalinfo not found";
  TempFolder tmp;
  const int w = 700, h = 600;
  const LayerSet layers = test_layers(w, h);
  Georeference geo;
  geo.geotransform = local_geotransform(1.0);
  write_geotiff(tmp / "d.tif", layers, layers.layers[1], geo);
  for (int band = 1; band <= 3; ++band) {
    const std::vector<float> v = read_band(tmp / "d.tif", band);
    ASSERT_EQ(v.size(), std::size_t(w) * h);
    for (std::size_t t = 0; t < v.size(); ++t)
      ASSERT_EQ(v[t], layers.layers[1].data[t * 3 + std::size_t(band - 1)]) << band << " " << t;
  }
}

TEST(GeoTiffOutput, WithoutHolesNoNodataTagAndALocalGeotransform) {
  if (!test::have_gdal_tools()) GTEST_SKIP() << "gdalinfo not found";
  TempFolder tmp;
  const LayerSet layers = test_layers(40, 30);
  Georeference geo;
  geo.geotransform = local_geotransform(0.25);
  write_geotiff(tmp / "p.tif", layers, layers.layers[0], geo);
  const nlohmann::json out = gdalinfo_json(tmp / "p.tif");
  ASSERT_TRUE(out.is_object());
  EXPECT_FALSE(out["bands"][0].contains("noDataValue"));
  EXPECT_FALSE(out.contains("coordinateSystem") && out["coordinateSystem"].contains("wkt") &&
               !out["coordinateSystem"]["wkt"].get<std::string>().empty());
  const std::vector<double> gt = out["geoTransform"];
  EXPECT_EQ(gt, (std::vector<double>{-0.125, 0.25, 0, 0.125, 0, -0.25}));
}

TEST(GeoTiffOutput, AFailedWriteLeavesNothing) {
  TempFolder tmp;
  const LayerSet layers = test_layers(8, 8);
  EXPECT_THROW(write_geotiff(tmp / "no" / "such" / "folder.tif", layers, layers.layers[0], Georeference{}),
               InputError);
  EXPECT_TRUE(fs::is_empty(tmp.path()));
}

}  // namespace
}  // namespace hfbake

namespace hfbake {
namespace {

// A w x h float32 GeoTIFF (strips or 256-tiles) with a geotransform, values from a fixed recurrence.
void write_float_geotiff(const fs::path& file, int w, int h, bool tiled) {
  GDALAllRegister();
  GDALDriver* drv = GetGDALDriverManager()->GetDriverByName("GTiff");
  ASSERT_TRUE(drv);
  const char* strips[] = {"COMPRESS=DEFLATE", nullptr};
  const char* tiles[] = {"COMPRESS=DEFLATE", "TILED=YES", "BLOCKXSIZE=256", "BLOCKYSIZE=256", nullptr};
  std::unique_ptr<GDALDataset> ds(
      drv->Create(file.c_str(), w, h, 1, GDT_Float32, const_cast<char**>(tiled ? tiles : strips)));
  ASSERT_TRUE(ds);
  double gt[6] = {500000, 2, 0, 100000, 0, -2};
  ds->SetGeoTransform(gt);
  std::vector<float> v(std::size_t(w) * h);
  std::uint32_t s = 11;
  for (float& x : v) s = s * 1664525u + 1013904223u, x = float(s >> 8) * 1e-3f;
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, w, h, v.data(), w, h, GDT_Float32, 0, 0, nullptr),
            CE_None);
}

// GDAL's own read of the whole band in one call: the truth for the banded reader.
std::vector<float> gdal_whole_band(const fs::path& file) {
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  const int w = ds->GetRasterXSize(), h = ds->GetRasterYSize();
  std::vector<float> v(std::size_t(w) * h);
  EXPECT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, w, h, v.data(), w, h, GDT_Float32, 0, 0, nullptr),
            CE_None);
  return v;
}

TEST(GeoRaster, BandedReadEqualsGdalsWholeRead) {
  TempFolder tmp;
  for (const bool tiled : {false, true}) {
    const fs::path file = tmp / (tiled ? "tiled.tif" : "strips.tif");
    write_float_geotiff(file, 700, 613, tiled);
    std::vector<double> fractions;
    const Plane p =
        read_georaster_band(file, 0, {"j", "/height/image"}, [&](double f) { fractions.push_back(f); });
    EXPECT_EQ(p.width, 700);
    EXPECT_EQ(p.height, 613);
    EXPECT_TRUE(p.values == gdal_whole_band(file)) << file;
    ASSERT_GE(fractions.size(), 2u) << file;  // 613 rows: at least 3 bands of 256
    EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
    EXPECT_EQ(fractions.back(), 1.0);
  }
}

TEST(GeoRaster, TruncatedRasterIsAOneLineErrorNamingTheFile) {
  TempFolder tmp;
  const fs::path file = tmp / "cut.tif";
  write_float_geotiff(file, 1024, 1024, false);
  fs::resize_file(file, fs::file_size(file) / 2);
  try {
    read_georaster_band(file, 0, {"job.json", "/height/image"});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string line = e.line();
    EXPECT_EQ(line.rfind("job.json: /height/image: " + file.string() + ": cannot ", 0), 0u) << line;
    EXPECT_EQ(line.find('\n'), std::string::npos) << line;
  }
}

// A double band's finite value beyond float's range would become an infinity and pass for a hole: it is
// refused, naming the texel, unless it is the band's NoData value; every other value is read as float(v).
TEST(GeoRaster, DoubleValuesBeyondFloatAreRefusedUnlessNoData) {
  TempFolder tmp;
  const auto write = [&](const fs::path& file, bool declare) {
    GDALAllRegister();
    GDALDriver* drv = GetGDALDriverManager()->GetDriverByName("GTiff");
    std::unique_ptr<GDALDataset> ds(drv->Create(file.c_str(), 5, 4, 1, GDT_Float64, nullptr));
    ASSERT_TRUE(ds);
    std::vector<double> z(20);
    for (int t = 0; t < 20; ++t) z[std::size_t(t)] = 100.0 + 0.1 * t;
    z[13] = -1e300;  // texel (3, 2)
    if (declare) ds->GetRasterBand(1)->SetNoDataValue(-1e300);
    ASSERT_EQ(
        ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 5, 4, z.data(), 5, 4, GDT_Float64, 0, 0, nullptr),
        CE_None);
  };
  write(tmp / "sentinel.tif", false);
  write(tmp / "declared.tif", true);
  for (const bool window : {false, true}) {
    try {
      if (window)
        read_georaster_window(tmp / "sentinel.tif", 0, 1, 1, 4, 3, {"job.json", "/height/image"});
      else
        read_georaster_band(tmp / "sentinel.tif", 0, {"job.json", "/height/image"});
      ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(),
                "job.json: /height/image: " + (tmp / "sentinel.tif").string() +
                    ": texel (3, 2) is -1e+300, beyond a float's range: heights are baked as floats (if "
                    "it marks missing data, declare it the band's NoData value)");
    }
  }
  const Plane p = read_georaster_band(tmp / "declared.tif", 0, {"job.json", "/height/image"});
  EXPECT_EQ(p.sample_type, "Float64");
  EXPECT_EQ(p.values[12], float(100.0 + 0.1 * 12));
  EXPECT_TRUE(std::isinf(p.values[13]));  // the NoData value: a hole for the loader's nodata rule
}

}  // namespace
}  // namespace hfbake

namespace hfbake {
namespace {

// Windows read one by one equal GDAL's whole read at their places, on strips and tiles; a window beyond the
// raster is an InputError naming the file.
TEST(GeoRaster, WindowReadEqualsGdalsWholeRead) {
  TempFolder tmp;
  for (const bool tiled : {false, true}) {
    const fs::path file = tmp / (tiled ? "tiled.tif" : "strips.tif");
    write_float_geotiff(file, 700, 613, tiled);
    const std::vector<float> whole = gdal_whole_band(file);
    for (const std::array<int, 4> w : {std::array<int, 4>{0, 0, 700, 613},
                                       {1, 2, 3, 4},
                                       {250, 255, 300, 7},
                                       {699, 612, 1, 1},
                                       {0, 300, 700, 313}}) {
      const Plane p = read_georaster_window(file, 0, w[0], w[1], w[2], w[3], {"j", "/height/image"});
      ASSERT_EQ(p.width, w[2]);
      ASSERT_EQ(p.height, w[3]);
      for (int j = 0; j < w[3]; ++j)
        for (int i = 0; i < w[2]; ++i)
          ASSERT_EQ(p.values[std::size_t(j) * std::size_t(w[2]) + std::size_t(i)],
                    whole[std::size_t(w[1] + j) * 700 + std::size_t(w[0] + i)])
              << file << " window at " << w[0] << ", " << w[1];
    }
    try {
      read_georaster_window(file, 0, 650, 0, 51, 10, {"j.json", "/height/image"});
      ADD_FAILURE() << "a window beyond the raster was read";
    } catch (const InputError& e) {
      EXPECT_NE(e.line().find(file.string()), std::string::npos) << e.line();
    }
  }
}

// A COG written a window at a time, in any order, with interleaved channels and a row stride wider than the
// window: GDAL reads back every band as written, with the band names, CRS-less geotransform and metadata;
// the work file is gone.
TEST(GeoTiffOutput, WindowedCogHoldsEveryWindowAsWritten) {
  TempFolder tmp;
  const int w = 300, h = 170, nc = 3;
  std::vector<float> truth(std::size_t(w) * h * nc);
  for (std::size_t t = 0; t < truth.size(); ++t) truth[t] = float(std::sin(0.001 * double(t)) * 10);
  Georeference geo;
  geo.geotransform = local_geotransform(0.5);
  GeoTiffOptions options;
  options.metadata = {{"HFBAKE_METHOD", "relief"}};
  {
    TiledGeoTiff out(tmp / "work.tif", w, h, "bent", {"X", "Y", "Z"}, geo, options);
    // Windows of 64 x 48 from the bottom right, each handed as a part of a 100-texel-wide buffer.
    for (int y0 = (h - 1) / 48 * 48; y0 >= 0; y0 -= 48)
      for (int x0 = (w - 1) / 64 * 64; x0 >= 0; x0 -= 64) {
        const int ww = std::min(64, w - x0), wh = std::min(48, h - y0);
        std::vector<float> buffer(std::size_t(100) * std::size_t(wh + 1) * nc, -1.0f);
        for (int j = 0; j < wh; ++j)
          for (int i = 0; i < ww; ++i)
            for (int c = 0; c < nc; ++c)
              buffer[((std::size_t(j) + 1) * 100 + std::size_t(i) + 5) * nc + std::size_t(c)] =
                  truth[(std::size_t(y0 + j) * w + std::size_t(x0 + i)) * nc + std::size_t(c)];
        out.write(x0, y0, ww, wh, buffer.data() + (100 + 5) * nc, 100);
      }
    out.finish(tmp / "bent.tif");
  }
  EXPECT_FALSE(fs::exists(tmp / "work.tif"));
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open((tmp / "bent.tif").c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(ds);
  ASSERT_EQ(ds->GetRasterCount(), nc);
  EXPECT_STREQ(ds->GetMetadataItem("LAYOUT", "IMAGE_STRUCTURE"), "COG");
  EXPECT_STREQ(ds->GetMetadataItem("HFBAKE_METHOD"), "relief");
  double gt[6];
  ds->GetGeoTransform(gt);
  EXPECT_EQ(gt[1], 0.5);
  for (int c = 0; c < nc; ++c) {
    GDALRasterBand* b = ds->GetRasterBand(c + 1);
    EXPECT_EQ(std::string(b->GetDescription()), std::string("bent.") + "XYZ"[c]);
    std::vector<float> v(std::size_t(w) * h);
    ASSERT_EQ(b->RasterIO(GF_Read, 0, 0, w, h, v.data(), w, h, GDT_Float32, 0, 0, nullptr), CE_None);
    for (std::size_t t = 0; t < v.size(); ++t)
      ASSERT_EQ(v[t], truth[t * nc + std::size_t(c)]) << "band " << c << " texel " << t;
  }
  // A one-channel layer's band is described by the layer's name, and read back as its channel; a band of
  // several, or one written as "<layer>.Y", by its suffix.
  {
    TiledGeoTiff one(tmp / "work1.tif", 8, 4, "svf", mono_channels(), geo, options);
    one.write(0, 0, 8, 4, truth.data(), 8);
    one.finish(tmp / "svf.tif");
  }
  std::unique_ptr<GDALDataset> svf(GDALDataset::Open((tmp / "svf.tif").c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(svf);
  EXPECT_STREQ(svf->GetRasterBand(1)->GetDescription(), "svf");
  EXPECT_EQ(geotiff_band_channel("svf", "svf"), mono_channels().front());
  EXPECT_EQ(geotiff_band_channel("svf", "svf.Y"), "Y");
  EXPECT_EQ(geotiff_band_channel("bent", "bent.Z"), "Z");
}

}  // namespace
}  // namespace hfbake

namespace hfbake {
namespace {

// geotiff_writing_bytes against the parts counted here by hand: for every band four 512 x 512 float tiles
// (1 MiB each), two of the first tile (min(width, 512) x min(height, 512) floats) and 512 bytes per texel of
// width plus height, the overview levels
// listed for each shape (halved, rounded down, while the last is wider or taller than 512), 4 bytes a texel
// and band, held up to GDAL's block cache, and the copy holding NoData with holes.
TEST(GeoTiffOutput, WritingBytesCountTheTilesAndTheOverviewsUpToTheCache) {
  constexpr double MiB = 1 << 20;
  struct Case {
    int width, height, channels;
    double overview_texels;
  };
  const Case cases[] = {{2048, 2048, 16, 1024.0 * 1024 + 512.0 * 512},
                        {1000, 1000, 32, 500.0 * 500},
                        {4000, 700, 3, 2000.0 * 350 + 1000.0 * 175 + 500.0 * 87},
                        {512, 512, 64, 0},
                        {513, 300, 1, 256.0 * 150},
                        {16, 16, 64, 0}};
  {
    const GdalCacheLimit cache(std::size_t(1) << 30);  // holds every case's overviews
    for (const Case& c : cases)
      for (const bool holes : {false, true}) {
        const double first_tile = 4.0 * std::min(c.width, 512) * std::min(c.height, 512);
        const double expected = (4 * MiB + 2 * first_tile + 512.0 * (c.width + c.height)) * c.channels +
                                4.0 * c.channels * c.overview_texels +
                                (holes ? 4.0 * c.channels * c.width * c.height : 0.0);
        EXPECT_DOUBLE_EQ(geotiff_writing_bytes(c.width, c.height, c.channels, holes), expected)
            << c.width << "x" << c.height << "x" << c.channels << (holes ? " with holes" : "");
      }
  }
  const GdalCacheLimit cache(std::size_t(32) << 20);  // below 2048^2 x 16's 80 MiB of overviews
  EXPECT_DOUBLE_EQ(geotiff_writing_bytes(2048, 2048, 16, false), 8 * MiB * 16 + 32 * MiB);
}

}  // namespace
}  // namespace hfbake
