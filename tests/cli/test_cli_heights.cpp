// Heights in world units whatever the file: an integer image's samples are its stored integers through
// OpenImageIO and GDAL alike, times height_scale (docs/heights.md). The truth: a float EXR holding the world
// heights the job states, baked by the same method, must give the same pixels; and the line validate and bake
// print names the reader and the range.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "run_hfbake.hpp"

namespace {
namespace fs = std::filesystem;
using hfbake::cli_test::Result;

constexpr int kSide = 48;

class CliHeights : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_test_cli_heights_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  Result hfbake(const std::string& args) { return hfbake::cli_test::run_hfbake(dir_, args); }

  // A job baking `height` with p1 (ao) into out_<name>.
  fs::path write_job(const std::string& name, const nlohmann::json& height) {
    const nlohmann::json j = {{"version", 1},
                              {"name", name},
                              {"height", height},
                              {"bake", {{{"method", "p1"}, {"directions", 8}}}},
                              {"output", {{"dir", "out_" + name}}}};
    const fs::path p = dir_ / (name + ".json");
    std::ofstream(p) << j.dump(2);
    return p;
  }

  // Writes `values` (one channel) as `type`; integer types get the values as their stored integers.
  void write_image(const std::string& name, const std::vector<float>& values, OIIO::TypeDesc type) {
    const fs::path p = dir_ / name;
    auto out = OIIO::ImageOutput::create(p.string());
    ASSERT_TRUE(out) << name;
    OIIO::ImageSpec spec(kSide, kSide, 1, type);
    ASSERT_TRUE(out->open(p.string(), spec)) << name;
    bool ok = false;
    if (type == OIIO::TypeDesc::UINT16) {
      std::vector<std::uint16_t> v(values.begin(), values.end());
      ok = out->write_image(type, v.data());
    } else if (type == OIIO::TypeDesc::UINT8) {
      std::vector<std::uint8_t> v(values.begin(), values.end());
      ok = out->write_image(type, v.data());
    } else if (type == OIIO::TypeDesc::INT16) {
      std::vector<std::int16_t> v(values.begin(), values.end());
      ok = out->write_image(type, v.data());
    } else {
      ok = out->write_image(OIIO::TypeDesc::FLOAT, values.data());
    }
    ASSERT_TRUE(ok && out->close()) << name;
  }

  // The ao channel of a bake's EXR.
  std::vector<float> ao(const std::string& name) {
    const fs::path p = dir_ / ("out_" + name) / (name + ".p1.exr");
    auto in = OIIO::ImageInput::open(p.string());
    if (!in) return {};
    const OIIO::ImageSpec& spec = in->spec();
    int c = 0;
    for (int k = 0; k < spec.nchannels; ++k)
      if (spec.channelnames[k] == "ao") c = k;
    std::vector<float> v(std::size_t(spec.width) * spec.height);
    if (!in->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, v.data())) return {};
    return v;
  }

  fs::path dir_;
};

// Integer heights spanning exactly [0, top]: a bump and a ridge, so the bake has something to occlude.
std::vector<float> integer_heights(float top) {
  std::vector<double> v(std::size_t(kSide) * kSide);
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      const double x = (i - 20.0) / 7.0, y = (j - 26.0) / 9.0;
      v[std::size_t(j) * kSide + i] = 0.7 * std::exp(-(x * x + y * y)) + 0.15 * std::sin(0.4 * i + 0.2 * j);
    }
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double a = *lo, b = *hi;
  std::vector<float> out(v.size());
  for (std::size_t t = 0; t < v.size(); ++t) out[t] = float(std::round(top * (v[t] - a) / (b - a)));
  return out;
}

// The world heights hfbake makes of stored heights and a scale: float(stored * scale).
std::vector<float> world(const std::vector<float>& stored, double scale) {
  std::vector<float> w(stored.size());
  for (std::size_t t = 0; t < stored.size(); ++t) w[t] = float(double(stored[t]) * scale);
  return w;
}

TEST_F(CliHeights, IntegerImagesBakeLikeAFloatImageOfTheSameWorldHeights) {
  const double relief = 12.0;  // world units over a 48-unit field
  struct Case {
    const char* file;
    OIIO::TypeDesc type;
    float top;
  };
  for (const Case& c :
       {Case{"h16.png", OIIO::TypeDesc::UINT16, 65535}, Case{"h8.png", OIIO::TypeDesc::UINT8, 255},
        Case{"h16.tif", OIIO::TypeDesc::UINT16, 65535}}) {
    SCOPED_TRACE(c.file);
    const std::vector<float> stored = integer_heights(c.top);
    const double scale = relief / c.top;
    write_image(c.file, stored, c.type);
    write_image(std::string(c.file) + ".exr", world(stored, scale), OIIO::TypeDesc::FLOAT);
    std::string stem = c.file;  // h16.png -> h16_png
    std::replace(stem.begin(), stem.end(), '.', '_');
    const Result a = hfbake("bake " + write_job(stem, {{"image", c.file}, {"height_scale", scale}}).string());
    ASSERT_EQ(a.exit_code, 0) << a.err;
    const Result b = hfbake("bake --quiet " +
                            write_job(stem + "_exr", {{"image", std::string(c.file) + ".exr"}}).string());
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const std::vector<float> from_integers = ao(stem), from_floats = ao(stem + "_exr");
    ASSERT_EQ(from_integers.size(), std::size_t(kSide) * kSide);
    EXPECT_EQ(from_integers, from_floats);
    // The bake is not all white: the heights were not scaled to [0, 1] on the way.
    float lowest = 1;
    for (const float v : from_integers) lowest = std::min(lowest, v);
    EXPECT_LT(lowest, 0.9f);
    // The bake's line names the reader, the sample type and the range in world units.
    const std::string type = c.type == OIIO::TypeDesc::UINT16 ? "uint16" : "uint8";
    const std::string format = std::string(c.file).ends_with(".png") ? "png" : "tiff";
    EXPECT_NE(a.err.find("heights: " + std::string(c.file) + " through OpenImageIO (" + format + ", " + type +
                         " integers as stored); 48x48 texels of 1 (48 x 48 world units); stored 0 .. "),
              std::string::npos)
        << a.err;
    EXPECT_NE(a.err.find(" -> heights 0 .. 12 world units (relief 12)"), std::string::npos) << a.err;
    EXPECT_EQ(a.err.find("warning"), std::string::npos) << a.err;
  }
}

// GDAL (the image with georeferencing beside it in an .aux.xml) and OpenImageIO (the same image without) read
// the same integers for every integer type the format holds (PNG: uint8, uint16; TIFF: uint8, uint16, int16):
// the same bake as a float EXR of the world heights the job states. A placed PNG is read by OpenImageIO,
// GDAL only placing it (docs/heights.md).
TEST_F(CliHeights, GdalAndOpenImageIoAgreeOnEveryIntegerType) {
  const double relief = 10.0;
  struct Case {
    const char* ext;
    OIIO::TypeDesc type;
    float top, offset;  // stored integers: offset .. offset + top
    const char *oiio, *gdal;
  };
  for (const Case& c :
       {Case{"png", OIIO::TypeDesc::UINT8, 255, 0, "png, uint8", "OpenImageIO, placed by GDAL (PNG, uint8"},
        Case{"png", OIIO::TypeDesc::UINT16, 65535, 0, "png, uint16",
             "OpenImageIO, placed by GDAL (PNG, uint16"},
        Case{"tif", OIIO::TypeDesc::UINT8, 255, 0, "tiff, uint8", "GDAL (GTiff, Byte"},
        Case{"tif", OIIO::TypeDesc::UINT16, 65535, 0, "tiff, uint16", "GDAL (GTiff, UInt16"},
        Case{"tif", OIIO::TypeDesc::INT16, 65535, -32768, "tiff, int16", "GDAL (GTiff, Int16"}}) {
    const std::string type = c.type.c_str(), name = type + "_" + c.ext;
    SCOPED_TRACE(name);
    std::vector<float> stored = integer_heights(c.top);
    for (float& v : stored) v += c.offset;
    const double scale = relief / c.top;
    const std::string plain = "plain_" + name + "." + c.ext, geo = "geo_" + name + "." + c.ext;
    write_image(plain, stored, c.type);
    write_image(geo, stored, c.type);
    write_image(name + ".exr", world(stored, scale), OIIO::TypeDesc::FLOAT);
    std::ofstream(dir_ / (geo + ".aux.xml"))
        << "<PAMDataset>\n  <GeoTransform>0, 1, 0, 48, 0, -1</GeoTransform>\n</PAMDataset>\n";
    const Result a =
        hfbake("bake " + write_job("plain_" + name, {{"image", plain}, {"height_scale", scale}}).string());
    ASSERT_EQ(a.exit_code, 0) << a.err;
    const Result b =
        hfbake("bake " + write_job("geo_" + name, {{"image", geo}, {"height_scale", scale}}).string());
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const Result f = hfbake("bake --quiet " + write_job("exr_" + name, {{"image", name + ".exr"}}).string());
    ASSERT_EQ(f.exit_code, 0) << f.err;
    EXPECT_NE(a.err.find("through OpenImageIO (" + std::string(c.oiio) + " integers as stored)"),
              std::string::npos)
        << a.err;
    EXPECT_NE(b.err.find("through " + std::string(c.gdal) + " integers as stored)"), std::string::npos)
        << b.err;
    // The stored range as integers, whatever the reader.
    char range[96];
    std::snprintf(range, sizeof range, "stored %.0f .. %.0f", c.offset, c.offset + c.top);
    EXPECT_NE(a.err.find(range), std::string::npos) << a.err;
    EXPECT_NE(b.err.find(range), std::string::npos) << b.err;
    const std::vector<float> x = ao("plain_" + name), y = ao("geo_" + name), z = ao("exr_" + name);
    ASSERT_EQ(x.size(), std::size_t(kSide) * kSide);
    EXPECT_EQ(x, z);
    EXPECT_EQ(y, z);
    EXPECT_LT(*std::min_element(z.begin(), z.end()), 0.9f);  // not a flattened field
  }
}

// The heights line says which channel of a several-channel image was read, and a GDAL raster's own scale and
// offset (not applied; height_scale and height_offset apply them): a user sees why the heights are not the
// ones another GIS tool shows.
TEST_F(CliHeights, TheHeightsLineNamesTheChannelAndTheFilesScale) {
  {
    const fs::path p = dir_ / "rgb.png";
    auto out = OIIO::ImageOutput::create(p.string());
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(kSide, kSide, 3, OIIO::TypeDesc::UINT16);
    ASSERT_TRUE(out->open(p.string(), spec));
    std::vector<std::uint16_t> v(std::size_t(kSide) * kSide * 3);
    for (std::size_t t = 0; t < v.size(); ++t) v[t] = std::uint16_t(t % 997);
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT16, v.data()));
    out->close();
  }
  Result r = hfbake("validate " + write_job("rgb", {{"image", "rgb.png"}, {"channel", "G"}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("through OpenImageIO (png, channel G of R, G, B, uint16"), std::string::npos) << r.err;

  write_image("scaled.tif", integer_heights(65535), OIIO::TypeDesc::UINT16);
  std::ofstream(dir_ / "scaled.tif.aux.xml")
      << "<PAMDataset>\n  <GeoTransform>0, 1, 0, 48, 0, -1</GeoTransform>\n  <PAMRasterBand band=\"1\">\n"
         "    <Offset>250</Offset>\n    <Scale>0.01</Scale>\n  </PAMRasterBand>\n</PAMDataset>\n";
  r = hfbake("validate " + write_job("scaled", {{"image", "scaled.tif"}, {"height_scale", 0.001}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(
      r.err.find("through GDAL (GTiff, UInt16 integers as stored) (the file declares scale 0.01 and offset "
                 "250, not applied"),
      std::string::npos)
      << r.err;
  // Without height_scale the stored centimetres are far steeper than terrain: the warning names the file's
  // scale and the keys that apply it.
  r = hfbake("validate " + write_job("scaled_as_stored", {{"image", "scaled.tif"}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("steeper than any terrain; check height_scale (world units per stored integer"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("(the file declares scale 0.01, not applied: \"height_scale\": 0.01 and "
                       "\"height_offset\": 250 apply it)"),
            std::string::npos)
      << r.err;
}

// A declared scale the job does not apply is a warning whatever the relief (decimetres read as metres are
// ten times too steep, a plausible relief): as `hfbake horizon` warns. Given height_scale, no warning.
TEST_F(CliHeights, ADeclaredScaleNotAppliedIsWarnedWhateverTheRelief) {
  write_image("dm.tif", integer_heights(150), OIIO::TypeDesc::UINT16);
  std::ofstream(dir_ / "dm.tif.aux.xml")
      << "<PAMDataset>\n  <GeoTransform>0, 1, 0, 48, 0, -1</GeoTransform>\n  <PAMRasterBand band=\"1\">\n"
         "    <Scale>0.1</Scale>\n  </PAMRasterBand>\n</PAMDataset>\n";
  Result r = hfbake("validate " + write_job("dm", {{"image", "dm.tif"}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("hfbake: warning: " + (dir_ / "dm.json").string()), std::string::npos) << r.err;
  EXPECT_NE(
      r.err.find("the file declares scale 0.1 and offset 0, not applied (heights are the stored values, "
                 "docs/heights.md): \"height_scale\": 0.1 and \"height_offset\": 0 apply them"),
      std::string::npos)
      << r.err;
  r = hfbake("validate " + write_job("dm_scaled", {{"image", "dm.tif"}, {"height_scale", 0.1}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
}

// A height image OpenImageIO reads brings its libraries in before the bake: validate's estimate shows them as
// a part of their own, not as the scene's (a 2 x 2 PNG's scene is the process and its few texels).
TEST_F(CliHeights, AnImageReadersLibrariesAreAPartOfTheirOwn) {
  write_image("small.png", integer_heights(255), OIIO::TypeDesc::UINT8);
  const Result r = hfbake("validate " + write_job("small", {{"image", "small.png"}}).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto at = r.err.find("to bake: scene ");
  ASSERT_NE(at, std::string::npos) << r.err;
  EXPECT_LT(std::stod(r.err.substr(at + 15)), 80) << r.err;  // MiB: the process and the field
  EXPECT_NE(r.err.find(" MiB, image reader "), std::string::npos) << r.err;
}

// JPEG heights are lossy: validate says so (a plausible relief, so no other warning takes its place).
TEST_F(CliHeights, JpegHeightsAreWarnedLossy) {
  write_image("h.jpg", integer_heights(255), OIIO::TypeDesc::UINT8);
  const Result r =
      hfbake("validate " + write_job("jpg", {{"image", "h.jpg"}, {"height_scale", 0.05}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("hfbake: warning: " + (dir_ / "jpg.json").string() + ": JPEG is lossy"),
            std::string::npos)
      << r.err;
}

// Without height_scale, a 16-bit image's integers are world units: validate states the range and warns that
// the relief is implausible; a float image of [0, 1] heights over a 48-unit field is warned nearly flat.
TEST_F(CliHeights, ValidateStatesTheRangeAndWarnsOnImplausibleRelief) {
  write_image("raw16.png", integer_heights(65535), OIIO::TypeDesc::UINT16);
  Result r = hfbake("validate " + write_job("raw16", {{"image", "raw16.png"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("; heights 0 .. 65535 world units (relief 65535)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("hfbake: warning: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("times the field's 48-unit side: steeper than any terrain"), std::string::npos)
      << r.err;
  // bake says it too, --quiet or not: --quiet silences progress, not warnings.
  r = hfbake("bake --quiet --no-cache " + (dir_ / "raw16.json").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("hfbake: warning: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("steeper than any terrain"), std::string::npos) << r.err;

  std::vector<float> unit = integer_heights(65535);
  for (float& v : unit) v /= 65535;
  write_image("unit.exr", unit, OIIO::TypeDesc::FLOAT);
  r = hfbake("validate " + write_job("unit", {{"image", "unit.exr"}, {"texel_size", 100}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("through OpenImageIO (openexr, float)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nearly flat"), std::string::npos) << r.err;

  // A raster with a CRS holds elevations: the same few tenths of relief (a plain's lidar tile) are baked
  // without the warning; without the CRS, the same file is warned.
  std::vector<float> plain = integer_heights(65535);
  for (float& v : plain) v *= 0.3f / 65535;
  write_image("plain.tif", plain, OIIO::TypeDesc::FLOAT);
  write_image("plain_crs.tif", plain, OIIO::TypeDesc::FLOAT);
  std::ofstream(dir_ / "plain_crs.tif.aux.xml")
      << "<PAMDataset>\n  <SRS>EPSG:32633</SRS>\n"
         "  <GeoTransform>500000, 1, 0, 6500048, 0, -1</GeoTransform>\n"
         "</PAMDataset>\n";
  r = hfbake("validate " + write_job("plain", {{"image", "plain.tif"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("nearly flat"), std::string::npos) << r.err;
  r = hfbake("validate " + write_job("plain_crs", {{"image", "plain_crs.tif"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("through GDAL"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;

  // A nearly flat map whose relief one stray texel sets (a 16-bit image of 0 .. 3 with a marker at 65535):
  // the relief looks plausible, yet the bake is close to unoccluded; validate names the texel.
  std::vector<float> marked(std::size_t(kSide) * kSide);
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) marked[std::size_t(j) * kSide + i] = float((i / 7 + j / 5) % 4);
  marked[std::size_t(7) * kSide + 5] = 65535;
  write_image("marked.png", marked, OIIO::TypeDesc::UINT16);
  r = hfbake("validate " +
             write_job("marked", {{"image", "marked.png"}, {"height_scale", 20.0 / 65535}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("but 1 texel stands out of them by up to 19.99"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(the farthest at texel (5, 7))"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nearly flat"), std::string::npos) << r.err;

  // A reprojection's fill: a georeferenced raster's corners stored as 0 beside terrain 250 units up is
  // warned, naming the corner; a coast, its sea at 0 beside a beach rising from it, is not.
  std::vector<float> warped(std::size_t(kSide) * kSide), coast(warped.size());
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      const std::size_t t = std::size_t(j) * kSide + i;
      warped[t] = i + j < 12 ? 0.0f : 250.0f + float((i * 7 + j * 3) % 11);
      coast[t] = i < 16 ? 0.0f : 0.2f * float(i - 15) + 0.1f * float((i * 7 + j * 3) % 3);
    }
  for (const char* name : {"warped", "coast"}) {
    write_image(std::string(name) + ".tif", name[0] == 'w' ? warped : coast, OIIO::TypeDesc::FLOAT);
    std::ofstream(dir_ / (std::string(name) + ".tif.aux.xml"))
        << "<PAMDataset>\n  <SRS>EPSG:32633</SRS>\n"
           "  <GeoTransform>500000, 1, 0, 6500048, 0, -1</GeoTransform>\n"
           "</PAMDataset>\n";
  }
  r = hfbake("validate " + write_job("warped", {{"image", "warped.tif"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("78 texels (3.39 %) are stored as exactly 0, the corner (0, 0) among them, 250 world "
                       "units or more below 99 % of the other heights"),
            std::string::npos)
      << r.err;
  r = hfbake("validate " + write_job("coast", {{"image", "coast.tif"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;

  // Holes stored as -9999 that the file does not declare: the steepness warning says what would make them
  // holes.
  std::vector<float> holed = warped;
  holed[std::size_t(30) * kSide + 30] = -9999;
  write_image("holed.tif", holed, OIIO::TypeDesc::FLOAT);
  r = hfbake("validate " + write_job("holed", {{"image", "holed.tif"}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("steeper than any terrain; check height_scale (world units per stored unit) and "
                       "texel_size; if the texels stored as -9999 mark missing data, \"nodata_value\": -9999 "
                       "with \"nodata\": \"fill\" in height makes them holes"),
            std::string::npos)
      << r.err;

  // A NoData value that real heights hold: 40 on a ramp of whole heights is a diagonal line of texels,
  // filled as holes with a warning; a block of -9999 holes (outside the heights) is filled without one.
  std::vector<float> ramp(std::size_t(kSide) * kSide);
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) ramp[std::size_t(j) * kSide + i] = float(i + j);
  write_image("ramp.tif", ramp, OIIO::TypeDesc::FLOAT);
  r = hfbake("validate " +
             write_job("ramp", {{"image", "ramp.tif"}, {"nodata", "fill"}, {"nodata_value", 40}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("the NoData value 40 lies inside the other heights' range (0 .. 94) and its 41 texels "
                       "lie in thin lines and specks, not blocks: real heights taken for holes?"),
            std::string::npos)
      << r.err;
  for (int j = 10; j < 20; ++j)
    for (int i = 10; i < 20; ++i) ramp[std::size_t(j) * kSide + i] = -9999;
  write_image("voids.tif", ramp, OIIO::TypeDesc::FLOAT);
  r = hfbake(
      "validate " +
      write_job("voids", {{"image", "voids.tif"}, {"nodata", "fill"}, {"nodata_value", -9999}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;

  // A plausible field: no warning, and --quiet prints nothing.
  r = hfbake("validate --quiet " +
             write_job("fine", {{"image", "raw16.png"}, {"height_scale", 20.0 / 65535}}).string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

}  // namespace
