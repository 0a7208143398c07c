// hfbake bake --tiles, end to end (the binary): on rasters that fit both ways, the tiled bake's COGs hold
// the whole bake's texels bit for bit, for every method with a bounded reach (relief's far field included:
// the tiles walk the whole raster's coarse copy), on a family of fields (sines, terraces, craters, white
// noise, the lidar DEM when present) at tile sizes that cut them unevenly; a tile task's files are its job
// file's alone, and a merge takes no other; and what a tiled bake refuses is one line naming the job file and
// the key, with nothing written. The truth is the whole bake of the same
// job (no tiles: one field in memory), read back with GDAL.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../hostile/child_process.hpp"
#include "run_hfbake.hpp"

namespace {
namespace fs = std::filesystem;
using hfbake::cli_test::Result;

const fs::path kDem = fs::path(HFBAKE_SHARED_DATA_DIR) / "TM1_564_146.tif";

struct Bands {
  int width = 0, height = 0;
  std::vector<std::vector<float>> values;  // per band
};

Bands read_bands(const fs::path& file) {
  Bands r;
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER));
  if (!ds) return r;
  r.width = ds->GetRasterXSize();
  r.height = ds->GetRasterYSize();
  for (int b = 1; b <= ds->GetRasterCount(); ++b) {
    std::vector<float> v(std::size_t(r.width) * std::size_t(r.height));
    if (ds->GetRasterBand(b)->RasterIO(GF_Read, 0, 0, r.width, r.height, v.data(), r.width, r.height,
                                       GDT_Float32, 0, 0, nullptr) != CE_None)
      return {};
    r.values.push_back(std::move(v));
  }
  return r;
}

// A GeoTIFF's metadata item (GDAL's default domain); "" when absent.
std::string metadata_item(const fs::path& file, const char* key) {
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER));
  const char* v = ds ? ds->GetMetadataItem(key) : nullptr;
  return std::string(v ? v : "");
}

// Each regular file in `dir` (not below it) by name, with its bytes.
std::map<std::string, std::string> folder_files(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    files[e.path().filename().string()] = bytes.str();
  }
  return files;
}

// A float32 GeoTIFF of heights z(i, j) with a 0.5 m north-up geotransform.
template <class F>
void write_heights(const fs::path& file, int width, int height, F z, bool geographic = false) {
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  std::unique_ptr<GDALDataset> ds(driver->Create(file.c_str(), width, height, 1, GDT_Float32, nullptr));
  std::vector<float> v(std::size_t(width) * std::size_t(height));
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) v[std::size_t(j) * std::size_t(width) + std::size_t(i)] = float(z(i, j));
  // Projected: 0.5 world units a texel, no CRS. Geographic: WGS 84 at 46.5 N, 1e-5 degrees a texel (texels of
  // about 0.77 x 1.11 m in the local frame, the Earth's curvature on).
  double gt[6] = {400000, 0.5, 0, 100000, 0, -0.5};
  if (geographic) {
    const double g[6] = {15.0, 1e-5, 0, 46.5, 0, -1e-5};
    std::copy(g, g + 6, gt);
    OGRSpatialReference srs;
    srs.importFromEPSG(4326);
    ds->SetSpatialRef(&srs);
  }
  ds->SetGeoTransform(gt);
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, width, height, v.data(), width, height,
                                           GDT_Float32, 0, 0, nullptr),
            CE_None);
}

class CliTiles : public ::testing::Test {
 protected:
  void SetUp() override {
    GDALAllRegister();
    dir_ = fs::temp_directory_path() / ("hfbake_test_cli_tiles_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  Result hfbake(const std::string& args) { return hfbake::cli_test::run_hfbake(dir_, args); }

  fs::path write_job(const std::string& name, const nlohmann::json& height, const nlohmann::json& bake,
                     const nlohmann::json& extra = nlohmann::json::object()) {
    nlohmann::json j = {{"version", 1},
                        {"name", name},
                        {"height", height},
                        {"bake", bake},
                        {"output", {{"dir", "out_" + name}, {"geotiff", true}}}};
    if (extra.is_object()) j.update(extra, true);
    const fs::path p = dir_ / (name + ".json");
    std::ofstream(p) << j.dump(2);
    return p;
  }

  // Bakes `image` whole and in tiles of each size with `bake`'s entries; every COG of the tiled bake must
  // hold the whole bake's bits.
  void expect_tiles_equal_whole(const std::string& image, const nlohmann::json& bake,
                                const std::vector<int>& tile_sizes,
                                const nlohmann::json& height_keys = nlohmann::json::object()) {
    nlohmann::json height = {{"image", image}};
    height.update(height_keys);
    Result r = hfbake("bake --quiet --no-cache " + write_job("whole", height, bake).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::vector<fs::path> cogs;
    for (const auto& e : fs::directory_iterator(dir_ / "out_whole"))
      if (e.path().extension() == ".tif") cogs.push_back(e.path().filename());
    ASSERT_FALSE(cogs.empty());
    for (const int tile : tile_sizes) {
      const std::string name = "tiled" + std::to_string(tile);
      r = hfbake("bake --quiet --tiles --tile-size " + std::to_string(tile) + " " +
                 write_job(name, height, bake).string());
      ASSERT_EQ(r.exit_code, 0) << r.err;
      std::size_t written = 0;
      for (const auto& e : fs::directory_iterator(dir_ / ("out_" + name)))
        written += e.path().extension() == ".tif";
      EXPECT_EQ(written, cogs.size()) << "a tiled bake writes the COGs and nothing else";
      for (const fs::path& cog : cogs) {
        std::string tiled_name = cog.string();
        tiled_name.replace(0, 5, name);  // whole.<stem>.<layer>.tif -> tiledN.<stem>.<layer>.tif
        const Bands whole = read_bands(dir_ / "out_whole" / cog);
        const Bands tiled = read_bands(dir_ / ("out_" + name) / tiled_name);
        ASSERT_EQ(tiled.width, whole.width) << tiled_name;
        ASSERT_EQ(tiled.height, whole.height) << tiled_name;
        ASSERT_EQ(tiled.values.size(), whole.values.size()) << tiled_name;
        for (std::size_t b = 0; b < whole.values.size(); ++b) {
          std::size_t differ = 0, first = 0;
          for (std::size_t t = 0; t < whole.values[b].size(); ++t)
            if (std::memcmp(&whole.values[b][t], &tiled.values[b][t], sizeof(float)) != 0 && differ++ == 0)
              first = t;
          EXPECT_EQ(differ, 0u) << image << " " << tiled_name << " band " << b + 1 << " tile " << tile
                                << ": first at texel (" << first % std::size_t(whole.width) << ", "
                                << first / std::size_t(whole.width) << "): " << whole.values[b][first]
                                << " whole, " << tiled.values[b][first] << " tiled";
        }
      }
    }
  }

  // The family: smooth sines, terraces (steps: the horizons' kinks), craters, white noise.
  void write_family(int width, int height) {
    write_heights(dir_ / "sines.tif", width, height,
                  [](int i, int j) { return 3 * std::sin(0.21 * i) * std::cos(0.13 * j) + 0.02 * i; });
    write_heights(dir_ / "terraces.tif", width, height,
                  [](int i, int j) { return std::floor(0.1 * i + 0.07 * j) * 1.5; });
    write_heights(dir_ / "craters.tif", width, height, [](int i, int j) {
      const double r = std::hypot(std::fmod(i, 37.0) - 18, std::fmod(j, 29.0) - 14);
      return r < 10 ? 0.04 * r * r : 4.0 - 0.1 * (r - 10);
    });
    std::mt19937 rng(11);
    std::vector<float> noise(std::size_t(width) * std::size_t(height));
    for (float& v : noise) v = std::uniform_real_distribution<float>(0, 2)(rng);
    write_heights(dir_ / "noise.tif", width, height,
                  [&](int i, int j) { return noise[std::size_t(j) * std::size_t(width) + std::size_t(i)]; });
  }

  fs::path dir_;
};

const nlohmann::json kBounded = {
    {{"method", "relief"}, {"directions", 8}, {"search_radius", 4.5}, {"layers", {"svf", "horizon_deg"}}},
    {{"method", "hbao"}, {"directions", 8}, {"radius", 3}, {"falloff", "smooth"}},
    {{"method", "hbao"}, {"directions", 4}, {"max_distance", 2.5}, {"surface", "triangles"}}};

TEST_F(CliTiles, TiledBakeEqualsWholeBakeOnAFamilyOfFields) {
  write_family(150, 97);
  for (const char* field : {"sines.tif", "terraces.tif", "craters.tif", "noise.tif"}) {
    SCOPED_TRACE(field);
    expect_tiles_equal_whole(field, kBounded, {16, 45, 100});
  }
}

TEST_F(CliTiles, TiledBakeEqualsWholeBakeOnTheLidarDem) {
  if (!fs::exists(kDem)) GTEST_SKIP() << "no real DEM at " << kDem << " (the shared data folder is absent)";
  // A 300^2 window of the 1 m lidar DEM, georeferencing kept.
  std::unique_ptr<GDALDataset> src(GDALDataset::Open(kDem.c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(src);
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  std::unique_ptr<GDALDataset> dst(
      driver->Create((dir_ / "dem.tif").c_str(), 300, 300, 1, GDT_Float32, nullptr));
  std::vector<float> v(300 * 300);
  ASSERT_EQ(src->GetRasterBand(1)->RasterIO(GF_Read, 350, 350, 300, 300, v.data(), 300, 300, GDT_Float32, 0,
                                            0, nullptr),
            CE_None);
  double gt[6];
  src->GetGeoTransform(gt);
  gt[0] += 350 * gt[1];
  gt[3] += 350 * gt[5];
  dst->SetGeoTransform(gt);
  dst->SetProjection(src->GetProjectionRef());
  ASSERT_EQ(dst->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 300, 300, v.data(), 300, 300, GDT_Float32, 0, 0,
                                            nullptr),
            CE_None);
  dst.reset();
  const nlohmann::json bake = {{{"method", "relief"},
                                {"directions", 16},
                                {"search_radius", 20},
                                {"layers", {"svf", "openness_positive"}}},
                               {{"method", "hbao"}, {"directions", 8}, {"radius", 8}, {"falloff", "smooth"}},
                               {{"method", "relief"},
                                {"directions", 16},
                                {"search_radius", 150},
                                {"far_field", {{"beyond", 20}, {"cell", 8}}},
                                {"layers", {"svf", "horizon_deg"}}}};
  expect_tiles_equal_whole("dem.tif", bake, {64, 128});
}

// relief with a far field: the tiles' halo is the far field's distance, not the search radius, and every
// tile walks the coarse copy of the whole raster, so its texels are the whole bake's bit for bit (the
// whole bake coarsens the same raster the same way). Radius 40 m = 80 texels, exact within 4 m = 8.
TEST_F(CliTiles, TiledBakeWithFarFieldEqualsWholeBake) {
  write_family(150, 97);
  const nlohmann::json bake = {{{"method", "relief"},
                                {"directions", 8},
                                {"search_radius", 40},
                                {"far_field", {{"beyond", 4}, {"cell", 4}}},
                                {"layers", {"svf", "openness_negative", "horizon_deg"}}},
                               {{"method", "relief"},
                                {"directions", 5},
                                {"search_radius", 30},
                                {"far_field", {{"beyond", 2.5}, {"cell", 8}}},
                                {"layers", {"horizon_deg"}}}};
  const Result plan = hfbake("validate --tiles --tile-size 45 " +
                             write_job("plan", {{"image", "craters.tif"}}, bake).string());
  ASSERT_EQ(plan.exit_code, 0) << plan.err;
  EXPECT_NE(plan.err.find("with a halo of 10, beside coarse copies of the raster of 1 MiB"),
            std::string::npos)
      << plan.err;
  for (const char* field : {"sines.tif", "terraces.tif", "craters.tif", "noise.tif"}) {
    SCOPED_TRACE(field);
    expect_tiles_equal_whole(field, bake, {16, 45, 100});
  }
}

// height_scale and height_offset move the tiles' heights and the coarse copies' alike: the tiles are the
// whole bake's texels.
TEST_F(CliTiles, TiledBakeWithScaleAndOffsetEqualsWholeBake) {
  write_family(150, 97);
  const nlohmann::json bake = {
      {{"method", "relief"},
       {"directions", 8},
       {"search_radius", 40},
       {"far_field", {{"beyond", 4}, {"cell", 4}}},
       {"layers", {"svf", "horizon_deg"}}},
      {{"method", "p1"}, {"directions", 8}, {"far_field", {{"beyond", 6}, {"cell", 4}}}, {"layers", {"ao"}}}};
  expect_tiles_equal_whole("craters.tif", bake, {45}, {{"height_scale", 1.5}, {"height_offset", -300}});
}

// A geographic raster (rectangular texels in its local frame, the Earth's curvature from its ellipsoid):
// relief's and p1's tiles are the whole bake's texels.
TEST_F(CliTiles, TiledGeographicRasterEqualsWholeBake) {
  write_heights(
      dir_ / "geo.tif", 150, 97,
      [](int i, int j) {
        const double r = std::hypot(std::fmod(i, 37.0) - 18, std::fmod(j, 29.0) - 14);
        return r < 10 ? 0.04 * r * r : 4.0 - 0.1 * (r - 10);
      },
      true);
  const nlohmann::json bake = {{{"method", "relief"},
                                {"directions", 8},
                                {"search_radius", 30},
                                {"far_field", {{"beyond", 4}, {"cell", 4}}},
                                {"layers", {"svf", "horizon_deg"}}},
                               {{"method", "p1"},
                                {"directions", 8},
                                {"lights", false},
                                {"far_field", {{"beyond", 5}, {"cell", 4}}},
                                {"layers", {"ao", "horizon"}}}};
  expect_tiles_equal_whole("geo.tif", bake, {16, 45});
}

// p1 and sun with a far field: every tile's exact search over its window, beyond `beyond` the raster's coarse
// copy's floor (methods/p1/far_floor.hpp), so the tiles are the whole bake's texels bit for bit.
TEST_F(CliTiles, TiledP1AndSunWithFarFieldEqualWholeBake) {
  write_family(150, 97);
  const nlohmann::json bake = {
      {{"method", "p1"},
       {"directions", 8},
       {"far_field", {{"beyond", 6}, {"cell", 4}}},
       {"layers", {"ao", "vsky", "horizon", "bent_normal"}}},
      {{"method", "p1"},
       {"directions", 5},
       {"far_field", {{"beyond", 3.5}, {"cell", 8}}},
       {"layers", {"vsky"}}},
      // sun's horizons are p1's: the sun's own azimuths and the sky term's K directions.
      {{"method", "sun"},
       {"start", "2026-06-21T05:00"},
       {"end", "2026-06-21T19:00"},
       {"utc_offset", 2},
       {"step_minutes", 120},
       {"latitude", 46.5},
       {"longitude", 8},
       {"directions", 8},
       {"far_field", {{"beyond", 5}, {"cell", 4}}},
       {"layers", {"irradiation", "sun_hours"}}}};
  for (const char* field : {"sines.tif", "terraces.tif", "craters.tif", "noise.tif"}) {
    SCOPED_TRACE(field);
    expect_tiles_equal_whole(field, bake, {16, 45, 100});
    // The certified bound, the largest of the tiles' interiors': never below the whole bake's (a tile's
    // texel knows only the casters its window holds, so its slack over the floor can only be larger), the
    // same in one process and through tile tasks and their merge.
    const fs::path job = write_job("farm", {{"image", field}}, bake);
    for (const int i : {1, 0, 2})
      ASSERT_EQ(hfbake("bake --quiet --tiles --tile-size 45 --tile-task " + std::to_string(i) + "/3 " +
                       job.string())
                    .exit_code,
                0);
    ASSERT_EQ(hfbake("merge --quiet --tiles --tile-size 45 " + job.string()).exit_code, 0);
    for (const auto& [file, key] : {std::pair{".p1-0.ao.tif", "HFBAKE_P1_FAR_FIELD_BOUND"},
                                    std::pair{".sun.sun_hours.tif", "HFBAKE_SUN_FAR_FIELD_BOUND"}}) {
      const std::string whole = metadata_item(dir_ / "out_whole" / ("whole" + std::string(file)), key);
      const std::string tiled = metadata_item(dir_ / "out_tiled45" / ("tiled45" + std::string(file)), key);
      ASSERT_FALSE(whole.empty()) << file;
      ASSERT_FALSE(tiled.empty()) << file;
      EXPECT_GE(std::stod(tiled), std::stod(whole)) << file;
      EXPECT_LT(std::stod(tiled), 10.0) << file;
      EXPECT_EQ(metadata_item(dir_ / "out_farm" / ("farm" + std::string(file)), key), tiled) << file;
    }
    fs::remove_all(dir_ / "out_farm");
  }
}

// The farm's halves: tile tasks (--tile-task I/N, any order) and merge --tiles write the COGs of the
// one-process tiled bake, bit for bit; a missing tile file or one of another plan is refused naming it, with
// no COG written.
TEST_F(CliTiles, TileTasksMergeToTheTiledBake) {
  write_family(150, 97);
  const nlohmann::json height = {{"image", "craters.tif"}};
  Result r = hfbake("bake --quiet --tiles --tile-size 40 " + write_job("one", height, kBounded).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path job = write_job("farm", height, kBounded);
  for (const int i : {2, 0, 1}) {
    r = hfbake("bake --quiet --tiles --tile-size 40 --tile-task " + std::to_string(i) + "/3 " + job.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out_farm" / "farm.relief.svf.tif")) << "a tile task wrote an output";
  // Another plan's tiles: refused, naming the first file that is not of this plan.
  r = hfbake("merge --quiet --tiles --tile-size 50 " + job.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("tiles/farm+tile-0."), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out_farm" / "farm.relief.svf.tif"));
  // Tiles baked from other heights (the raster replaced since the tasks ran): refused, naming the first.
  fs::rename(dir_ / "craters.tif", dir_ / "craters_kept.tif");
  fs::copy_file(dir_ / "terraces.tif", dir_ / "craters.tif");
  r = hfbake("merge --quiet --tiles --tile-size 40 " + job.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("tiles/farm+tile-0."), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out_farm" / "farm.relief.svf.tif"));
  fs::remove(dir_ / "craters.tif");
  fs::rename(dir_ / "craters_kept.tif", dir_ / "craters.tif");
  // A damaged tile file (one value changed, or made NaN, in place): refused, naming it.
  const fs::path damaged = dir_ / "out_farm" / "tiles" / "farm+tile-3.relief.svf.tif";
  fs::copy_file(damaged, dir_ / "kept_svf.tif");
  for (const float bad : {0.5f, std::numeric_limits<float>::quiet_NaN()}) {
    {
      std::unique_ptr<GDALDataset> ds(GDALDataset::Open(damaged.c_str(), GDAL_OF_RASTER | GDAL_OF_UPDATE));
      ASSERT_TRUE(ds);
      float v = 0;
      ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Read, 3, 2, 1, 1, &v, 1, 1, GDT_Float32, 0, 0, nullptr),
                CE_None);
      v = std::isnan(bad) ? bad : v + bad;
      ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 3, 2, 1, 1, &v, 1, 1, GDT_Float32, 0, 0, nullptr),
                CE_None);
    }
    r = hfbake("merge --quiet --tiles --tile-size 40 " + job.string());
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find(damaged.string() + ": is damaged"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out_farm" / "farm.relief.svf.tif"));
    fs::copy_file(dir_ / "kept_svf.tif", damaged, fs::copy_options::overwrite_existing);
  }
  // A missing tile file: refused, naming it.
  const fs::path gone = dir_ / "out_farm" / "tiles" / "farm+tile-5.relief.svf.tif";
  const fs::path kept = dir_ / "kept.tif";
  fs::rename(gone, kept);
  r = hfbake("merge --quiet --tiles --tile-size 40 " + job.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find(gone.string() + ": is missing"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out_farm" / "farm.relief.svf.tif"));
  // A truncated tile file: refused in one line naming it once.
  fs::copy_file(kept, gone);
  fs::resize_file(gone, fs::file_size(kept) / 2);
  r = hfbake("merge --quiet --tiles --tile-size 40 " + job.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_EQ(r.error_lines()[0].find("hfbake: error: " + gone.string() + ": "), 0u) << r.err;
  EXPECT_EQ(r.error_lines()[0].find(gone.string(), 16), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out_farm" / "farm.relief.svf.tif"));
  // A folder, a FIFO or an empty file at its name: refused, saying what stands there (a folder, where no
  // task could write either, as the job's folder check finds it).
  for (const auto& [what, make] : std::vector<std::pair<std::string, std::function<void()>>>{
           {job.string() + ": /output/dir: " + gone.string() + " is a folder where an output goes",
            [&] { fs::create_directory(gone); }},
           {gone.string() + ": cannot read tile 5: not a regular file (a FIFO)",
            [&] { ASSERT_EQ(mkfifo(gone.c_str(), 0600), 0); }},
           {gone.string() + ": is empty, not tile 5", [&] { std::ofstream{gone}; }}}) {
    fs::remove_all(gone);
    make();
    r = hfbake("merge --quiet --tiles --tile-size 40 " + job.string());
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_EQ(r.error_lines()[0].find("hfbake: error: " + what), 0u) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out_farm" / "farm.relief.svf.tif"));
  }
  fs::remove_all(gone);
  fs::rename(kept, gone);
  r = hfbake("merge --quiet --tiles --tile-size 40 " + job.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::size_t compared = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "out_one")) {
    if (e.path().extension() != ".tif") continue;
    const std::string name = "farm" + e.path().filename().string().substr(3);  // one.<stem>.<layer>.tif
    const Bands one = read_bands(e.path()), farm = read_bands(dir_ / "out_farm" / name);
    ASSERT_FALSE(one.values.empty()) << e.path();
    EXPECT_TRUE(one.values == farm.values) << name;
    ++compared;
  }
  std::size_t merged = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "out_farm")) merged += e.path().extension() == ".tif";
  EXPECT_GE(compared, 6u);  // relief's svf and horizon_deg, each hbao entry's obscurance and bent_normal, ...
  EXPECT_EQ(merged, compared);
}

// A forged tile file, each under the name of the tile it claims to be, with the values and checksum its task
// wrote: a tile of another job (the same heights and entries, another name), another tile of this job,
// another layer's file of the same tile, and the tile with its plan record changed. Merge refuses each in one
// line naming the file, and writes no COG.
TEST_F(CliTiles, MergeRefusesTilesOfAnotherJobTileLayerOrPlan) {
  write_family(150, 97);
  const nlohmann::json height = {{"image", "craters.tif"}};
  const fs::path job = write_job("farm", height, kBounded), copy = write_job("copy", height, kBounded);
  for (const fs::path& j : {job, copy})
    for (const int i : {0, 1, 2})
      ASSERT_EQ(
          hfbake("bake --quiet --tiles --tile-size 40 --tile-task " + std::to_string(i) + "/3 " + j.string())
              .exit_code,
          0);
  const fs::path tiles = dir_ / "out_farm" / "tiles";
  const fs::path target = tiles / "farm+tile-1.relief.svf.tif", kept = dir_ / "kept.tif";
  fs::copy_file(target, kept);
  // The plan record as the task wrote it, with the halo one texel wider.
  const auto other_plan = [&] {
    std::string of = metadata_item(target, "HFBAKE_TILE_OF");
    const std::string halo = "with a halo of ";
    const std::size_t at = of.find(halo);
    if (at == std::string::npos) return;
    const std::size_t n = at + halo.size(), end = of.find_first_not_of("0123456789", n);
    of.replace(n, end - n, std::to_string(std::stoi(of.substr(n, end - n)) + 1));
    CPLPushErrorHandler(CPLQuietErrorHandler);  // GDAL's notes that the file is no longer a COG
    std::unique_ptr<GDALDataset> ds(GDALDataset::Open(target.c_str(), GDAL_OF_RASTER | GDAL_OF_UPDATE));
    ASSERT_TRUE(ds);
    ASSERT_EQ(ds->SetMetadataItem("HFBAKE_TILE_OF", of.c_str()), CE_None);
    ds.reset();
    CPLPopErrorHandler();
  };
  struct Forgery {
    std::string what;
    std::function<void()> make;
  };
  const std::vector<Forgery> forgeries = {
      {"another job's tile",
       [&] {
         fs::copy_file(dir_ / "out_copy" / "tiles" / "copy+tile-1.relief.svf.tif", target,
                       fs::copy_options::overwrite_existing);
       }},
      {"another tile",
       [&] {
         fs::copy_file(tiles / "farm+tile-2.relief.svf.tif", target, fs::copy_options::overwrite_existing);
       }},
      {"another layer",
       [&] {
         fs::copy_file(tiles / "farm+tile-1.hbao-1.obscurance.tif", target,
                       fs::copy_options::overwrite_existing);
       }},
      {"another plan", other_plan},
  };
  for (const Forgery& f : forgeries) {
    SCOPED_TRACE(f.what);
    f.make();
    ASSERT_NE(metadata_item(target, "HFBAKE_TILE_SUM"), "") << "the forgery carries a checksum of its values";
    const Result r = hfbake("merge --quiet --tiles --tile-size 40 " + job.string());
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.err.find(target.string() + ": is not tile 1 of this job"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out_farm" / "farm.relief.svf.tif"));
    for (const auto& e : fs::directory_iterator(dir_ / "out_farm"))  // a COG a merge should not have written
      if (e.path().extension() == ".tif") fs::remove(e.path());
    fs::copy_file(kept, target, fs::copy_options::overwrite_existing);
  }
  const Result r = hfbake("merge --quiet --tiles --tile-size 40 " + job.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// A tile task's files are its job's alone. A job named a.tile-1 baking GeoTIFFs into the tiles/ folder of job
// a, and a's tile tasks, leave each other's files as they wrote them, whichever bakes first, and a's merge
// takes its own tiles. The entries are a sweep whose stems hold a '.' (relief-search_radius2.5).
TEST_F(CliTiles, TileFilesShareNoNameWithAnotherJobsFiles) {
  write_family(150, 97);
  const nlohmann::json height = {{"image", "sines.tif"}};
  const nlohmann::json bake = {
      {{"method", "relief"}, {"directions", 8}, {"search_radius", {2.5, 3}}, {"layers", {"svf"}}}};
  const fs::path a = write_job("a", height, bake);
  const fs::path other =
      write_job("a.tile-1", height, bake, {{"output", {{"dir", "out_a/tiles"}, {"geotiff", true}}}});
  const fs::path tiles = dir_ / "out_a" / "tiles";
  const auto tasks = [&] {
    for (const int i : {0, 1, 2}) {
      const Result r =
          hfbake("bake --quiet --tiles --tile-size 40 --tile-task " + std::to_string(i) + "/3 " + a.string());
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
  };
  // The tile files of a's tasks, and the other job's outputs, by name (the hidden locks and records aside).
  const auto split = [&] {
    std::map<std::string, std::string> own, others;
    for (auto& [name, bytes] : folder_files(tiles))
      if (name[0] != '.') (name.rfind("a+tile-", 0) == 0 ? own : others)[name] = bytes;
    return std::pair{own, others};
  };
  Result r = hfbake("bake --quiet --no-cache " + other.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto baked = split().second;
  ASSERT_TRUE(baked.count("a.tile-1.relief-search_radius2.5.svf.tif")) << "the other job's GeoTIFF";
  tasks();
  const auto [own, others] = split();
  EXPECT_TRUE(others == baked) << "a tile task replaced or removed a file of the other job";
  EXPECT_TRUE(own.count("a+tile-1.relief-search_radius2.5.svf.tif"));
  EXPECT_EQ(own.size(), 12u * 2u) << "12 tiles, each of 2 entries with one layer";
  r = hfbake("bake --quiet --no-cache " + other.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(split().first == own) << "the other job replaced or removed a tile file";
  r = hfbake("merge --quiet --tiles --tile-size 40 " + a.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "out_a" / "a.relief-search_radius2.5.svf.tif"));
}

// Two job files of one name and output folder (other heights) never share tiles/: it holds one job file's
// tiles of that name. Tasks of one job file run at once; a task, a merge, `validate --tiles` or `slurm
// --tiles` of the other is refused in one line naming tiles/ and the job file whose tiles it holds, with
// nothing written; with
// --overwrite it takes the name over. Started at once, 5 times: one job file's task bakes, the other's is
// refused, and tiles/ holds the first's tiles only.
TEST_F(CliTiles, OneJobNameInTilesHasOneJobFile) {
  write_family(150, 97);
  const nlohmann::json same = {{"name", "t"}, {"output", {{"dir", "out_t"}}}};
  const fs::path ja = write_job("ja", {{"image", "craters.tif"}}, kBounded, same);
  const fs::path jb = write_job("jb", {{"image", "terraces.tif"}}, kBounded, same);
  const fs::path tiles = dir_ / "out_t" / "tiles";
  const auto task = [](const fs::path& job, int i, const std::string& more = "") {
    return "bake --quiet --tiles --tile-size 40 --tile-task " + std::to_string(i) + "/3 " + more +
           job.string();
  };
  const auto owned_by = [&](const fs::path& job) {
    return "/name: the tiles of job t in " + tiles.string() + " were baked from " +
           fs::canonical(job).string() + ": give this job another name or output folder, or give --overwrite";
  };
  const auto start = [&](const fs::path& job, int i, const std::string& err) {
    return hfbake_test::start_hfbake({"bake", "--quiet", "--tiles", "--tile-size", "40", "--tile-task",
                                      std::to_string(i) + "/3", job.string()},
                                     dir_ / err, dir_, 300);
  };
  // One job file's tasks, all at once.
  std::vector<pid_t> pids;
  for (const int i : {0, 1, 2}) pids.push_back(start(ja, i, "task" + std::to_string(i) + ".txt"));
  for (const pid_t pid : pids) EXPECT_EQ(hfbake_test::wait_exit(pid), 0);
  const auto baked = folder_files(tiles);
  // The other job file: its task, merge, validate --tiles and slurm --tiles (before anything is submitted)
  // are refused, naming the owner.
  for (const std::string& command : {task(jb, 1), "merge --quiet --tiles --tile-size 40 " + jb.string(),
                                     "validate --quiet --tiles --tile-size 40 " + jb.string(),
                                     "slurm --dry-run --tiles --tile-size 40 --shards 3 " + jb.string()}) {
    SCOPED_TRACE(command);
    const Result r = hfbake(command);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find(jb.string() + ": " + owned_by(ja)), std::string::npos) << r.err;
    EXPECT_TRUE(folder_files(tiles) == baked) << "a refused job file changed tiles/";
    EXPECT_FALSE(fs::exists(dir_ / "out_t" / "t.relief.svf.tif"));
  }
  Result r = hfbake("merge --quiet --tiles --tile-size 40 " + ja.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // --overwrite takes the name over: then the first job file is refused, and its merge (with --overwrite
  // too) refuses the tile the other baked.
  r = hfbake(task(jb, 0, "--overwrite "));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = hfbake(task(ja, 0));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find(ja.string() + ": " + owned_by(jb)), std::string::npos) << r.err;
  r = hfbake("merge --quiet --overwrite --tiles --tile-size 40 " + ja.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find((tiles / "t+tile-0.").string()), std::string::npos) << r.err;
  EXPECT_NE(r.error_lines()[0].find(": is not tile 0 of this job"), std::string::npos) << r.err;
  // Raced: the first task to claim the name bakes; the other is refused and writes no tile.
  for (int run = 0; run < 5; ++run) {
    SCOPED_TRACE(run);
    fs::remove_all(dir_ / "out_t");
    const pid_t pa = start(ja, 0, "a.txt"), pb = start(jb, 1, "b.txt");
    const int ea = hfbake_test::wait_exit(pa), eb = hfbake_test::wait_exit(pb);
    ASSERT_TRUE((ea == 0 && eb == 2) || (ea == 2 && eb == 0)) << ea << " " << eb;
    const fs::path& winner = ea == 0 ? ja : jb;
    std::ifstream lost(dir_ / (ea == 0 ? "b.txt" : "a.txt"));
    std::stringstream err;
    err << lost.rdbuf();
    EXPECT_NE(err.str().find(owned_by(winner)), std::string::npos) << err.str();
    // Task 0 bakes tiles 0..3 of 12, task 1 tiles 4..7.
    const char first = ea == 0 ? '0' : '4';
    std::size_t tile_files = 0;
    for (const auto& [name, bytes] : folder_files(tiles)) {
      if (name.rfind("t+tile-", 0) != 0) continue;
      ++tile_files;
      EXPECT_TRUE(name[7] >= first && name[7] < first + 4 && name[8] == '.')
          << name << " is not the winner's";
    }
    EXPECT_GT(tile_files, 0u);
  }
}

// tiles/ or the tiles' lock name taken by a link: validate --tiles, a tile task and a merge refuse the job in
// one line naming the job file and /output/dir, and the link's target stays empty.
TEST_F(CliTiles, ALinkInPlaceOfTilesIsRefused) {
  write_heights(dir_ / "f.tif", 40, 30, [](int i, int j) { return 0.1 * i * j; });
  const fs::path job = write_job("t", {{"image", "f.tif"}}, {{{"method", "relief"}, {"search_radius", 2}}});
  const fs::path out = dir_ / "out_t", target = dir_ / "elsewhere";
  fs::create_directories(out / "tiles");
  fs::create_directories(target);
  for (const fs::path& link : {out / "tiles" / ".hfbake-t+tiles.lock", out / "tiles"}) {
    SCOPED_TRACE(link.string());
    if (link == out / "tiles") fs::remove_all(link);
    fs::create_directory_symlink(target, link);
    for (const std::string command :
         {"validate --quiet --tiles --tile-size 16 ", "bake --quiet --tiles --tile-size 16 --tile-task 0/1 ",
          "merge --quiet --tiles --tile-size 16 "}) {
      SCOPED_TRACE(command);
      const Result r = hfbake(command + job.string());
      EXPECT_EQ(r.exit_code, 2) << r.err;
      ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
      EXPECT_NE(r.error_lines()[0].find(job.string() + ": /output/dir: " + link.string() + " is "),
                std::string::npos)
          << r.err;
      EXPECT_TRUE(fs::is_empty(target));
    }
    fs::remove(link);
  }
}

// A tile task whose windows hold a hole is refused in one line naming the raster's texel, before it claims
// the job's name in tiles/: the output folder is left as it was (no tiles/, no record).
TEST_F(CliTiles, ATileTaskWithAHoleIsRefusedBeforeItClaimsTheTiles) {
  write_heights(dir_ / "f.tif", 40, 30, [](int i, int j) { return i == 7 && j == 5 ? NAN : 0.1 * i * j; });
  const fs::path job = write_job("t", {{"image", "f.tif"}}, {{{"method", "relief"}, {"search_radius", 2}}});
  const Result r = hfbake("bake --quiet --no-cache --tiles --tile-size 16 --tile-task 0/1 " + job.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("texel (7, 5) has no valid height"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out_t" / "tiles")) << "the refused task claimed tiles/";
}

// A tiled bake writes no previews (output.previews is for a whole bake): its plan is the same with previews
// on as off, and with a memory limit that fits its tiles without OpenImageIO's libraries it is not refused
// for a preview it never writes; no preview file appears.
TEST_F(CliTiles, PreviewsAreNotCountedByATiledBakeThatWritesNone) {
  write_heights(dir_ / "f.tif", 256, 256, [](int i, int j) { return 0.05 * i + 0.1 * std::sin(0.2 * j); });
  const nlohmann::json bake = {{{"method", "relief"}, {"directions", 16}, {"search_radius", 10}}};
  std::string plans[2];
  for (const bool previews : {false, true}) {
    const std::string name = previews ? "on" : "off";
    const fs::path job =
        write_job(name, {{"image", "f.tif"}}, bake,
                  {{"output", {{"dir", "out_" + name}, {"geotiff", true}, {"previews", previews}}}});
    const Result v = hfbake("validate --tiles --memory-limit 200M " + job.string());
    ASSERT_EQ(v.exit_code, 0) << v.err;
    plans[previews] = v.err.substr(v.err.find("valid ("));
    const Result b = hfbake("bake --quiet --tiles --memory-limit 200M " + job.string());
    ASSERT_EQ(b.exit_code, 0) << b.err;
    for (const fs::directory_entry& e : fs::directory_iterator(dir_ / ("out_" + name)))
      EXPECT_EQ(e.path().string().find(".preview.png"), std::string::npos) << e.path();
  }
  EXPECT_EQ(plans[0], plans[1]);
}

// A folder at the job's tiles record or at one of its tile files' names: validate and the tile task refuse
// the job at /output/dir before baking, naming the folder, which is kept.
TEST_F(CliTiles, AFolderAtATileFilesNameIsRefused) {
  write_heights(dir_ / "f.tif", 40, 30, [](int i, int j) { return 0.1 * i * j; });
  const fs::path job = write_job("t", {{"image", "f.tif"}}, {{{"method", "relief"}, {"search_radius", 2}}});
  const fs::path tiles = dir_ / "out_t" / "tiles";
  for (const std::string name : {".hfbake-t+tiles.job", "t+tile-1.relief.svf.tif"}) {
    SCOPED_TRACE(name);
    fs::create_directories(tiles / name);
    for (const std::string command : {"validate --quiet --tiles --tile-size 16 ",
                                      "bake --quiet --tiles --tile-size 16 --tile-task 0/1 "}) {
      SCOPED_TRACE(command);
      const Result r = hfbake(command + job.string());
      EXPECT_EQ(r.exit_code, 2) << r.err;
      ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
      EXPECT_NE(r.error_lines()[0].find(job.string() + ": /output/dir: " + (tiles / name).string() +
                                        " is a folder where an output goes"),
                std::string::npos)
          << r.err;
      EXPECT_TRUE(fs::is_directory(tiles / name));
    }
    for (const fs::directory_entry& e : fs::directory_iterator(tiles))
      EXPECT_EQ(e.path().filename(), name) << "a tile task wrote " << e.path();
    fs::remove_all(tiles / name);
  }
}

// The heights lying where the job's tile task would write a tile file, or its tiles record: validate refuses
// the job naming the key, and the file is kept.
TEST_F(CliTiles, AnInputWhereATileTaskWritesIsRefused) {
  fs::create_directories(dir_ / "out_t" / "tiles");
  for (const std::string name : {"t+tile-0.relief.svf.tif", ".hfbake-t+tiles.job"}) {
    SCOPED_TRACE(name);
    const fs::path input = dir_ / "out_t" / "tiles" / name;
    write_heights(input, 40, 30, [](int i, int j) { return 0.1 * i * j; });
    const fs::path job =
        write_job("t", {{"image", input.string()}}, {{{"method", "relief"}, {"search_radius", 2}}});
    const Result r = hfbake("validate --quiet --tiles --tile-size 16 " + job.string());
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find(job.string() + ": /height/image: " + input.string() +
                                      " is where this job writes an output"),
              std::string::npos)
        << r.err;
    EXPECT_TRUE(fs::exists(input));
    fs::remove(input);
  }
}

// Each refusal: exit 2, one error line naming the job file and `pointer`, and no output folder.
TEST_F(CliTiles, RefusalsAreOneLineAndWriteNothing) {
  write_heights(dir_ / "f.tif", 40, 30, [](int i, int j) { return 0.1 * i * j; });
  // f.tif resampled to 12000^2: its coarse copy of cells of one texel, 8 bytes a cell, fills 1 GiB alone.
  std::ofstream(dir_ / "big.vrt")
      << "<VRTDataset rasterXSize=\"12000\" rasterYSize=\"12000\"><GeoTransform>400000, 0.5, 0, 100000, 0, "
         "-0.5</GeoTransform><VRTRasterBand dataType=\"Float32\" band=\"1\"><SimpleSource><SourceFilename "
         "relativeToVRT=\"1\">f.tif</SourceFilename><SourceBand>1</SourceBand><SrcRect xOff=\"0\" yOff=\"0\" "
         "xSize=\"40\" ySize=\"30\"/><DstRect xOff=\"0\" yOff=\"0\" xSize=\"12000\" ySize=\"12000\"/>"
         "</SimpleSource></VRTRasterBand></VRTDataset>\n";
  const nlohmann::json relief = {{{"method", "relief"}, {"search_radius", 3}}};
  const nlohmann::json far = {
      {{"method", "relief"}, {"search_radius", 3}, {"far_field", {{"beyond", 2}, {"cell", 1}}}}};
  struct Case {
    std::string name;
    nlohmann::json height, bake, extra;
    std::string pointer, args;
  };
  const std::vector<Case> cases = {
      {"p1", {{"image", "f.tif"}}, {{{"method", "p1"}, {"directions", 8}}}, {}, "/bake/0", ""},
      {"nlp", {{"image", "f.tif"}}, {{{"method", "nlp"}}}, {}, "/bake/0/method", ""},
      {"sun",
       {{"image", "f.tif"}},
       {{{"method", "sun"},
         {"start", "2026-06-21T05:00"},
         {"end", "2026-06-21T19:00"},
         {"utc_offset", 2},
         {"latitude", 46.5},
         {"longitude", 15.0}}},
       {},
       "/bake/0",
       ""},
      {"unbounded",
       {{"image", "f.tif"}},
       {{{"method", "hbao"}, {"directions", 8}, {"max_distance", 1e6}}},
       {},
       "/bake/0",
       ""},
      {"procedural", {{"procedural", {{"kind", "fractal"}, {"size", {32, 32}}}}}, relief, {}, "/height", ""},
      {"fill", {{"image", "f.tif"}, {"nodata", "fill"}}, relief, {}, "/height/nodata", ""},
      {"repeat", {{"image", "f.tif"}, {"wrap", "repeat"}}, relief, {}, "/height/wrap", ""},
      {"nogeotiff", {{"image", "f.tif"}}, relief, {{"output", {{"geotiff", false}}}}, "/output/geotiff", ""},
      {"reference", {{"image", "f.tif"}}, relief, {{"reference", {{"samples", 4}}}}, "/reference", ""},
      {"budget", {{"image", "f.tif"}}, relief, {}, "/height", "--memory-limit 100M"},
      {"tile_size", {{"image", "f.tif"}}, relief, {}, "/height", "--tile-size 16 --memory-limit 100M"},
      {"coarse", {{"image", "big.vrt"}}, far, {}, "/height", "--memory-limit 1G"},
      // A 64-direction horizon_deg: its COG's 64 bands hold 5 MiB each while it is written, after the tiles.
      {"wide_cog",
       {{"image", "f.tif"}},
       {{{"method", "relief"}, {"search_radius", 3}, {"directions", 64}, {"layers", {"horizon_deg"}}}},
       {},
       "/output/geotiff",
       "--memory-limit 300M"},
  };
  for (const Case& c : cases)
    for (const char* command : {"validate", "bake"}) {
      SCOPED_TRACE(c.name + " " + command);
      const fs::path job = write_job(c.name, c.height, c.bake, c.extra);
      const Result r = hfbake(std::string(command) + " --quiet --tiles " + c.args + " " + job.string());
      EXPECT_EQ(r.exit_code, 2) << r.err;
      const std::vector<std::string> lines = r.error_lines();
      ASSERT_EQ(lines.size(), 1u) << r.err;
      EXPECT_NE(lines[0].find(job.string() + ": " + c.pointer + ":"), std::string::npos) << lines[0];
      EXPECT_FALSE(fs::exists(dir_ / ("out_" + c.name))) << "a refused tiled bake made its output folder";
    }
  // The far field's coarse copy is what does not fit: 12000^2 cells of 8 bytes.
  const Result coarse =
      hfbake("validate --quiet --tiles --memory-limit 1G " + (dir_ / "coarse.json").string());
  EXPECT_NE(coarse.err.find("coarse copies of the raster (about 1099 MiB) and GDAL's block cache"),
            std::string::npos)
      << coarse.err;
  const Result wide =
      hfbake("validate --quiet --tiles --memory-limit 300M " + (dir_ / "wide_cog.json").string());
  EXPECT_NE(wide.err.find("writing the COG of layer horizon_deg (64 bands) holds about"), std::string::npos)
      << wide.err;
  EXPECT_EQ(
      hfbake("validate --quiet --tiles --memory-limit 500M " + (dir_ / "wide_cog.json").string()).exit_code,
      0);
  // The same raster and method as a valid job: validate says so, with the halo of 3 m on 0.5 m texels.
  const Result ok =
      hfbake("validate --tiles --tile-size 16 " + write_job("ok", {{"image", "f.tif"}}, relief).string());
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_NE(ok.err.find("valid (40x30 in 6 tiles (3 x 2) of 16^2 texels with a halo of 8)"),
            std::string::npos)
      << ok.err;
}

// A hole in a tile: refused naming the texel in the raster's coordinates, nothing written.
TEST_F(CliTiles, HoleIsRefusedNamingTheRasterTexel) {
  write_heights(dir_ / "hole.tif", 64, 48, [](int i, int j) { return i == 50 && j == 40 ? NAN : 0.1 * i; });
  const fs::path job =
      write_job("hole", {{"image", "hole.tif"}}, {{{"method", "relief"}, {"search_radius", 2}}});
  for (const char* command : {"validate", "bake"}) {
    const Result r = hfbake(std::string(command) + " --quiet --tiles --tile-size 16 " + job.string());
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const std::vector<std::string> lines = r.error_lines();
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_NE(lines[0].find("/height/image: "), std::string::npos) << lines[0];
    EXPECT_NE(lines[0].find("texel (50, 40)"), std::string::npos) << lines[0];
  }
  EXPECT_FALSE(fs::exists(dir_ / "out_hole" / "hole.relief.svf.tif"));
}

}  // namespace
