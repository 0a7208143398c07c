// hfbake with georeferenced rasters, end to end (the binary): the pixel size of a GeoTIFF is the texel
// size, its NoData value makes holes, geographic CRSs and non-square pixels are refused in one line,
// output.geotiff writes Cloud-Optimised GeoTIFFs georeferenced like the input, and the sun method takes its
// place and true north from the CRS. The truth is GDAL's own tools (gdal_translate makes the variants,
// gdalinfo reads the outputs), OGR's transforms, and a bake of the same heights as an EXR with the texel
// size given by hand.
#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <ogr_spatialref.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>
#include "run_hfbake.hpp"

#include <OpenImageIO/imageio.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "../io/gdal_tool.hpp"

namespace {
namespace fs = std::filesystem;
using hfbake::test::gdalinfo_json;
using hfbake::test::run_tool;

const fs::path kData = HFBAKE_SHARED_DATA_DIR;
const fs::path kDem = kData / "TM1_564_146.tif";

using hfbake::cli_test::Result;

struct Raster {
  int width = 0, height = 0;
  std::vector<float> values;
  std::array<double, 6> gt{};
  std::optional<double> nodata;
};

Raster read_raster(const fs::path& file, int band = 1) {
  Raster r;
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER));
  if (!ds) return r;
  r.width = ds->GetRasterXSize();
  r.height = ds->GetRasterYSize();
  ds->GetGeoTransform(r.gt.data());
  GDALRasterBand* b = ds->GetRasterBand(band);
  int has = 0;
  const double nd = b->GetNoDataValue(&has);
  if (has) r.nodata = nd;
  r.values.resize(std::size_t(r.width) * r.height);
  if (b->RasterIO(GF_Read, 0, 0, r.width, r.height, r.values.data(), r.width, r.height, GDT_Float32, 0, 0,
                  nullptr) != CE_None)
    r.values.clear();
  return r;
}

class CliGdal : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kDem))
      GTEST_SKIP() << "no real DEM in " << kData << " (the shared data folder is absent)";
    if (!hfbake::test::have_gdal_tools()) GTEST_SKIP() << "GDAL's tools not found (apt-get install gdal-bin)";
    GDALAllRegister();
    dir_ = fs::temp_directory_path() / ("hfbake_test_cli_gdal_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }

  Result hfbake(const std::string& args) { return hfbake::cli_test::run_hfbake(dir_, args); }

  // gdal_translate ARGS (file names relative to the test folder); fails the test when the tool does.
  void translate(const std::string& args) {
    int status = -1;
    run_tool("cd '" + dir_.string() + "' && gdal_translate -q " + args, &status);
    ASSERT_EQ(status, 0) << "gdal_translate " << args;
  }

  // gdalwarp -q -r bilinear -dstnodata -9999 ARGS (file names relative to the test folder); fails the test
  // when the tool does.
  void warp(const std::string& args) {
    int status = -1;
    run_tool("cd '" + dir_.string() + "' && gdalwarp -q -r bilinear -dstnodata -9999 " + args, &status);
    ASSERT_EQ(status, 0) << "gdalwarp " << args;
  }

  fs::path write_job(const std::string& file, const std::string& name, const nlohmann::json& height,
                     int directions = 16) {
    const nlohmann::json j = {
        {"version", 1},
        {"name", name},
        {"height", height},
        {"bake", {{{"method", "p1"}, {"directions", directions}, {"layers", {"ao", "vsky"}}}}},
        {"output", {{"dir", "out_" + name}, {"geotiff", true}, {"pixel_type", "float"}}}};
    const fs::path p = dir_ / file;
    std::ofstream(p) << j.dump(2);
    return p;
  }

  // The 1 m DEM cut to a 160 x 160 window (georeferencing kept), and the same pixels as a 2 m raster.
  void make_crops() {
    translate("-srcwin 400 400 160 160 '" + kDem.string() + "' dem1m.tif");
    const Raster r = read_raster(dir_ / "dem1m.tif");
    const double x0 = r.gt[0], y0 = r.gt[3];
    translate("-a_ullr " + std::to_string(x0) + " " + std::to_string(y0) + " " + std::to_string(x0 + 320) +
              " " + std::to_string(y0 - 320) + " dem1m.tif dem2m.tif");
  }

  // An n x n float32 GeoTIFF of `z` (row-major) in the D96/TM CRS (EPSG:3794) with geotransform `gt`.
  void write_d96_raster(const std::string& name, int n, const std::vector<float>& z, const double (&gt)[6]) {
    GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
    GDALDataset* ds = gtiff->Create((dir_ / name).c_str(), n, n, 1, GDT_Float32, nullptr);
    ASSERT_TRUE(ds);
    double g[6];
    std::copy(gt, gt + 6, g);
    ds->SetGeoTransform(g);
    OGRSpatialReference srs;
    srs.importFromEPSG(3794);
    ds->SetSpatialRef(&srs);
    EXPECT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, n, n, const_cast<float*>(z.data()), n, n,
                                             GDT_Float32, 0, 0, nullptr),
              CE_None);
    GDALClose(ds);
  }

  fs::path dir_;
};

double max_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
  double m = 0;
  for (std::size_t t = 0; t < a.size(); ++t) m = std::max(m, double(std::abs(a[t] - b[t])));
  return m;
}

TEST_F(CliGdal, PixelSizeIsTheDefaultTexelSize) {
  make_crops();
  // gdalinfo says the copy's pixels are 2 m: the truth for what hfbake must use.
  ASSERT_EQ(gdalinfo_json(dir_ / "dem2m.tif")["geoTransform"][1].get<double>(), 2.0);
  Result r = hfbake("bake --quiet " + write_job("a.json", "m1", {{"image", "dem1m.tif"}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = hfbake("bake --quiet " + write_job("b.json", "m2", {{"image", "dem2m.tif"}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Raster ao1 = read_raster(dir_ / "out_m1" / "m1.p1.ao.tif");
  const Raster ao2 = read_raster(dir_ / "out_m2" / "m2.p1.ao.tif");
  ASSERT_EQ(ao1.values.size(), 160u * 160u);
  ASSERT_EQ(ao2.values.size(), 160u * 160u);
  EXPECT_GT(max_abs_diff(ao1.values, ao2.values), 0.01) << "the 2 m copy baked like the 1 m one";
  EXPECT_EQ(ao2.gt[1], 2.0);
  EXPECT_EQ(ao2.gt[5], -2.0);

  // The same heights as an EXR (no georeferencing: OpenImageIO) with texel_size 2 by hand: the same ao.
  const Raster heights = read_raster(dir_ / "dem1m.tif");
  {
    auto out = OIIO::ImageOutput::create((dir_ / "dem.exr").string());
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(160, 160, 1, OIIO::TypeDesc::FLOAT);
    ASSERT_TRUE(out->open((dir_ / "dem.exr").string(), spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, heights.values.data()));
    out->close();
  }
  r = hfbake("bake --quiet " +
             write_job("c.json", "e2", {{"image", "dem.exr"}, {"texel_size", 2.0}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Raster exr2 = read_raster(dir_ / "out_e2" / "e2.p1.ao.tif");
  EXPECT_EQ(max_abs_diff(exr2.values, ao2.values), 0.0);
  // Without a CRS: the local geotransform, pixel size = texel_size.
  EXPECT_EQ(exr2.gt[1], 2.0);
  EXPECT_EQ(exr2.gt[0], -1.0);

  // A job value that agrees is fine, one that disagrees is refused (validate as bake), in one line.
  r = hfbake("validate " +
             write_job("d.json", "m1b", {{"image", "dem1m.tif"}, {"texel_size", 1.0}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = hfbake("validate " +
             write_job("f.json", "m1c", {{"image", "dem1m.tif"}, {"texel_size", "from_file"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const fs::path bad = write_job("g.json", "m2b", {{"image", "dem2m.tif"}, {"texel_size", 1.0}});
  for (const char* cmd : {"validate ", "bake "}) {
    r = hfbake(cmd + bad.string());
    EXPECT_EQ(r.exit_code, 2) << cmd;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_EQ(
        r.error_lines()[0].rfind("hfbake: error: " + bad.string() +
                                     ": /height/texel_size: is 1 but the pixel size of dem2m.tif is 2 metre",
                                 0),
        0u)
        << r.err;
  }
  // "from_file" needs a file with a geotransform.
  const fs::path exr_from_file =
      write_job("h.json", "e3", {{"image", "dem.exr"}, {"texel_size", "from_file"}});
  r = hfbake("validate " + exr_from_file.string());
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("/height/texel_size: is \"from_file\" but dem.exr has no georeferencing"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out_m2b"));
}

TEST_F(CliGdal, OutputsHaveTheInputsCrsAndGeotransformAndAreCogs) {
  make_crops();
  const Result r = hfbake("bake --quiet " + write_job("a.json", "m1", {{"image", "dem1m.tif"}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json input = gdalinfo_json(dir_ / "dem1m.tif");
  for (const char* layer : {"ao", "vsky"}) {
    const fs::path tif = dir_ / "out_m1" / (std::string("m1.p1.") + layer + ".tif");
    const nlohmann::json out = gdalinfo_json(tif);
    ASSERT_TRUE(out.is_object()) << tif;
    EXPECT_EQ(out["geoTransform"], input["geoTransform"]);
    OGRSpatialReference a, b;
    ASSERT_EQ(a.importFromWkt(out["coordinateSystem"]["wkt"].get<std::string>().c_str()), OGRERR_NONE);
    ASSERT_EQ(b.importFromWkt(input["coordinateSystem"]["wkt"].get<std::string>().c_str()), OGRERR_NONE);
    EXPECT_TRUE(a.IsSame(&b));
    EXPECT_EQ(out["metadata"]["IMAGE_STRUCTURE"]["LAYOUT"], "COG");
    EXPECT_EQ(out["bands"][0]["type"], "Float32");
    EXPECT_FALSE(out["bands"][0].contains("noDataValue")) << "no holes, no NoData tag";
    EXPECT_NE(out["metadata"][""]["HFBAKE_AZIMUTH_CONVENTION"].get<std::string>().find(
                  "compass azimuth = (90 + phi) mod 360"),
              std::string::npos);
    EXPECT_EQ(out["metadata"][""].value("HFBAKE_TEXEL_SIZE", ""), "1 1");  // as the EXR's hfbake:texel_size
  }
  // Values equal the EXR's (float EXR, read with OpenImageIO).
  auto in = OIIO::ImageInput::open((dir_ / "out_m1" / "m1.p1.exr").string());
  ASSERT_TRUE(in);
  const OIIO::ImageSpec& spec = in->spec();
  int c = -1;
  for (int k = 0; k < spec.nchannels; ++k)
    if (spec.channelnames[k] == "ao.Y") c = k;
  ASSERT_GE(c, 0);
  std::vector<float> exr(160 * 160);
  ASSERT_TRUE(in->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, exr.data()));
  EXPECT_EQ(max_abs_diff(exr, read_raster(dir_ / "out_m1" / "m1.p1.ao.tif").values), 0.0);
}

TEST_F(CliGdal, NodataValueOfTheFileMakesHoles) {
  // The nodata variant with its NaN holes stored as -9999 and declared as the NoData value: what a GIS
  // export looks like. The NaN texels of the original are the truth for where the holes are.
  const Raster nan = read_raster(kData / "TM1_564_146_nodata.tif");
  ASSERT_EQ(nan.values.size(), 1000u * 1000u);
  std::vector<float> z = nan.values;
  std::size_t holes = 0;
  for (float& v : z)
    if (std::isnan(v)) v = -9999.0f, ++holes;
  ASSERT_GT(holes, 0u);
  {
    GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
    std::unique_ptr<GDALDataset> src(
        GDALDataset::Open((kData / "TM1_564_146_nodata.tif").c_str(), GDAL_OF_RASTER));
    GDALDataset* ds = gtiff->Create((dir_ / "minus9999.tif").c_str(), 1000, 1000, 1, GDT_Float32, nullptr);
    ASSERT_TRUE(ds);
    std::array<double, 6> gt = nan.gt;
    ds->SetGeoTransform(gt.data());
    ds->SetSpatialRef(src->GetSpatialRef());
    ds->GetRasterBand(1)->SetNoDataValue(-9999);
    ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 1000, 1000, z.data(), 1000, 1000, GDT_Float32, 0,
                                             0, nullptr),
              CE_None);
    GDALClose(ds);
  }
  ASSERT_EQ(gdalinfo_json(dir_ / "minus9999.tif")["bands"][0]["noDataValue"].get<double>(), -9999.0);

  // Without "nodata": "fill" the holes are an error (validate as bake), one line.
  const fs::path refused = write_job("a.json", "refused", {{"image", "minus9999.tif"}}, 4);
  for (const char* cmd : {"validate ", "bake "}) {
    const Result r = hfbake(cmd + refused.string());
    EXPECT_EQ(r.exit_code, 2) << cmd;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find("/height/image: minus9999.tif: texel ("), std::string::npos) << r.err;
    EXPECT_NE(r.error_lines()[0].find("the file's NoData value (-9999"), std::string::npos) << r.err;
    EXPECT_NE(r.error_lines()[0].find("(" + std::to_string(holes) + " of 1000000 texels"), std::string::npos)
        << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out_refused" / "refused.p1.exr"));

  // With "fill", validate's heights line says how many texels are filled.
  {
    const Result v =
        hfbake("validate " +
               write_job("v.json", "counted", {{"image", "minus9999.tif"}, {"nodata", "fill"}}, 4).string());
    ASSERT_EQ(v.exit_code, 0) << v.err;
    EXPECT_NE(v.err.find("; " + std::to_string(holes) + " texels without a height ("), std::string::npos)
        << v.err;
  }
  // With "fill": holes, not pits. The GeoTIFF has NoData exactly at the holes, and every other texel
  // equals the bake of the NaN original (the same holes, filled the same way).
  Result r =
      hfbake("bake --quiet " +
             write_job("b.json", "filled", {{"image", "minus9999.tif"}, {"nodata", "fill"}}, 4).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = hfbake("bake --quiet " +
             write_job("c.json", "nan",
                       {{"image", (kData / "TM1_564_146_nodata.tif").string()}, {"nodata", "fill"}}, 4)
                 .string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Raster filled = read_raster(dir_ / "out_filled" / "filled.p1.ao.tif");
  const Raster from_nan = read_raster(dir_ / "out_nan" / "nan.p1.ao.tif");
  ASSERT_EQ(filled.values.size(), z.size());
  ASSERT_TRUE(filled.nodata);
  EXPECT_EQ(*filled.nodata, -9999.0);
  std::size_t marked = 0;
  for (std::size_t t = 0; t < z.size(); ++t) {
    if (std::isnan(nan.values[t])) {
      ASSERT_EQ(filled.values[t], -9999.0f) << t;
      ++marked;
    } else {
      ASSERT_EQ(filled.values[t], from_nan.values[t]) << t;
      ASSERT_GE(filled.values[t], 0.0f);
      ASSERT_LE(filled.values[t], 1.0f + 1e-5f);
    }
  }
  EXPECT_EQ(marked, holes);
  // The ao next to a hole is not that of a pit: -9999 m wells would black out their neighbours.
  double lowest = 1;
  for (std::size_t t = 0; t < z.size(); ++t)
    if (!std::isnan(nan.values[t])) lowest = std::min(lowest, double(filled.values[t]));
  EXPECT_GT(lowest, 0.2);
}

// A geographic raster bakes in its local frame with the methods that take rectangular texels and the
// Earth's curvature; the others (and p1's directional lights), a raster spanning too much latitude or
// reaching a pole, one whose CRS is in grads, a texel_size given in the job and a refraction without
// curvature are refused in one line naming the file and field.
TEST_F(CliGdal, GeographicRastersAreCheckedInOneLine) {
  translate("-srcwin 0 0 64 64 -a_srs EPSG:4326 -a_ullr 15.0 46.5 15.001 46.499 '" + kDem.string() +
            "' degrees.tif");
  // 1.2 degrees of latitude around 46.5: the east-west scale is 1.1 % off at the edge rows.
  translate("-srcwin 0 0 64 64 -a_srs EPSG:4326 -a_ullr 15.0 47.1 15.001 45.9 '" + kDem.string() +
            "' tall.tif");
  translate("-srcwin 0 0 64 64 -a_srs EPSG:4326 -a_ullr 15.0 89.95 15.1 89.92 '" + kDem.string() +
            "' pole.tif");
  // NTF (Paris): a geographic CRS in grads, read as degrees it would put the field 5 degrees north.
  translate("-srcwin 0 0 64 64 -a_srs EPSG:4807 -a_ullr 0.5 52.0 0.501 51.999 '" + kDem.string() +
            "' grads.tif");
  auto relief_job = [&](const std::string& file, const std::string& name, nlohmann::json height) {
    const nlohmann::json j = {{"version", 1},
                              {"name", name},
                              {"height", height},
                              {"bake", {{{"method", "relief"}, {"directions", 8}, {"search_radius", 5}}}},
                              {"output", {{"dir", "out_" + name}}}};
    std::ofstream(dir_ / file) << j.dump(2);
    return dir_ / file;
  };
  auto method_job = [&](const std::string& file, const std::string& name, const char* method) {
    const nlohmann::json j = {{"version", 1},
                              {"name", name},
                              {"height", {{"image", "degrees.tif"}}},
                              {"bake", {{{"method", method}, {"directions", 8}}}},
                              {"output", {{"dir", "out_" + name}}}};
    std::ofstream(dir_ / file) << j.dump(2);
    return dir_ / file;
  };
  struct Case {
    fs::path job;
    std::string line;  // the error line's start after "hfbake: error: <job>: "
  };
  const Case cases[] = {
      {method_job("hbao.json", "deg", "hbao"), "/bake/0/method: hbao needs square texels"},
      {method_job("p1.json", "p1", "p1"), "/bake/0/lights: is on (the default) with the direct layer"},
      {relief_job("tall.json", "tall", {{"image", "tall.tif"}}),
       "/height/image: " + (dir_ / "tall.tif").string() + ": spans latitudes"},
      {relief_job("pole.json", "pole", {{"image", "pole.tif"}}),
       "/height/image: " + (dir_ / "pole.tif").string() + ": its rows reach latitude"},
      {relief_job("grads.json", "grads", {{"image", "grads.tif"}}),
       "/height/image: " + (dir_ / "grads.tif").string() +
           ": has a geographic CRS (NTF (Paris)) in grads, not degrees"},
      {relief_job("texel.json", "texel", {{"image", "degrees.tif"}, {"texel_size", 1.0}}),
       "/height/texel_size: is given, but degrees.tif has a geographic CRS"},
      {relief_job("flat.json", "flat", {{"image", "degrees.tif"}, {"curvature", false}, {"refraction", 0.1}}),
       "/height/refraction: applies with Earth curvature only"},
  };
  for (const Case& c : cases)
    for (const char* cmd : {"validate ", "bake "}) {
      const Result r = hfbake(cmd + c.job.string());
      EXPECT_EQ(r.exit_code, 2) << cmd << c.job;
      ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
      EXPECT_EQ(r.error_lines()[0].rfind("hfbake: error: " + c.job.string() + ": " + c.line, 0), 0u) << r.err;
    }
  EXPECT_FALSE(fs::exists(dir_ / "out_deg"));
  // relief validates, and validate states the local frame's texel (0.001 / 64 degrees: 1.20 x 1.74 m at
  // 46.5 N on WGS 84) and the curvature, on by default.
  const Result r = hfbake("validate " + relief_job("ok.json", "ok", {{"image", "degrees.tif"}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("64x64 texels of 1.19"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("a geographic raster in the local frame at latitude 46.4995"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("Earth curvature on (refraction 0.13"), std::string::npos) << r.err;
  // The EXR records the texel's two sides: the WGS 84 ellipsoid's radii of curvature at the raster's centre
  // latitude times the pixel's 0.001 / 64 degrees of longitude and of latitude.
  const Result b = hfbake("bake " + (dir_ / "ok.json").string() + " --quiet");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  auto in = OIIO::ImageInput::open((dir_ / "out_ok" / "ok.relief.exr").string());
  ASSERT_TRUE(in);
  std::istringstream sides(in->spec().get_string_attribute("hfbake:texel_size"));
  double sx = 0, sy = 0;
  sides >> sx >> sy;
  const double a = 6378137.0, e2 = 0.00669437999014, lat = 46.4995 * M_PI / 180,
               step = 0.001 / 64 * M_PI / 180;
  const double w = 1 - e2 * std::sin(lat) * std::sin(lat);
  EXPECT_NEAR(sx, a / std::sqrt(w) * std::cos(lat) * step, 1e-3)
      << in->spec().get_string_attribute("hfbake:texel_size");
  EXPECT_NEAR(sy, a * (1 - e2) / (w * std::sqrt(w)) * step, 1e-3)
      << in->spec().get_string_attribute("hfbake:texel_size");
}

// A geographic raster whose pixel is 10 x 10 m in its local frame (WGS 84's radii of curvature at its
// centre latitude, 45.99525 N) up to the frame's rounding has square texels: a square-texel method bakes it.
TEST_F(CliGdal, AGeographicRasterSizedSquareHasSquareTexels) {
  const double dlon = 0.00012908235150332906, dlat = 8.996751886820413e-05, lat = 45.995252219470;
  char ullr[160];
  std::snprintf(ullr, sizeof ullr, "-a_ullr 15.0 %.15f %.15f %.15f", lat + 32 * dlat, 15.0 + 64 * dlon,
                lat - 32 * dlat);
  translate("-srcwin 0 0 64 64 -a_srs EPSG:4326 " + std::string(ullr) + " '" + kDem.string() +
            "' square.tif");
  const nlohmann::json j = {{"version", 1},
                            {"name", "sq"},
                            {"height", {{"image", "square.tif"}, {"curvature", false}}},
                            {"bake", {{{"method", "hbao"}, {"directions", 4}}}},
                            {"output", {{"dir", "out_sq"}}}};
  std::ofstream(dir_ / "sq.json") << j.dump(2);
  const Result r = hfbake("validate " + (dir_ / "sq.json").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("64x64 texels of 10 ("), std::string::npos) << r.err;
}

// The median and the 95th percentile of |a - b| over the pairs given.
std::pair<double, double> median_p95(std::vector<double> d) {
  if (d.empty()) return {NAN, NAN};
  std::sort(d.begin(), d.end());
  return {d[d.size() / 2], d[std::size_t(0.95 * double(d.size() - 1))]};
}

// Bilinear value of a raster band at fractional pixel-centre coordinates (x = i at centres).
double bilinear(const Raster& r, double x, double y) {
  const int i = int(std::floor(x)), j = int(std::floor(y));
  const double fx = x - i, fy = y - j;
  auto at = [&](int a, int b) { return double(r.values[std::size_t(b) * r.width + a]); };
  return (at(i, j) * (1 - fx) + at(i + 1, j) * fx) * (1 - fy) +
         (at(i, j + 1) * (1 - fx) + at(i + 1, j + 1) * fx) * fy;
}

// A geographic copy of the lidar tile bakes, and its layers agree with the projected tile's as closely as
// those of the projected tile resampled there and back (the resampling's own effect): the geographic
// texels (0.0000111 degrees: 0.86 x 1.24 m in the local frame) are compared at their own positions, moved
// into the tile's CRS by OGR, against the projected bake interpolated there. All with the Earth's
// curvature: p1's ao and vsky at K = 32, relief at K = 16 with a 25 m radius. docs/gis.md "Geographic
// DEMs" quotes the figures.
TEST_F(CliGdal, GeographicCopyOfTheLidarTileBakesLikeIt) {
  translate("-srcwin 300 300 400 400 '" + kDem.string() + "' proj.tif");
  const Raster proj_dem = read_raster(dir_ / "proj.tif");
  warp("-t_srs EPSG:4326 proj.tif geo.tif");
  const double x0 = proj_dem.gt[0], y0 = proj_dem.gt[3];
  char te[160];
  std::snprintf(te, sizeof te, "-te %.6f %.6f %.6f %.6f -tr 1 1", x0, y0 - 400, x0 + 400, y0);
  std::unique_ptr<GDALDataset> proj_ds(GDALDataset::Open((dir_ / "proj.tif").c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(proj_ds);
  const std::string proj_wkt = proj_ds->GetProjectionRef();
  warp("-t_srs EPSG:3794 " + std::string(te) + " geo.tif back.tif");
  const char* layers[] = {"p1.ao", "p1.vsky", "relief.svf", "relief.openness_positive", "relief.horizon_deg"};
  for (const char* name : {"proj", "geo", "back"}) {
    const nlohmann::json j = {
        {"version", 1},
        {"name", name},
        {"height", {{"image", std::string(name) + ".tif"}, {"nodata", "fill"}, {"curvature", true}}},
        {"bake",
         {{{"method", "p1"}, {"directions", 32}, {"layers", {"ao", "vsky"}}},
          {{"method", "relief"},
           {"directions", 16},
           {"search_radius", 25},
           {"azimuth_convention", "compass"},
           {"layers", {"svf", "openness_positive", "horizon_deg"}}}}},
        {"output", {{"dir", std::string("out_") + name}, {"geotiff", true}}}};
    std::ofstream(dir_ / (std::string(name) + ".json")) << j.dump(2);
    const Result r = hfbake("bake --quiet " + (dir_ / (std::string(name) + ".json")).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const Raster geo_dem = read_raster(dir_ / "geo.tif");
  // Each geographic texel's position in the tile's pixels.
  OGRSpatialReference wgs84, tile;
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  tile.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  ASSERT_EQ(wgs84.importFromEPSG(4326), OGRERR_NONE);
  ASSERT_EQ(tile.importFromWkt(proj_wkt.c_str()), OGRERR_NONE);
  std::unique_ptr<OGRCoordinateTransformation> to_tile(OGRCreateCoordinateTransformation(&wgs84, &tile));
  ASSERT_TRUE(to_tile);
  const std::size_t n = geo_dem.values.size();
  std::vector<double> px(n), py(n);
  for (int j = 0; j < geo_dem.height; ++j)
    for (int i = 0; i < geo_dem.width; ++i) {
      const std::size_t t = std::size_t(j) * geo_dem.width + i;
      px[t] = geo_dem.gt[0] + (i + 0.5) * geo_dem.gt[1];
      py[t] = geo_dem.gt[3] + (j + 0.5) * geo_dem.gt[5];
    }
  ASSERT_TRUE(to_tile->Transform(int(n), px.data(), py.data()));
  // Beyond relief's 25 m radius every ray stays on valid heights; p1's unbounded rays reach the filled
  // corners of the geographic copy, whose fill the projected tile does not have.
  constexpr double kMargin = 30;
  for (const char* layer : layers) {
    const bool per_direction = std::string(layer) == "relief.horizon_deg";
    const int bands = per_direction ? 16 : 1;
    std::vector<double> d_geo, d_back;
    for (int band = 1; band <= bands; ++band) {
      const std::string file = std::string(".") + layer + ".tif";
      const Raster p = read_raster(dir_ / "out_proj" / ("proj" + file), band);
      const Raster g = read_raster(dir_ / "out_geo" / ("geo" + file), band);
      const Raster b = read_raster(dir_ / "out_back" / ("back" + file), band);
      ASSERT_EQ(p.values.size(), 400u * 400u);
      ASSERT_EQ(b.values.size(), 400u * 400u);
      ASSERT_EQ(g.values.size(), n);
      for (std::size_t t = 0; t < n; ++t) {
        const double x = (px[t] - p.gt[0]) / p.gt[1] - 0.5, y = (py[t] - p.gt[3]) / p.gt[5] - 0.5;
        if (x < kMargin || y < kMargin || x > 399 - kMargin || y > 399 - kMargin) continue;
        d_geo.push_back(std::abs(g.values[t] - bilinear(p, x, y)));
      }
      for (int j = int(kMargin); j < 400 - int(kMargin); ++j)
        for (int i = int(kMargin); i < 400 - int(kMargin); ++i) {
          const std::size_t t = std::size_t(j) * 400 + i;
          d_back.push_back(std::abs(double(b.values[t]) - double(p.values[t])));
        }
    }
    const auto [geo_median, geo_p95] = median_p95(d_geo);
    const auto [back_median, back_p95] = median_p95(d_back);
    std::printf(
        "%s: geographic vs projected median %.5g, 95 %% %.5g (%zu values); resampled there and back "
        "median %.5g, 95 %% %.5g\n",
        layer, geo_median, geo_p95, d_geo.size(), back_median, back_p95);
    EXPECT_GT(d_geo.size(), 100000u);
    // Per direction the two grids' norths also differ by the meridian convergence (0.61 degrees here:
    // the geographic grid's is true north), which turns every horizon_deg direction by that much; the
    // averages over the directions (svf, openness) do not see it. p1's rays are unbounded, and the
    // geographic copy's corners (NoData, filled from their neighbours) are terrain the projected window
    // does not have, which rises into some of its horizons.
    const bool unbounded = std::string(layer).rfind("p1.", 0) == 0;
    const double turned = per_direction || unbounded ? 1.2 : 1.0;
    EXPECT_LE(geo_median, turned * back_median) << layer;
    EXPECT_LE(geo_p95, back_p95) << layer;
  }
}

// Web Mercator's map metres are 1 / cos(latitude) ground metres (about 1.45 at the lidar tile's 46.4 N): a
// DEM warped to it is warned with that factor; the same DEM in its own D96/TM (true to scale within 0.01 %)
// is not.
TEST_F(CliGdal, ACrsFarFromTrueScaleIsWarnedWithItsFactor) {
  make_crops();
  warp("-t_srs EPSG:3857 -tr 1.45 1.45 dem1m.tif merc.tif");
  const Result merc =
      hfbake("validate " + write_job("m.json", "merc", {{"image", "merc.tif"}, {"nodata", "fill"}}).string());
  ASSERT_EQ(merc.exit_code, 0) << merc.err;
  const std::size_t at = merc.err.find("the CRS's map units are ");
  ASSERT_NE(at, std::string::npos) << merc.err;
  const double k = std::stod(merc.err.substr(at + 24));
  EXPECT_NEAR(k, 1.0 / std::cos(46.4 * std::acos(-1.0) / 180), 0.01) << merc.err;
  // Following the advice (height_scale k) ends the warning; another scale keeps it, advising k in all.
  const std::size_t advised = merc.err.find("or give height_scale ");
  ASSERT_NE(advised, std::string::npos) << merc.err;
  const double scale = std::stod(merc.err.substr(advised + 21));
  const Result fixed =
      hfbake("validate " + write_job("mf.json", "mercf",
                                     {{"image", "merc.tif"}, {"nodata", "fill"}, {"height_scale", scale}})
                               .string());
  ASSERT_EQ(fixed.exit_code, 0) << fixed.err;
  EXPECT_EQ(fixed.err.find("map units are"), std::string::npos) << fixed.err;
  const Result half =
      hfbake("validate " +
             write_job("mh.json", "merch", {{"image", "merc.tif"}, {"nodata", "fill"}, {"height_scale", 2.0}})
                 .string());
  ASSERT_EQ(half.exit_code, 0) << half.err;
  const std::size_t again = half.err.find("or give height_scale ");
  ASSERT_NE(again, std::string::npos) << half.err;
  EXPECT_NEAR(std::stod(half.err.substr(again + 21)), scale, 1e-4) << half.err;
  const Result own = hfbake("validate " + write_job("d.json", "d96", {{"image", "dem1m.tif"}}).string());
  ASSERT_EQ(own.exit_code, 0) << own.err;
  EXPECT_EQ(own.err.find("map units are"), std::string::npos) << own.err;
}

// A rotated or sheared raster is refused in one line at /height/image; rotation terms of 1e-15 pixel (a
// conversion's rounding) are north-up, baked as the same raster without them.
TEST_F(CliGdal, OnlyARotationBeyondRoundingIsRefused) {
  translate("-srcwin 400 400 48 40 '" + kDem.string() + "' north.tif");
  const auto with_terms = [&](const std::string& file, double rotation) {
    translate("north.tif " + file);
    std::unique_ptr<GDALDataset> ds(
        GDALDataset::Open((dir_ / file).c_str(), GDAL_OF_RASTER | GDAL_OF_UPDATE));
    ASSERT_TRUE(ds);
    double g[6];
    ds->GetGeoTransform(g);
    g[2] = rotation * g[1], g[4] = rotation * g[1];
    ds->SetGeoTransform(g);
  };
  with_terms("tiny.tif", 1e-15);
  with_terms("turned.tif", 0.2);
  const Result turned = hfbake("validate " + write_job("t.json", "t", {{"image", "turned.tif"}}).string());
  EXPECT_EQ(turned.exit_code, 2) << turned.err;
  ASSERT_EQ(turned.error_lines().size(), 1u) << turned.err;
  EXPECT_NE(turned.err.find("/height/image: " + (dir_ / "turned.tif").string() + ": is rotated or sheared"),
            std::string::npos)
      << turned.err;
  std::vector<float> ao[2];
  int n = 0;
  for (const char* name : {"north", "tiny"}) {
    const Result r = hfbake(
        "bake --quiet --no-cache " +
        write_job(std::string(name) + ".json", name, {{"image", std::string(name) + ".tif"}}).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    ao[n++] = read_raster(dir_ / ("out_" + std::string(name)) / (std::string(name) + ".p1.ao.tif")).values;
  }
  EXPECT_EQ(max_abs_diff(ao[0], ao[1]), 0.0);
}

// A band that declares its heights in metres on a CRS in US survey feet (EPSG:2263) is warned with the
// factor that converts them, 3937 / 1200 (feet on a metre CRS: too steep, by its inverse); the heights line
// names the CRS's unit. With that height_scale, with the band in feet or with no unit declared, no warning; a
// metre CRS is not named.
TEST_F(CliGdal, HeightsInAnotherUnitThanThePixelsAreWarned) {
  translate("-srcwin 400 400 64 64 -a_srs EPSG:2263 '" + kDem.string() + "' feet.tif");
  translate("-srcwin 400 400 64 64 '" + kDem.string() + "' metres.tif");
  auto with_unit = [&](const std::string& file, const char* unit) {
    std::unique_ptr<GDALDataset> ds(
        GDALDataset::Open((dir_ / file).c_str(), GDAL_OF_RASTER | GDAL_OF_UPDATE));
    ASSERT_TRUE(ds);
    ds->GetRasterBand(1)->SetUnitType(unit);
  };
  translate("feet.tif feet_m.tif");
  translate("feet.tif feet_ft.tif");
  with_unit("feet_m.tif", "m");
  with_unit("feet_ft.tif", "ft");
  with_unit("metres.tif", "metre");
  const std::string warned = "the band's heights are in m and its pixels in US survey foot: slopes come out ";
  const Result m = hfbake("validate " + write_job("m.json", "m", {{"image", "feet_m.tif"}}).string());
  ASSERT_EQ(m.exit_code, 0) << m.err;
  const std::size_t at = m.err.find(warned);
  ASSERT_NE(at, std::string::npos) << m.err;
  EXPECT_NEAR(std::stod(m.err.substr(at + warned.size())), 3937.0 / 1200.0, 1e-4) << m.err;
  EXPECT_NE(m.err.find("times too flat; give height_scale 3.28083"), std::string::npos) << m.err;
  EXPECT_NE(m.err.find("world units, the CRS's US survey foot)"), std::string::npos) << m.err;
  // The other way round, heights in feet on a metre CRS: too steep, by the same ratio.
  translate("metres.tif metres_ft.tif");
  with_unit("metres_ft.tif", "US survey foot");
  const Result ft = hfbake("validate " + write_job("ft.json", "ft", {{"image", "metres_ft.tif"}}).string());
  ASSERT_EQ(ft.exit_code, 0) << ft.err;
  EXPECT_NE(ft.err.find("the band's heights are in US survey foot and its pixels in metre: slopes come out "
                        "3.28083 times too steep; give height_scale 0.304801"),
            std::string::npos)
      << ft.err;
  // Heights in centimetres on a metre CRS (a lidar product's integer centimetres): too steep by 100.
  translate("metres.tif metres_cm.tif");
  with_unit("metres_cm.tif", "cm");
  const Result cm = hfbake("validate " + write_job("cm.json", "cm", {{"image", "metres_cm.tif"}}).string());
  ASSERT_EQ(cm.exit_code, 0) << cm.err;
  EXPECT_NE(cm.err.find("the band's heights are in cm and its pixels in metre: slopes come out 100 times too "
                        "steep; give height_scale 0.01"),
            std::string::npos)
      << cm.err;
  const nlohmann::json cases[] = {{{"image", "feet_m.tif"}, {"height_scale", 3937.0 / 1200.0}},
                                  {{"image", "feet_ft.tif"}},
                                  {{"image", "feet.tif"}},
                                  {{"image", "metres.tif"}}};
  int n = 0;
  for (const nlohmann::json& height : cases) {
    const Result r =
        hfbake("validate " + write_job("c" + std::to_string(n++) + ".json", "c", height).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("heights are in"), std::string::npos) << height.dump() << r.err;
  }
  const Result own = hfbake("validate " + write_job("own.json", "own", {{"image", "metres.tif"}}).string());
  EXPECT_EQ(own.err.find("the CRS's"), std::string::npos) << own.err;
  // No unit on the band: the heights line says which unit they are taken in, and the factor for metres.
  const Result bare = hfbake("validate " + write_job("bare.json", "bare", {{"image", "feet.tif"}}).string());
  EXPECT_NE(
      bare.err.find("(the band declares no unit: heights taken in US survey foot; heights in metres need "
                    "height_scale 3.28083)"),
      std::string::npos)
      << bare.err;
  EXPECT_EQ(own.err.find("declares no unit"), std::string::npos) << own.err;
}

TEST_F(CliGdal, NonSquarePixelsAreRefusedInOneLine) {
  translate("-srcwin 0 0 64 64 -a_ullr 1000 2000 1064 1872 '" + kDem.string() + "' tall.tif");  // 1 x 2 m
  const fs::path job = write_job("a.json", "tall", {{"image", "tall.tif"}});
  for (const char* cmd : {"validate ", "bake "}) {
    const Result r = hfbake(cmd + job.string());
    EXPECT_EQ(r.exit_code, 2) << cmd;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_EQ(r.error_lines()[0].rfind("hfbake: error: " + job.string() + ": /height/image: " +
                                           (dir_ / "tall.tif").string() + ": has non-square pixels (1 x 2)",
                                       0),
              0u)
        << r.err;
  }
}

// What a bake reads through a DEM is every file GDAL reads for it: a VRT's source at an output's name is
// refused by validate, bake and horizon (the source's bytes stay), and a changed source (or a side file that
// declares NoData) makes shards baked before it another job's: merge refuses them.
TEST_F(CliGdal, AVrtsSourcesAreReadFilesOfTheJob) {
  fs::create_directories(dir_ / "out_v");
  translate("-srcwin 400 400 48 48 '" + kDem.string() + "' out_v/v.p1.ao.tif");
  translate("-of VRT out_v/v.p1.ao.tif v.vrt");
  const fs::path job = write_job("v.json", "v", {{"image", "v.vrt"}});
  const auto bytes = [&](const fs::path& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string source = bytes(dir_ / "out_v" / "v.p1.ao.tif");
  for (const char* cmd : {"validate ", "bake --quiet "}) {
    const Result r = hfbake(cmd + job.string());
    EXPECT_EQ(r.exit_code, 2) << cmd << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find(job.string() +
                                      ": /height/image: " + (dir_ / "out_v" / "v.p1.ao.tif").string() +
                                      " is where this job writes an output"),
              std::string::npos)
        << r.err;
  }
  const Raster vrt = read_raster(dir_ / "v.vrt");
  Result r = hfbake("horizon " + (dir_ / "v.vrt").string() + " --at " + std::to_string(vrt.gt[0] + 20) + "," +
                    std::to_string(vrt.gt[3] - 20) + " --plot " + (dir_ / "out_v" / "v.p1.ao.tif").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--plot: is " + (dir_ / "out_v" / "v.p1.ao.tif").string() + ", which GDAL reads"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(bytes(dir_ / "out_v" / "v.p1.ao.tif"), source) << "the VRT's source was written over";

  // Shards: the source changes between the two tasks; then a side file declares NoData.
  translate("-srcwin 400 400 48 48 '" + kDem.string() + "' src.tif");
  translate("-of VRT src.tif w.vrt");
  const fs::path shard_job = write_job("w.json", "w", {{"image", "w.vrt"}, {"nodata", "fill"}});
  ASSERT_EQ(hfbake("bake --quiet --shard 0/2 " + shard_job.string()).exit_code, 0);
  const Raster src = read_raster(dir_ / "src.tif");  // other heights in its place: another window of the DEM
  translate("-srcwin 300 300 48 48 -a_ullr " + std::to_string(src.gt[0]) + " " + std::to_string(src.gt[3]) +
            " " + std::to_string(src.gt[0] + 48) + " " + std::to_string(src.gt[3] - 48) + " '" +
            kDem.string() + "' src2.tif");
  fs::rename(dir_ / "src2.tif", dir_ / "src.tif");
  ASSERT_EQ(hfbake("bake --quiet --shard 1/2 " + shard_job.string()).exit_code, 0);
  r = hfbake("merge --quiet " + shard_job.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("belongs to another job"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out_w" / "w.p1.ao.tif"));
  ASSERT_EQ(hfbake("bake --quiet --shard 0/2 " + shard_job.string()).exit_code, 0);
  ASSERT_EQ(hfbake("merge --quiet " + shard_job.string()).exit_code, 0);  // both of these heights: merged
  // A GeoTIFF's side file that declares NoData changes the heights read: shards from before it are refused.
  translate("-srcwin 400 400 48 48 '" + kDem.string() + "' plain.tif");
  const fs::path plain_job = write_job("x.json", "x", {{"image", "plain.tif"}, {"nodata", "fill"}});
  ASSERT_EQ(hfbake("bake --quiet --shard 0/2 " + plain_job.string()).exit_code, 0);
  const float first = read_raster(dir_ / "plain.tif").values[0];
  std::ofstream(dir_ / "plain.tif.aux.xml") << "<PAMDataset><PAMRasterBand band=\"1\"><NoDataValue>" << first
                                            << "</NoDataValue></PAMRasterBand></PAMDataset>\n";
  ASSERT_EQ(hfbake("bake --quiet --shard 1/2 " + plain_job.string()).exit_code, 0);
  r = hfbake("merge --quiet " + plain_job.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("belongs to another job"), std::string::npos) << r.err;

  // A VRT of a VRT: the inner one's source is read too (refused at an output's name), and a source inside a
  // zip archive is the archive's bytes (a changed archive makes the shards another job's).
  translate("-of VRT v.vrt outer.vrt");
  const fs::path outer = write_job("o.json", "v", {{"image", "outer.vrt"}});
  r = hfbake("validate " + outer.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find((dir_ / "out_v" / "v.p1.ao.tif").string() + " is where this job writes an output"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(bytes(dir_ / "out_v" / "v.p1.ao.tif"), source);
  int status = -1;
  run_tool(
      "cd '" + dir_.string() + "' && cp plain.tif z.tif && python3 -m zipfile -c a.zip z.tif && rm z.tif",
      &status);
  ASSERT_EQ(status, 0);
  translate("-of VRT /vsizip/" + (dir_ / "a.zip").string() + "/z.tif zipped.vrt");
  const fs::path zipped = write_job("z.json", "z", {{"image", "zipped.vrt"}, {"nodata", "fill"}});
  ASSERT_EQ(hfbake("bake --quiet --shard 0/2 " + zipped.string()).exit_code, 0);
  run_tool("cd '" + dir_.string() + "' && cp src.tif z.tif && rm a.zip && python3 -m zipfile -c a.zip z.tif",
           &status);
  ASSERT_EQ(status, 0);
  ASSERT_EQ(hfbake("bake --quiet --shard 1/2 " + zipped.string()).exit_code, 0);
  r = hfbake("merge --quiet " + zipped.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("belongs to another job"), std::string::npos) << r.err;
}

// A mosaic whose sources leave a gap: GDAL reads 0 m there (no NoData value), a canyon to sea level in the
// middle of the terrain. validate, bake, a tiled bake and horizon refuse it in one line naming the file and
// how much is uncovered; with a NoData value for the gaps they are holes (refused, or filled when the job
// says so); a mosaic of adjacent sources is whole.
TEST_F(CliGdal, AMosaicsGapsAreRefusedUnlessTheyAreNoData) {
  translate("-srcwin 400 400 40 40 '" + kDem.string() + "' west.tif");
  translate("-srcwin 440 400 40 40 '" + kDem.string() + "' middle.tif");
  translate("-srcwin 480 400 40 40 '" + kDem.string() + "' east.tif");
  int status = -1;
  run_tool("cd '" + dir_.string() +
               "' && gdalbuildvrt -q gap.vrt west.tif east.tif && gdalbuildvrt -q -vrtnodata -9999 holes.vrt "
               "west.tif east.tif && gdalbuildvrt -q whole.vrt west.tif middle.tif east.tif",
           &status);
  ASSERT_EQ(status, 0);
  const fs::path gap = dir_ / "gap.vrt";
  const std::string said = gap.string() + ": 33.3 % of it is covered by none of its data";
  const fs::path job = write_job("gap.json", "gap", {{"image", "gap.vrt"}});
  const Raster whole = read_raster(dir_ / "whole.vrt");
  for (const std::string& command :
       {"validate " + job.string(), "bake --quiet " + job.string(),
        "bake --quiet --tiles --tile-size 32 " + job.string(),
        "horizon " + gap.string() + " --at " + std::to_string(whole.gt[0] + 10.5) + "," +
            std::to_string(whole.gt[3] - 10.5)}) {
    SCOPED_TRACE(command);
    const Result r = hfbake(command);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find(said), std::string::npos) << r.err;
    EXPECT_NE(r.error_lines()[0].find("gdalbuildvrt -vrtnodata"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out_gap"));
  }
  Result r = hfbake("validate " + write_job("holes.json", "holes", {{"image", "holes.vrt"}}).string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("1600 of 4800 texels have no valid height"), std::string::npos) << r.err;
  r = hfbake("bake --quiet " +
             write_job("filled.json", "filled", {{"image", "holes.vrt"}, {"nodata", "fill"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = hfbake("validate " + write_job("whole.json", "whole", {{"image", "whole.vrt"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// A GeoTIFF's rows of exactly 0 m (a sea) are heights: GDAL leaves an uncompressed file's blocks of zeros
// to the file system, which may keep them as holes, yet every block is in the file's table, and the DEM
// validates. A sparse GeoTIFF whose table lacks a block (SPARSE_OK, a block never written) is refused
// naming how much is missing.
TEST_F(CliGdal, AGeoTiffsZeroRowsAreHeightsAndItsMissingBlocksAreNot) {
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  const int n = 256;
  std::vector<float> z(std::size_t(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) z[std::size_t(j * n + i)] = j >= 192 ? 0.0f : float(1 + (i * 7 + j * 3) % 9);
  const double gt[6] = {500000, 1, 0, 5100256, 0, -1};
  OGRSpatialReference utm;
  utm.importFromEPSG(32633);
  {
    GDALDataset* ds = gtiff->Create((dir_ / "sea.tif").c_str(), n, n, 1, GDT_Float32, nullptr);
    ASSERT_TRUE(ds);
    ds->SetGeoTransform(const_cast<double*>(gt));
    ds->SetSpatialRef(&utm);
    ASSERT_EQ(
        ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, n, n, z.data(), n, n, GDT_Float32, 0, 0, nullptr),
        CE_None);
    GDALClose(ds);
    const char* sparse_options[] = {"SPARSE_OK=TRUE", "TILED=YES", "BLOCKXSIZE=64", "BLOCKYSIZE=64", nullptr};
    ds = gtiff->Create((dir_ / "sparse.tif").c_str(), n, n, 1, GDT_Float32,
                       const_cast<char**>(sparse_options));
    ASSERT_TRUE(ds);
    ds->SetGeoTransform(const_cast<double*>(gt));
    ds->SetSpatialRef(&utm);
    // Land everywhere (a sparse file leaves out blocks of zeros too), every block written but the last of
    // the first row of blocks.
    std::vector<float> land = z;
    for (float& v : land) v += 1;
    ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 192, 64, land.data(), 192, 64, GDT_Float32, 4,
                                             4 * std::size_t(n), nullptr),
              CE_None);
    ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 64, n, n - 64, land.data() + 64 * n, n, n - 64,
                                             GDT_Float32, 0, 0, nullptr),
              CE_None);
    GDALClose(ds);
  }
  Result r = hfbake("validate " + write_job("sea.json", "sea", {{"image", "sea.tif"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = hfbake("validate " + write_job("sparse.json", "sparse", {{"image", "sparse.tif"}}).string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("sparse.tif: 6.25 % of it is covered by none of its data"), std::string::npos)
      << r.err;
}

// A report's scene names the bytes of every file its heights were read from: a baseline baked from a VRT
// whose source has changed since is another job's, refused by compare (exit 2).
TEST_F(CliGdal, AReportsSceneCountsAVrtsSources) {
  translate("-srcwin 400 400 32 32 '" + kDem.string() + "' src.tif");
  translate("-of VRT src.tif v.vrt");
  const nlohmann::json job = {{"version", 1},
                              {"name", "r"},
                              {"height", {{"image", "v.vrt"}}},
                              {"bake", {{{"method", "p1"}, {"directions", 8}, {"layers", {"ao"}}}}},
                              {"reference", {{"samples", 4}, {"seed", 1}}},
                              {"output", {{"dir", "out_a"}}}};
  std::ofstream(dir_ / "r.json") << job.dump();
  ASSERT_EQ(hfbake("bake --quiet --no-cache " + (dir_ / "r.json").string()).exit_code, 0);
  const Raster src = read_raster(dir_ / "src.tif");
  translate("-srcwin 300 300 32 32 -a_ullr " + std::to_string(src.gt[0]) + " " + std::to_string(src.gt[3]) +
            " " + std::to_string(src.gt[0] + 32) + " " + std::to_string(src.gt[3] - 32) + " '" +
            kDem.string() + "' other.tif");
  fs::rename(dir_ / "other.tif", dir_ / "src.tif");
  ASSERT_EQ(
      hfbake("bake --quiet --no-cache --out " + (dir_ / "out_b").string() + " " + (dir_ / "r.json").string())
          .exit_code,
      0);
  const Result r = hfbake("compare " + (dir_ / "out_b" / "report.json").string() + " " +
                          (dir_ / "out_a" / "report.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("a report of another job: scene.height.image"), std::string::npos) << r.err;
}

// A TIFF without georeferencing is an image, read by OpenImageIO, but for one whose holes or values only
// GDAL reads as the file declares them: a NoData value (its texels are holes, filled on request) and
// MinIsWhite samples (OpenImageIO gives 255 - stored; heights are the stored values).
TEST_F(CliGdal, ATiffsNodataAndMinIsWhiteSamplesAreReadAsDeclared) {
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  std::vector<float> z(32 * 32);
  for (int j = 0; j < 32; ++j)
    for (int i = 0; i < 32; ++i) z[std::size_t(j * 32 + i)] = float(20 + (i * 7 + j * 3) % 200);
  std::vector<float> holed = z;
  holed[5 * 32 + 5] = holed[20 * 32 + 9] = -9999.0f;
  {
    GDALDataset* ds = gtiff->Create((dir_ / "holes.tif").c_str(), 32, 32, 1, GDT_Float32, nullptr);
    ASSERT_TRUE(ds);
    ds->GetRasterBand(1)->SetNoDataValue(-9999);
    ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 32, 32, holed.data(), 32, 32, GDT_Float32, 0, 0,
                                             nullptr),
              CE_None);
    GDALClose(ds);
    const char* options[] = {"PHOTOMETRIC=MINISWHITE", nullptr};
    ds = gtiff->Create((dir_ / "white.tif").c_str(), 32, 32, 1, GDT_Byte, const_cast<char**>(options));
    ASSERT_TRUE(ds);
    ASSERT_EQ(
        ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 32, 32, z.data(), 32, 32, GDT_Float32, 0, 0, nullptr),
        CE_None);
    GDALClose(ds);
  }
  const fs::path holes = write_job("h.json", "h", {{"image", "holes.tif"}, {"texel_size", 2}});
  Result r = hfbake("validate " + holes.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/height/image"), std::string::npos) << r.err;
  const fs::path filled =
      write_job("f.json", "f", {{"image", "holes.tif"}, {"texel_size", 2}, {"nodata", "fill"}});
  r = hfbake("validate " + filled.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("through GDAL (GTiff, Float32)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("heights 20 .. 219 world units"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("2 texels without a height"), std::string::npos) << r.err;
  // An RGB TIFF with NoData: its channels by the names OpenImageIO gives them, as without the NoData.
  {
    const char* rgb[] = {"PHOTOMETRIC=RGB", nullptr};
    GDALDataset* ds =
        gtiff->Create((dir_ / "rgb.tif").c_str(), 32, 32, 3, GDT_Float32, const_cast<char**>(rgb));
    ASSERT_TRUE(ds);
    for (int b = 1; b <= 3; ++b) {
      std::vector<float> band(z.size());
      for (std::size_t i = 0; i < z.size(); ++i) band[i] = z[i] * float(b);
      ds->GetRasterBand(b)->SetNoDataValue(-9999);
      ASSERT_EQ(ds->GetRasterBand(b)->RasterIO(GF_Write, 0, 0, 32, 32, band.data(), 32, 32, GDT_Float32, 0, 0,
                                               nullptr),
                CE_None);
    }
    GDALClose(ds);
  }
  r = hfbake("validate " +
             write_job("g.json", "g", {{"image", "rgb.tif"}, {"channel", "G"}, {"texel_size", 8}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("heights 40 .. 438 world units"), std::string::npos) << r.err;
  const fs::path white = write_job("w.json", "w", {{"image", "white.tif"}});
  r = hfbake("validate " + white.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("through GDAL (GTiff, Byte integers as stored)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("heights 20 .. 219 world units"), std::string::npos) << r.err;
}

// A binary PNM of 16-bit samples is read through GDAL, as stored, whatever its maxval (OpenImageIO overflows
// on samples above 32767: a maxval of 40000 read as 0..32768); an ASCII one of maxval above 32767, which only
// OpenImageIO reads, is refused naming the file and what to convert it to; so is a colour of such a maxval
// below 65535.
TEST_F(CliGdal, APnmsSixteenBitSamplesAreReadAsStored) {
  const auto pgm = [&](const std::string& name, int maxval, bool ascii) {
    std::vector<int> v(16 * 16);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = int(i * 2654435761u % std::uint32_t(maxval + 1));
    v[7] = maxval, v[9] = 0;
    std::ofstream out(dir_ / name, std::ios::binary);
    out << (ascii ? "P2" : "P5") << "\n16 16\n" << maxval << "\n";
    for (const int x : v)
      if (ascii)
        out << x << " ";
      else
        out << char(x >> 8) << char(x & 255);
  };
  for (const int maxval : {65535, 50000, 40000, 1023}) {
    SCOPED_TRACE(maxval);
    pgm("b.pgm", maxval, false);
    const Result r = hfbake("validate " + write_job("b.json", "b", {{"image", "b.pgm"}}).string());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("through GDAL (PNM, UInt16 integers as stored)"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("heights 0 .. " + std::to_string(maxval) + " world units"), std::string::npos)
        << r.err;
  }
  for (const int maxval : {40000, 65535}) {
    SCOPED_TRACE(maxval);
    pgm("a.pgm", maxval, true);
    const fs::path a = write_job("a.json", "a", {{"image", "a.pgm"}});
    for (const char* command : {"validate ", "bake --quiet --no-cache "}) {
      const Result r = hfbake(command + a.string());
      EXPECT_EQ(r.exit_code, 2) << r.err;
      EXPECT_NE(
          r.err.find(a.string() + ": /height/image: " + (dir_ / "a.pgm").string() + ": is a PNM of maxval " +
                     std::to_string(maxval) +
                     ", whose samples above 32767 OpenImageIO misreads: save it as a 16-bit PNG or TIFF"),
          std::string::npos)
          << r.err;
    }
    EXPECT_FALSE(fs::exists(dir_ / "out_a"));
  }
  // A colour (albedo) of maxval 65535 is read (a sample one too low is 1 / 65535 of a colour); one of maxval
  // 40000 is refused.
  for (const int maxval : {65535, 40000}) {
    SCOPED_TRACE(maxval);
    pgm("c.pgm", maxval, false);
    nlohmann::json j;
    std::ifstream(write_job("c.json", "c", {{"image", "b.pgm"}})) >> j;
    j["surface"] = {{"albedo", {{"image", "c.pgm"}}}};
    std::ofstream(dir_ / "c.json") << j.dump();
    const Result r = hfbake("validate " + (dir_ / "c.json").string());
    EXPECT_EQ(r.exit_code, maxval == 65535 ? 0 : 2) << r.err;
    if (maxval != 65535) {
      EXPECT_NE(
          r.err.find("/surface/albedo/image: " + (dir_ / "c.pgm").string() + ": is a PNM of maxval 40000"),
          std::string::npos)
          << r.err;
    }
  }
}

// A mask band (here a .msk side file) marks holes as a NoData value does: refused without "nodata": "fill",
// counted and filled with it.
TEST_F(CliGdal, AMaskBandMarksHoles) {
  translate("-srcwin 400 400 40 40 '" + kDem.string() + "' masked.tif");
  {
    CPLSetThreadLocalConfigOption("GDAL_TIFF_INTERNAL_MASK", "NO");
    GDALDataset* ds = GDALDataset::Open((dir_ / "masked.tif").c_str(), GDAL_OF_RASTER | GDAL_OF_UPDATE);
    ASSERT_TRUE(ds);
    ASSERT_EQ(ds->CreateMaskBand(GMF_PER_DATASET), CE_None);
    std::vector<std::uint8_t> valid(40 * 40, 255);
    for (int j = 0; j < 40; ++j)
      for (int i = 30; i < 40; ++i) valid[std::size_t(j * 40 + i)] = 0;  // 400 texels masked
    ASSERT_EQ(ds->GetRasterBand(1)->GetMaskBand()->RasterIO(GF_Write, 0, 0, 40, 40, valid.data(), 40, 40,
                                                            GDT_Byte, 0, 0, nullptr),
              CE_None);
    GDALClose(ds);
    CPLSetThreadLocalConfigOption("GDAL_TIFF_INTERNAL_MASK", nullptr);
  }
  ASSERT_TRUE(fs::exists(dir_ / "masked.tif.msk"));
  Result r = hfbake("validate " + write_job("m.json", "m", {{"image", "masked.tif"}}).string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/height/image"), std::string::npos) << r.err;
  r = hfbake("validate " + write_job("f.json", "f", {{"image", "masked.tif"}, {"nodata", "fill"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("400 texels without a height"), std::string::npos) << r.err;
}

// The curvature line's drop at 1 km is in metres whatever the CRS's unit: on a CRS in US survey feet, c per
// foot is c / 0.3048006 per metre, and 1 km away lies c 1e6 / 0.3048006 m lower.
TEST_F(CliGdal, TheCurvatureLineSaysMetresOnACrsInFeet) {
  std::vector<float> z(32 * 32, 100.0f);
  const double ft = 1200.0 / 3937.0;
  {
    GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
    GDALDataset* ds = gtiff->Create((dir_ / "feet.tif").c_str(), 32, 32, 1, GDT_Float32, nullptr);
    ASSERT_TRUE(ds);
    double gt[6] = {6500000.0, 10.0, 0.0, 1800000.0, 0.0, -10.0};
    ds->SetGeoTransform(gt);
    OGRSpatialReference srs;
    srs.importFromEPSG(2229);  // NAD83 / California zone 5, US survey feet
    ds->SetSpatialRef(&srs);
    ASSERT_EQ(
        ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 32, 32, z.data(), 32, 32, GDT_Float32, 0, 0, nullptr),
        CE_None);
    GDALClose(ds);
  }
  const Result r =
      hfbake("validate " + write_job("c.json", "c", {{"image", "feet.tif"}, {"curvature", true}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::size_t at = r.err.find("a point 1 km away is ");
  const std::size_t c_at = r.err.find(", c = ");
  ASSERT_NE(at, std::string::npos) << r.err;
  ASSERT_NE(c_at, std::string::npos) << r.err;
  const double drop = std::stod(r.err.substr(at + 21)), c = std::stod(r.err.substr(c_at + 6));
  EXPECT_NEAR(drop, c * 1e6 / ft, 1e-4 * drop) << r.err;
  EXPECT_NEAR(drop, 0.0683, 0.001) << r.err;  // about 1 km^2 / (2 x 6371 km) x (1 - 0.13)
}

// A raster placed by ground control points (no geotransform) and one with a CRS but no geotransform have no
// texel size or place hfbake can use: both are refused in one line at /height/image by validate and bake,
// nothing baked (a raster with neither is an image, baked with texel 1).
TEST_F(CliGdal, RastersWithoutAGeotransformButWithGcpsOrACrsAreRefused) {
  translate(
      "-srcwin 0 0 64 48 -gcp 0 0 500000 5000240 -gcp 64 0 500320 5000240 -gcp 0 48 500000 5000000 "
      "-gcp 64 48 500320 5000000 -a_srs EPSG:32633 '" +
      kDem.string() + "' gcp.tif");
  translate("-srcwin 0 0 64 48 '" + kDem.string() + "' plain.tif");
  {
    std::unique_ptr<GDALDataset> ds(GDALDataset::Open((dir_ / "plain.tif").c_str(), GDAL_OF_RASTER));
    ASSERT_TRUE(ds);
    EXPECT_EQ(ds->GetGCPCount(), 0);
  }
  translate("-a_srs EPSG:32633 plain.tif crs_only_src.tif");
  // gdal_translate gives a raster with a CRS a geotransform of its own; strip it to leave the CRS alone.
  {
    GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
    std::unique_ptr<GDALDataset> src(GDALDataset::Open((dir_ / "plain.tif").c_str(), GDAL_OF_RASTER));
    ASSERT_TRUE(src);
    std::vector<float> z(64 * 48);
    ASSERT_EQ(
        src->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, 64, 48, z.data(), 64, 48, GDT_Float32, 0, 0, nullptr),
        CE_None);
    GDALDataset* ds = gtiff->Create((dir_ / "crs_only.tif").c_str(), 64, 48, 1, GDT_Float32, nullptr);
    ASSERT_TRUE(ds);
    OGRSpatialReference srs;
    srs.importFromEPSG(32633);
    ds->SetSpatialRef(&srs);
    EXPECT_EQ(
        ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 64, 48, z.data(), 64, 48, GDT_Float32, 0, 0, nullptr),
        CE_None);
    GDALClose(ds);
    std::unique_ptr<GDALDataset> check(GDALDataset::Open((dir_ / "crs_only.tif").c_str(), GDAL_OF_RASTER));
    double gt[6];
    ASSERT_NE(check->GetGeoTransform(gt), CE_None);
    ASSERT_NE(check->GetSpatialRef(), nullptr);
  }
  for (const auto& [file, says] :
       {std::pair<std::string, std::string>{"gcp.tif",
                                            "is placed by ground control "
                                            "points, not by a geotransform"},
        {"crs_only.tif", "has a CRS (WGS 84 / UTM zone 33N) but no geotransform"}}) {
    const fs::path job = write_job(file + ".json", "r", {{"image", file}});
    for (const char* cmd : {"validate ", "bake "}) {
      const Result r = hfbake(cmd + job.string());
      EXPECT_EQ(r.exit_code, 2) << cmd << file;
      ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
      EXPECT_EQ(r.error_lines()[0].rfind("hfbake: error: " + job.string() +
                                             ": /height/image: " + (dir_ / file).string() + ": " + says,
                                         0),
                0u)
          << r.err;
      EXPECT_FALSE(fs::exists(dir_ / "out_r" / "r.p1.ao.tif")) << file;
    }
  }
  const Result plain = hfbake("validate " + write_job("p.json", "p", {{"image", "plain.tif"}}).string());
  EXPECT_EQ(plain.exit_code, 0) << plain.err;
}

// An 8-bit palette PNG reads the same heights with a world file beside it (through GDAL) as alone (through
// OpenImageIO, which expands the palette): its palette's red values, not its indices. The palette here maps
// index i to red 255 - i, so the indices would be the heights upside down.
TEST_F(CliGdal, APalettePngReadsTheSameHeightsWithAWorldFile) {
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* png = GetGDALDriverManager()->GetDriverByName("PNG");
  ASSERT_TRUE(mem && png);
  const int w = 40, h = 32;
  GDALDataset* ds = mem->Create("", w, h, 1, GDT_Byte, nullptr);
  std::vector<std::uint8_t> idx(std::size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      idx[std::size_t(y) * w + x] = std::uint8_t(3 + (x * 37 + y * 11 + x * y) % 230);
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, w, h, idx.data(), w, h, GDT_Byte, 0, 0, nullptr),
            CE_None);
  GDALColorTable table;
  for (int i = 0; i < 256; ++i) {
    const GDALColorEntry e{short(255 - i), short(i / 2), short(i), 255};
    table.SetColorEntry(i, &e);
  }
  ds->GetRasterBand(1)->SetColorInterpretation(GCI_PaletteIndex);
  ds->GetRasterBand(1)->SetColorTable(&table);
  for (const char* name : {"alone.png", "placed.png"}) {
    GDALDataset* out = png->CreateCopy((dir_ / name).c_str(), ds, FALSE, nullptr, nullptr, nullptr);
    ASSERT_TRUE(out);
    GDALClose(out);
  }
  GDALClose(ds);
  fs::remove(dir_ / "alone.png.aux.xml");
  fs::remove(dir_ / "placed.png.aux.xml");
  std::ofstream(dir_ / "placed.pgw") << "1\n0\n0\n-1\n500000.5\n5000031.5\n";
  std::vector<float> ao[2];
  int i = 0;
  for (const char* name : {"alone", "placed"}) {
    const fs::path job =
        write_job(std::string(name) + ".json", name, {{"image", std::string(name) + ".png"}});
    const Result r = hfbake("bake " + job.string() + " --no-cache --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Raster a = read_raster(dir_ / ("out_" + std::string(name)) / (std::string(name) + ".p1.ao.tif"));
    ASSERT_EQ(a.values.size(), std::size_t(w) * h) << name;
    ao[i++] = a.values;
  }
  EXPECT_EQ(max_abs_diff(ao[0], ao[1]), 0.0);
  const Result said = hfbake("validate " + (dir_ / "placed.json").string());
  EXPECT_NE(said.err.find("through OpenImageIO, placed by GDAL (PNG"), std::string::npos) << said.err;
  // The heights line's range is the palette's reds of the indices used (3 .. 232: reds 23 .. 252).
  EXPECT_NE(said.err.find("heights 23 .. 252"), std::string::npos) << said.err;
  // Channel "G" reads the palette's greens (i / 2: 1 .. 116), as without the world file.
  for (const char* name : {"alone", "placed"}) {
    const fs::path green = write_job(std::string(name) + "_g.json", std::string(name) + "_g",
                                     {{"image", std::string(name) + ".png"}, {"channel", "G"}});
    const Result g = hfbake("validate " + green.string());
    EXPECT_EQ(g.exit_code, 0) << g.err;
    EXPECT_NE(g.err.find("heights 1 .. 116"), std::string::npos) << g.err;
  }
  // A palette GeoTIFF is read through GDAL: channel "R" (or 0) names that red; another colour is refused
  // at /height/channel with the way to read it.
  translate("placed.png palette.tif");
  const fs::path red = write_job("r.json", "r", {{"image", "palette.tif"}, {"channel", "R"}});
  const Result r = hfbake("validate " + red.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("through GDAL (GTiff, red of its palette, Byte"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("heights 23 .. 252"), std::string::npos) << r.err;
  const fs::path green = write_job("g.json", "g", {{"image", "palette.tif"}, {"channel", "G"}});
  const Result g = hfbake("validate " + green.string());
  EXPECT_EQ(g.exit_code, 2) << g.err;
  ASSERT_EQ(g.error_lines().size(), 1u) << g.err;
  EXPECT_NE(g.error_lines()[0].find(green.string() + ": /height/channel: " + (dir_ / "palette.tif").string() +
                                    ": is a palette image read through GDAL"),
            std::string::npos)
      << g.err;
}

// A grey PNG of 16-bit samples written as stored, by hand (zlib), since neither GDAL nor OpenImageIO writes
// an interlaced (Adam7) one: each pass's rows, filter 0; `trns` >= 0: a tRNS chunk naming that grey.
void write_grey16_png(const fs::path& file, int w, int h, const std::vector<std::uint16_t>& v,
                      bool interlaced, int trns = -1) {
  std::string raw;
  const auto add_rows = [&](int x0, int y0, int dx, int dy) {
    if (x0 >= w || y0 >= h) return;
    for (int y = y0; y < h; y += dy) {
      raw.push_back('\0');
      for (int x = x0; x < w; x += dx) {
        const std::uint16_t s = v[std::size_t(y) * std::size_t(w) + std::size_t(x)];
        raw.push_back(char(s >> 8)), raw.push_back(char(s & 0xff));
      }
    }
  };
  if (interlaced)
    for (const auto& [x0, y0, dx, dy] : std::vector<std::array<int, 4>>{{0, 0, 8, 8},
                                                                        {4, 0, 8, 8},
                                                                        {0, 4, 4, 8},
                                                                        {2, 0, 4, 4},
                                                                        {0, 2, 2, 4},
                                                                        {1, 0, 2, 2},
                                                                        {0, 1, 1, 2}})
      add_rows(x0, y0, dx, dy);
  else
    add_rows(0, 0, 1, 1);
  uLongf packed_size = compressBound(uLong(raw.size()));
  std::string packed(packed_size, '\0');
  ASSERT_EQ(compress(reinterpret_cast<Bytef*>(packed.data()), &packed_size,
                     reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size())),
            Z_OK);
  packed.resize(packed_size);
  const auto be32 = [](std::uint32_t x) {
    return std::string{char(x >> 24), char(x >> 16 & 0xff), char(x >> 8 & 0xff), char(x & 0xff)};
  };
  std::string png = "\x89PNG\r\n\x1a\n";
  const auto chunk = [&](const std::string& type, const std::string& data) {
    const std::string body = type + data;
    png += be32(std::uint32_t(data.size())) + body +
           be32(std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size()))));
  };
  chunk("IHDR", be32(std::uint32_t(w)) + be32(std::uint32_t(h)) + std::string{16, 0, 0, 0, char(interlaced)});
  if (trns >= 0) chunk("tRNS", std::string{char(trns >> 8), char(trns & 0xff)});
  chunk("IDAT", packed);
  chunk("IEND", "");
  std::ofstream(file, std::ios::binary) << png;
}

// A world file changes where a PNG lies, never its heights: an interlaced 16-bit PNG (which GDAL 3.6 reads
// byte-swapped) and a 16-bit PNG whose tRNS grey is one of its heights (which GDAL takes for NoData) bake
// the same bits with a world file as without; a tiled bake, which reads the placed PNG through GDAL, refuses
// the interlaced one in one line naming it.
TEST_F(CliGdal, APngReadsTheSameHeightsWithAWorldFile) {
  const int w = 48, h = 40;
  std::vector<std::uint16_t> v(std::size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      v[std::size_t(y) * w + x] = std::uint16_t((x * 977 + y * 331 + (x * y) % 7 * 1500) % 40001);
  for (const bool interlaced : {true, false}) {
    SCOPED_TRACE(interlaced ? "interlaced" : "tRNS");
    const int trns = interlaced ? -1 : int(v[std::size_t(3) * w + 5]);
    std::vector<float> ao[2];
    for (const std::string name : {"alone", "placed"}) {
      const std::string stem = name + (interlaced ? "_i" : "_t");
      write_grey16_png(dir_ / (stem + ".png"), w, h, v, interlaced, trns);
      if (name == "placed") std::ofstream(dir_ / (stem + ".pgw")) << "1\n0\n0\n-1\n500000.5\n5000039.5\n";
      const fs::path job =
          write_job(stem + ".json", stem, {{"image", stem + ".png"}, {"height_scale", 1e-3}});
      const Result r = hfbake("bake " + job.string() + " --no-cache --quiet");
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const Raster a = read_raster(dir_ / ("out_" + stem) / (stem + ".p1.ao.tif"));
      ASSERT_EQ(a.values.size(), std::size_t(w) * h);
      ao[name == "placed"] = a.values;
    }
    EXPECT_EQ(max_abs_diff(ao[0], ao[1]), 0.0);
  }
  const fs::path job = dir_ / "placed_i.json";
  nlohmann::json doc = nlohmann::json::parse(std::ifstream(job));
  doc["bake"] = {{{"method", "relief"}, {"search_radius", 3}}};
  std::ofstream(job) << doc.dump();
  const Result t = hfbake("validate --tiles --tile-size 16 " + job.string());
  EXPECT_EQ(t.exit_code, 2) << t.err;
  ASSERT_EQ(t.error_lines().size(), 1u) << t.err;
  EXPECT_NE(t.error_lines()[0].find((dir_ / "placed_i.png").string() + ": is an interlaced 16-bit PNG"),
            std::string::npos)
      << t.err;
}

// Without "channel", a band GDAL declares alpha is passed over: a GeoTIFF whose first band is alpha (255
// everywhere) bakes its second. Named, the alpha band is read.
TEST_F(CliGdal, WithoutAChannelAnAlphaBandIsPassedOver) {
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  const int w = 32, h = 24;
  GDALDataset* ds = gtiff->Create((dir_ / "ab.tif").c_str(), w, h, 2, GDT_Float32, nullptr);
  ASSERT_TRUE(ds);
  std::vector<float> alpha(std::size_t(w) * h, 255.0f), z(std::size_t(w) * h);
  for (std::size_t t = 0; t < z.size(); ++t) z[t] = 3.0f + float(t % 7) * 0.5f;  // 3 .. 6
  ds->GetRasterBand(1)->SetColorInterpretation(GCI_AlphaBand);
  ds->GetRasterBand(2)->SetColorInterpretation(GCI_GrayIndex);
  ASSERT_EQ(
      ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, w, h, alpha.data(), w, h, GDT_Float32, 0, 0, nullptr),
      CE_None);
  ASSERT_EQ(ds->GetRasterBand(2)->RasterIO(GF_Write, 0, 0, w, h, z.data(), w, h, GDT_Float32, 0, 0, nullptr),
            CE_None);
  double gt[6] = {500000, 1, 0, 5000024, 0, -1};
  ds->SetGeoTransform(gt);
  GDALClose(ds);
  const Result r = hfbake("validate " + write_job("ab.json", "ab", {{"image", "ab.tif"}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("band 2 of 2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("heights 3 .. 6 world units"), std::string::npos) << r.err;
  const Result named =
      hfbake("validate " + write_job("a0.json", "a0", {{"image", "ab.tif"}, {"channel", 0}}).string());
  ASSERT_EQ(named.exit_code, 0) << named.err;
  EXPECT_NE(named.err.find("band 1 of 2"), std::string::npos) << named.err;
}

// A palette GeoTIFF's NoData index marks holes, and only those: an index whose colour's red equals the
// NoData index is a height like any other.
TEST_F(CliGdal, APalettesNoDataIndexIsTheOnlyHole) {
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  const int w = 32, h = 24;
  GDALDataset* ds = gtiff->Create((dir_ / "pal.tif").c_str(), w, h, 1, GDT_Byte, nullptr);
  ASSERT_TRUE(ds);
  std::vector<std::uint8_t> idx(std::size_t(w) * h);
  std::size_t holes = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::uint8_t i = (x + y) % 9 == 0       ? 2
                             : (x * 3 + y) % 5 == 0 ? 4
                                                    : std::uint8_t(10 + (x * y) % 50);
      idx[std::size_t(y) * w + x] = i;
      holes += i == 2;
    }
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, w, h, idx.data(), w, h, GDT_Byte, 0, 0, nullptr),
            CE_None);
  GDALColorTable table;
  for (int i = 0; i < 256; ++i) {
    const GDALColorEntry e{short(i == 4 ? 2 : 100 + i / 2), 0, 0, 255};  // index 4: red 2, the NoData index
    table.SetColorEntry(i, &e);
  }
  ds->GetRasterBand(1)->SetColorInterpretation(GCI_PaletteIndex);
  ds->GetRasterBand(1)->SetColorTable(&table);
  ds->GetRasterBand(1)->SetNoDataValue(2);
  double gt[6] = {500000, 1, 0, 5000024, 0, -1};
  ds->SetGeoTransform(gt);
  GDALClose(ds);
  const Result r = hfbake("validate " + write_job("pal.json", "pal", {{"image", "pal.tif"}}).string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(
      r.err.find("(" + std::to_string(holes) + " of " + std::to_string(w * h) + " texels have no valid"),
      std::string::npos)
      << holes << " holes: " << r.err;
  const Result f = hfbake(
      "validate " + write_job("palf.json", "palf", {{"image", "pal.tif"}, {"nodata", "fill"}}).string());
  EXPECT_EQ(f.exit_code, 0) << f.err;
  EXPECT_NE(f.err.find(std::to_string(holes) + " texels without a height"), std::string::npos)
      << holes << " holes: " << f.err;
}

// `hfbake horizon` at a point of a Web Mercator DEM, whose map units are 1 / cos(latitude) times the ground's
// there, measures on the ground: its far casters' elevations and distances are those of the same point on
// the DEM's own CRS (true to scale within 1e-4), up to the warp's resampling; its JSON records the factor,
// and it warns of nothing. Without the correction the elevations come out about 1.45 times flatter (in
// tan) and the distances 1.45 times longer.
TEST_F(CliGdal, HorizonMeasuresOnTheGroundInACrsFarFromTrueScale) {
  warp("-t_srs EPSG:3857 '" + kDem.string() + "' merc.tif");
  auto horizon = [&](const fs::path& dem, const std::string& out) {
    const Result r = hfbake("horizon '" + dem.string() + "' --at 15.8397,46.4551 --lonlat " +
                            "--directions 16 --format json --out " + (dir_ / out).string());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
    return nlohmann::json::parse(std::ifstream(dir_ / out));
  };
  const nlohmann::json merc = horizon(dir_ / "merc.tif", "merc.json"), own = horizon(kDem, "own.json");
  const double k = 1.0 / std::cos(46.4551 * std::acos(-1.0) / 180);
  EXPECT_NEAR(merc["map_scale_factor"].get<double>(), k, 0.005 * k);
  EXPECT_NEAR(own["map_scale_factor"].get<double>(), 1.0, 1e-3);
  int far = 0;
  for (std::size_t r = 0; r < own["rays"].size(); ++r) {
    const nlohmann::json &a = own["rays"][r], &b = merc["rays"][r];
    if (!a["found"].get<bool>() || a["distance"].get<double>() < 100) continue;
    ASSERT_TRUE(b["found"].get<bool>()) << r;
    ++far;
    EXPECT_NEAR(b["elevation_deg"].get<double>(), a["elevation_deg"].get<double>(), 0.1) << "ray " << r;
    EXPECT_NEAR(b["distance"].get<double>(), a["distance"].get<double>(), 0.01 * a["distance"].get<double>())
        << "ray " << r;
  }
  EXPECT_GE(far, 4) << "too few far casters to compare";
}

TEST_F(CliGdal, AnInterruptedBakeLeavesNoGeoTiff) {
  // p1's GeoTIFFs are staged before the long reference runs; the interrupt must take them away with it.
  make_crops();
  nlohmann::json j = {{"version", 1},
                      {"name", "stop"},
                      {"height", {{"image", "dem1m.tif"}}},
                      {"bake", {{{"method", "p1"}, {"directions", 8}}}},
                      {"reference", {{"samples", 200000}}},
                      {"output", {{"dir", "out"}, {"geotiff", true}}}};
  const fs::path p = dir_ / "stop.json";
  std::ofstream(p) << j.dump();
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const std::string devnull = "/dev/null";
    if (!freopen(devnull.c_str(), "w", stderr)) _exit(126);
    execl(HFBAKE_BINARY, "hfbake", "bake", p.c_str(), "--quiet", static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait until p1's GeoTIFF is in the staging folder, then interrupt.
  bool staged = false;
  const auto t0 = std::chrono::steady_clock::now();
  while (!staged && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(30)) {
    std::error_code ec;
    for (fs::recursive_directory_iterator it(dir_ / "out", ec), end; !ec && it != end; it.increment(ec))
      if (it->path().filename() == "stop.p1.ao.tif") staged = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(staged) << "p1's GeoTIFF never appeared in the staging folder";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_TRUE(!fs::exists(dir_ / "out") || fs::is_empty(dir_ / "out"));
}

}  // namespace

namespace {

TEST_F(CliGdal, CompassTermsOfTheHorizonChannels) {
  // A north-up plane rising 45° towards the north (row 0 = north is the high edge). Geometry says the
  // horizon looking north (uphill) has sine sin 45°, looking south -sin 45°, east and west 0. With K = 4,
  // channel k looks along phi = 90° k, compass azimuth A = 90° + phi: east, south, west, north.
  const int n = 33;
  std::vector<float> z(std::size_t(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) z[std::size_t(j) * n + i] = float(n - j);
  write_d96_raster("north_up.tif", n, z, {500000, 1, 0, 100000, 0, -1});
  const nlohmann::json j = {{"version", 1},
                            {"name", "plane"},
                            {"height", {{"image", "north_up.tif"}}},
                            {"bake", {{{"method", "p1"}, {"directions", 4}, {"layers", {"horizon"}}}}},
                            {"output", {{"dir", "out"}, {"geotiff", true}}}};
  std::ofstream(dir_ / "plane.json") << j.dump();
  const Result r = hfbake("bake --quiet " + (dir_ / "plane.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path tif = dir_ / "out" / "plane.p1.horizon.tif";
  const std::size_t centre = std::size_t(n / 2) * n + n / 2;
  const double s45 = std::sqrt(0.5);
  const double expected[4] = {0, -s45, 0, s45};  // east, south, west, north
  for (int k = 0; k < 4; ++k) {
    const Raster band = read_raster(tif, k + 1);
    ASSERT_EQ(band.values.size(), z.size());
    EXPECT_NEAR(band.values[centre], expected[k], 1e-3) << "channel " << k;
  }
  EXPECT_NE(gdalinfo_json(tif)["metadata"][""]["HFBAKE_AZIMUTH_CONVENTION"].get<std::string>().find(
                "north-up raster: +x = east, +y = south, compass azimuth = (90 + phi) mod 360"),
            std::string::npos);
}

// relief's "compass" directions are the map's: a plane rising 45° towards geographic north, written
// north-up, south-up (rows running north) and east-to-west (columns running west), gives at its centre the
// horizon +45° looking north, -45° south and 0 east and west on every raster, each band named by its compass
// azimuth (K = 4: north, east, south, west).
TEST_F(CliGdal, ReliefCompassDirectionsFollowTheRastersNorth) {
  const int n = 33;
  struct Orientation {
    const char* name;
    double gt[6];
    bool rows_north;
    const char* north;
  };
  const Orientation rasters[] = {
      {"north_up", {500000, 1, 0, 100000, 0, -1}, false, "north = image top (-y), east = image right (+x)"},
      {"south_up",
       {500000, 1, 0, 100000 - n, 0, 1},
       true,
       "north = image bottom (+y), east = image right (+x)"},
      {"east_to_west",
       {500000 + n, -1, 0, 100000, 0, -1},
       false,
       "north = image top (-y), east = image left (-x)"}};
  for (const Orientation& o : rasters) {
    SCOPED_TRACE(o.name);
    std::vector<float> z(std::size_t(n) * n);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) z[std::size_t(j) * n + i] = float(o.rows_north ? j : n - j);
    const std::string tif = std::string(o.name) + ".tif";
    write_d96_raster(tif, n, z, o.gt);
    const std::string out = std::string("out_") + o.name;
    const nlohmann::json j = {{"version", 1},
                              {"name", "plane"},
                              {"height", {{"image", tif}}},
                              {"bake",
                               {{{"method", "relief"},
                                 {"directions", 4},
                                 {"search_radius", 5},
                                 {"azimuth_convention", "compass"},
                                 {"layers", {"horizon_deg"}}}}},
                              {"output", {{"dir", out}, {"geotiff", true}}}};
    const fs::path job = dir_ / (std::string(o.name) + ".json");
    std::ofstream(job) << j.dump();
    const Result r = hfbake("bake --quiet " + job.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const fs::path result = dir_ / out / "plane.relief.horizon_deg.tif";
    const std::size_t centre = std::size_t(n / 2) * n + n / 2;
    const double expected[4] = {45, 0, -45, 0};  // north, east, south, west
    for (int k = 0; k < 4; ++k) {
      const Raster band = read_raster(result, k + 1);
      ASSERT_EQ(band.values.size(), z.size());
      EXPECT_NEAR(band.values[centre], expected[k], 0.01) << "channel " << k;
    }
    const nlohmann::json info = gdalinfo_json(result);
    EXPECT_NE(info.dump().find(o.north), std::string::npos) << info["metadata"].dump();
  }
}

TEST_F(CliGdal, SunTakesThePlaceAndTrueNorthFromTheCrs) {
  // A flat DEM in D96/TM 100 km east of its central meridian (15 E), about 46 N: the sun method takes the
  // centre's longitude and latitude and the grid's azimuth of true north there from the CRS. The truth is
  // OGR's transform, called here: the centre to longitude/latitude, and a step north from it back into
  // the grid, whose direction is true north's grid azimuth.
  const int n = 17;
  const double x0 = 600000, y0 = 110000;  // the raster's top-left corner
  {
    GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
    GDALDataset* ds = gtiff->Create((dir_ / "flat.tif").c_str(), n, n, 1, GDT_Float32, nullptr);
    ASSERT_TRUE(ds);
    double gt[6] = {x0, 2, 0, y0, 0, -2};
    ds->SetGeoTransform(gt);
    OGRSpatialReference srs;
    srs.importFromEPSG(3794);
    ds->SetSpatialRef(&srs);
    std::vector<float> z(std::size_t(n) * n, 300.0f);
    ASSERT_EQ(
        ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, n, n, z.data(), n, n, GDT_Float32, 0, 0, nullptr),
        CE_None);
    GDALClose(ds);
  }
  const nlohmann::json j = {{"version", 1},
                            {"name", "flat"},
                            {"height", {{"image", "flat.tif"}}},
                            {"bake",
                             {{{"method", "sun"},
                               {"start", "2026-06-21T11:00"},
                               {"end", "2026-06-21T13:00"},
                               {"utc_offset", 0},
                               {"step_minutes", 30},
                               {"layers", {"sun_hours"}}}}},
                            {"output", {{"dir", "out"}}}};
  std::ofstream(dir_ / "flat.json") << j.dump();
  const Result r = hfbake("bake --quiet " + (dir_ / "flat.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto in = OIIO::ImageInput::open((dir_ / "out" / "flat.sun.exr").string());
  ASSERT_TRUE(in);
  const std::string place = in->spec().get_string_attribute("hfbake:sun:place");
  double lat = 0, lon = 0, north = 0;
  ASSERT_EQ(std::sscanf(place.c_str(), "latitude %lf, longitude %lf", &lat, &lon), 2) << place;
  const auto at = place.find("true north at grid azimuth ");
  ASSERT_NE(at, std::string::npos) << place;
  ASSERT_EQ(std::sscanf(place.c_str() + at, "true north at grid azimuth %lf", &north), 1) << place;

  OGRSpatialReference grid, geo;
  grid.importFromEPSG(3794);
  geo.CopyGeogCSFrom(&grid);
  grid.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  geo.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> to_geo(OGRCreateCoordinateTransformation(&grid, &geo));
  std::unique_ptr<OGRCoordinateTransformation> to_grid(OGRCreateCoordinateTransformation(&geo, &grid));
  ASSERT_TRUE(to_geo && to_grid);
  double x = x0 + n, y = y0 - n;  // the raster's centre (2 m pixels)
  ASSERT_TRUE(to_geo->Transform(1, &x, &y));
  EXPECT_NEAR(lon, x, 1e-5);
  EXPECT_NEAR(lat, y, 1e-5);
  double xn = x, yn = y + 0.01;  // 1.1 km north
  ASSERT_TRUE(to_grid->Transform(1, &xn, &yn));
  const double cx = x0 + n, cy = y0 - n;
  const double expected = std::atan2(xn - cx, yn - cy) * 180 / M_PI;
  EXPECT_NEAR(north, expected, 2e-3);
  EXPECT_GT(std::abs(north), 0.5);  // 100 km from the central meridian at 46 N: about 1 degree
  // Flat ground around noon: the sun is up and in front of every texel for the whole 2 hours.
  const OIIO::ImageSpec& spec = in->spec();
  ASSERT_EQ(spec.nchannels, 1);
  std::vector<float> hours(std::size_t(spec.width) * spec.height);
  ASSERT_TRUE(in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, hours.data()));
  for (float h : hours) ASSERT_EQ(h, 2.0f);
}

// Without a CRS and without latitude and longitude, a sun entry has no place: validate refuses it naming the
// entry's latitude, and bake refuses it before any entry bakes.
TEST_F(CliGdal, SunWithoutAPlaceIsRefusedBeforeAnyBake) {
  const nlohmann::json j = {{"version", 1},
                            {"name", "s"},
                            {"height", {{"procedural", {{"kind", "fractal"}, {"size", {32, 32}}}}}},
                            {"bake",
                             {{{"method", "p1"}, {"directions", 8}, {"layers", {"ao"}}},
                              {{"method", "sun"},
                               {"start", "2026-06-21T11:00"},
                               {"end", "2026-06-21T13:00"},
                               {"utc_offset", 0},
                               {"layers", {"sun_hours"}}}}},
                            {"output", {{"dir", "out_s"}}}};
  const fs::path job = dir_ / "s.json";
  std::ofstream(job) << j.dump();
  for (const char* command : {"validate ", "bake --quiet --no-cache "}) {
    const Result r = hfbake(command + job.string());
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(
        r.err.find(job.string() +
                   ": /bake/1/latitude: required: the height field has no CRS that places it on the Earth"),
        std::string::npos)
        << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out_s"));
}

// The estimate `validate` prints holds what writing the COGs takes (the COG driver's own memory, and where
// holes are filled the writer's copy of a layer holding NoData), within the +-25 % every estimate keeps:
// the peak resident size of each bake (wait4's, that process alone) against "about N MiB to bake".
TEST_F(CliGdal, TheMemoryEstimateHoldsTheGeoTiffsWriting) {
  auto job = [&](const std::string& name, const nlohmann::json& entry, bool holes = false) {
    const nlohmann::json height =
        holes ? nlohmann::json{{"image", (kData / "TM1_564_146_nodata.tif").string()}, {"nodata", "fill"}}
              : nlohmann::json{{"image", kDem.string()}};
    const nlohmann::json j = {{"version", 1},
                              {"name", name},
                              {"height", height},
                              {"bake", {entry}},
                              {"output", {{"dir", "out_" + name}, {"geotiff", true}}}};
    const fs::path p = dir_ / (name + ".json");
    std::ofstream(p) << j.dump(2);
    return p;
  };
  std::vector<fs::path> jobs = {
      job("svf", {{"method", "relief"}, {"directions", 16}, {"search_radius", 4}, {"layers", {"svf"}}}),
      job("deg", {{"method", "relief"},
                  {"directions", 16},
                  {"search_radius", 4},
                  {"layers", {"svf", "horizon_deg"}}}),
      job("hz", {{"method", "p1"}, {"directions", 64}, {"layers", {"ao", "vsky", "horizon"}}}),
      job("hz_holes", {{"method", "p1"}, {"directions", 64}, {"layers", {"ao", "vsky", "horizon"}}}, true)};
  // A procedural 2048^2 field whose widest layer is a 16-direction horizon stack (256 MiB): its COG's
  // overviews and tiles take far less than the layer.
  const nlohmann::json procedural = {
      {"version", 1},
      {"name", "hz_2048"},
      {"height", {{"procedural", {{"kind", "fractal"}, {"size", {2048, 2048}}, {"seed", 3}}}}},
      {"environment", {{"uniform", 1}}},
      {"bake", {{{"method", "p1"}, {"directions", 16}, {"layers", {"ao", "horizon"}}}}},
      {"output", {{"dir", "out_hz_2048"}, {"geotiff", true}}}};
  const fs::path hz_2048 = dir_ / "hz_2048.json";
  std::ofstream(hz_2048) << procedural.dump(2);
  jobs.push_back(hz_2048);
  for (const fs::path& p : jobs) {
    const double estimate = hfbake::cli_test::validate_estimate_mib(dir_, p);
    ASSERT_GT(estimate, 0) << p;
    const hfbake::cli_test::BakePeak run = hfbake::cli_test::bake_peak(dir_, p);
    ASSERT_EQ(run.exit_code, 0) << p;
    const double peak = run.peak_mib;
    EXPECT_GT(peak, 0.75 * estimate) << p << ": estimate " << estimate << " MiB, peak " << peak << " MiB";
    EXPECT_LT(peak, 1.25 * estimate) << p << ": estimate " << estimate << " MiB, peak " << peak << " MiB";
  }
}

}  // namespace

namespace {

// A tiled bake within --memory-limit: at the least budget whose plan `validate --tiles` takes (found in
// steps of 4 MiB), the bake's peak resident size stays within that budget. The job's widest layer is a
// 16-band horizon_deg, so the COGs written after the tiles, not the tiles, set the least budget; beside it,
// hbao's layers' work files.
TEST_F(CliGdal, ATiledBakePeaksWithinTheLeastBudgetItsPlanTakes) {
  const nlohmann::json j = {{"version", 1},
                            {"name", "budget"},
                            {"height", {{"image", kDem.string()}}},
                            {"bake",
                             {{{"method", "relief"},
                               {"directions", 16},
                               {"search_radius", 4},
                               {"layers", {"svf", "openness_positive", "openness_negative", "horizon_deg"}}},
                              {{"method", "hbao"}, {"directions", 4}, {"max_distance", 8}}}},
                            {"output", {{"dir", "out_budget"}, {"geotiff", true}}}};
  const fs::path job = dir_ / "budget.json";
  std::ofstream(job) << j.dump(2);
  int least = 0;
  for (int mib = 120; mib <= 400 && least == 0; mib += 4)
    if (hfbake("validate --quiet --tiles --memory-limit " + std::to_string(mib) + "M " + job.string())
            .exit_code == 0)
      least = mib;
  ASSERT_GT(least, 0) << "no budget up to 400 MiB takes the job";
  const hfbake::cli_test::BakePeak run = hfbake::cli_test::run_peak(
      dir_, {"bake", "--quiet", "--tiles", "--memory-limit", std::to_string(least) + "M", job.string()});
  ASSERT_EQ(run.exit_code, 0);
  EXPECT_LE(run.peak_mib, double(least)) << "the least budget the plan takes: " << least << " MiB";
  EXPECT_TRUE(fs::exists(dir_ / "out_budget" / "budget.relief.horizon_deg.tif"));
}

}  // namespace
