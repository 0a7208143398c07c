// output.textures end to end (the hfbake binary): the textures equal the float EXR's values quantised by
// the issue's formula, a slope's bent normals follow the documented world and tangent conventions (the
// plane's normal in closed form is the truth), files appear under textures/ with the stable names, and
// bad texture entries are refused by validate in one line with their JSON pointer, nothing written.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "../cli/run_hfbake.hpp"
#include "temp_folder.hpp"

namespace {
namespace fs = std::filesystem;
using hfbake::cli_test::run_hfbake;
using hfbake::test::TempFolder;
using nlohmann::json;
constexpr double kPi = 3.14159265358979323846;

struct Pixels {
  int width = 0, height = 0, channels = 0;
  std::vector<float> values;  // read as float: 8/16-bit files come back as value / (2^bits - 1)
  OIIO::TypeDesc type;
};

Pixels read(const fs::path& file, const std::string& channel_prefix = "") {
  Pixels p;
  auto in = OIIO::ImageInput::open(file.string());
  if (!in) return p;
  const OIIO::ImageSpec& spec = in->spec();
  p.width = spec.width;
  p.height = spec.height;
  p.type = spec.format;
  int first = 0, count = spec.nchannels;
  if (!channel_prefix.empty()) {
    count = 0;
    for (int c = 0; c < spec.nchannels; ++c)
      if (spec.channelnames[c].rfind(channel_prefix, 0) == 0) {
        if (!count) first = c;
        ++count;
      }
  }
  p.channels = count;
  p.values.resize(std::size_t(p.width) * p.height * count);
  in->read_image(0, 0, first, first + count, OIIO::TypeDesc::FLOAT, p.values.data());
  return p;
}

// A 33 x 33 plane at 30 degrees facing +y (aspect 90: downhill towards +y), p1 with ao and bent normals.
json job(const fs::path& out, const json& textures,
         const json& procedural = {
             {"kind", "slope"}, {"size", {33, 33}}, {"angle_deg", 30}, {"aspect_deg", 90}}) {
  return {{"version", 1},
          {"name", "slope"},
          {"height", {{"procedural", procedural}}},
          {"bake", {{{"method", "p1"}, {"directions", 16}, {"layers", {"ao", "vsky", "bent_normal"}}}}},
          {"output", {{"dir", out.string()}, {"pixel_type", "float"}, {"textures", textures}}}};
}

fs::path write(const TempFolder& dir, const std::string& name, const json& j) {
  const fs::path f = dir / name;
  std::ofstream(f) << j.dump(2);
  return f;
}

TEST(TextureCli, AoTexturesAreTheExrValuesRounded) {
  TempFolder dir;
  for (int bits : {8, 16}) {
    const fs::path out = dir / ("out" + std::to_string(bits));
    const fs::path f = write(dir, "j.json", job(out, json::array({{{"layers", {"ao"}}, {"bits", bits}}})));
    const auto r = run_hfbake(dir.path(), "bake --quiet " + f.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Pixels exr = read(out / "slope.p1.exr", "ao.");
    const Pixels png = read(out / "textures" / "slope.p1.ao.png");
    ASSERT_EQ(png.channels, 1);
    ASSERT_EQ(png.width, 33);
    EXPECT_EQ(png.type, bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16);
    const double top = bits == 8 ? 255 : 65535;
    double lowest = 1;
    for (std::size_t i = 0; i < exr.values.size(); ++i) {
      ASSERT_EQ(std::lround(png.values[i] * top), std::lround(std::round(double(exr.values[i]) * top))) << i;
      lowest = std::min(lowest, double(exr.values[i]));
    }
    EXPECT_GT(lowest, 0.99);  // a plane: AO 1 (the values are not sRGB-brightened, not 226..255 of 1)
  }
}

// Every format and depth with the sRGB curve reads back as the EXR's values encoded (IEC 61966-2-1's curve,
// written out here): a TIFF's sRGB tag once moved its own image directory out of reach.
TEST(TextureCli, SrgbTexturesOfEveryFormatAreTheExrValuesEncoded) {
  TempFolder dir;
  const json textures = json::array({{{"layers", {"vsky"}}, {"transfer", "srgb"}, {"format", "png"}},
                                     {{"layers", {"vsky"}}, {"transfer", "srgb"}, {"format", "tif"}},
                                     {{"layers", {"vsky"}}, {"transfer", "srgb"}, {"format", "tga"}},
                                     {{"pack", "vsky16"},
                                      {"channels", {{"R", "vsky"}, {"G", "ao"}, {"B", "vsky"}}},
                                      {"transfer", "srgb"},
                                      {"format", "tif"},
                                      {"bits", 16}}});
  const fs::path out = dir / "out";
  const fs::path f = write(dir, "j.json", job(out, textures));
  const auto r = run_hfbake(dir.path(), "bake --quiet " + f.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Pixels exr = read(out / "slope.p1.exr", "vsky.");
  ASSERT_EQ(exr.values.size(), std::size_t(33 * 33));
  auto encode = [](double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055; };
  for (const char* name :
       {"slope.p1.vsky.png", "slope.p1.vsky.tif", "slope.p1.vsky.tga", "slope.p1.vsky16.tif"}) {
    SCOPED_TRACE(name);
    const Pixels tex = read(out / "textures" / name);
    ASSERT_EQ(tex.width, 33);
    ASSERT_EQ(tex.height, 33);
    const double top = tex.type == OIIO::TypeDesc::UINT16 ? 65535 : 255;
    for (std::size_t i = 0; i < exr.values.size(); ++i)
      ASSERT_EQ(std::lround(tex.values[i * std::size_t(tex.channels)] * top),
                std::lround(encode(double(exr.values[i])) * top))
          << i;
  }
  EXPECT_LT(exr.values[16 * 33 + 16], 0.95);  // a 30 degree slope sees (1 + cos 30) / 2 of the sky
}

TEST(TextureCli, SlopeBentNormalsFollowTheDocumentedConventions) {
  TempFolder dir;
  const fs::path out = dir / "out";
  const json textures =
      json::array({{{"layers", {"bent_normal"}}, {"space", "world"}, {"format", "tif"}, {"bits", 16}},
                   {{"layers", {"bent_normal"}}, {"y", "opengl"}, {"bits", 16}},
                   {{"pack", "bn_dx"}, {"channels", {{"R", "ao"}}}, {"format", "tga"}},
                   {{"layers", {"bent_normal"}}, {"y", "directx"}, {"format", "tga"}}});
  const auto r = run_hfbake(dir.path(), "bake --quiet " + write(dir, "j.json", job(out, textures)).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The plane's normal in closed form: tilted 30 degrees towards its aspect, +y.
  const double n[3] = {0, std::sin(30 * kPi / 180), std::cos(30 * kPi / 180)};
  const Pixels world = read(out / "textures" / "slope.p1.bent_normal.tif");
  const Pixels gl = read(out / "textures" / "slope.p1.bent_normal.png");
  const Pixels dx = read(out / "textures" / "slope.p1.bent_normal.tga");
  ASSERT_EQ(world.channels, 3);
  ASSERT_EQ(gl.channels, 3);
  ASSERT_EQ(dx.channels, 3);
  const std::size_t t = (16 * 33 + 16) * 3;  // the centre texel
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(world.values[t + c], 0.5 + 0.5 * n[c], 0.003) << "world " << c;
  EXPECT_NEAR(gl.values[t + 0], 0.5, 0.003);
  EXPECT_NEAR(gl.values[t + 1], 0.5 - 0.5 * n[1], 0.003);  // OpenGL: G = image up = -y
  EXPECT_NEAR(gl.values[t + 2], 0.5 + 0.5 * n[2], 0.003);
  EXPECT_NEAR(dx.values[t + 1], 0.5 + 0.5 * n[1], 0.004);  // DirectX: G = image down = +y (8 bits)
  EXPECT_GT(dx.values[t + 1], 0.6);
  EXPECT_LT(gl.values[t + 1], 0.4);
}

TEST(TextureCli, FlatFieldIsHalfHalfOneInBothTangentConventions) {
  TempFolder dir;
  const fs::path out = dir / "out";
  const json textures = json::array({{{"layers", {"bent_normal"}}, {"y", "opengl"}, {"bits", 16}},
                                     {{"layers", {"bent_normal"}}, {"y", "directx"}, {"format", "tif"}}});
  const json flat = {{"kind", "flat"}, {"size", {17, 17}}};
  const auto r =
      run_hfbake(dir.path(), "bake --quiet " + write(dir, "j.json", job(out, textures, flat)).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Pixels gl = read(out / "textures" / "slope.p1.bent_normal.png");
  const Pixels dx = read(out / "textures" / "slope.p1.bent_normal.tif");
  ASSERT_EQ(gl.values.size(), 17u * 17u * 3u);
  ASSERT_EQ(dx.values.size(), gl.values.size());
  for (std::size_t t = 0; t < 17 * 17; ++t) {
    // 0.5 is stored as round(0.5 * 65535) = 32768 and round(0.5 * 255) = 128.
    EXPECT_EQ(std::lround(gl.values[3 * t] * 65535), 32768);
    EXPECT_EQ(std::lround(gl.values[3 * t + 1] * 65535), 32768);
    EXPECT_EQ(std::lround(gl.values[3 * t + 2] * 65535), 65535);
    EXPECT_EQ(std::lround(dx.values[3 * t] * 255), 128);
    EXPECT_EQ(std::lround(dx.values[3 * t + 1] * 255), 128);
    EXPECT_EQ(std::lround(dx.values[3 * t + 2] * 255), 255);
  }
}

// The height field's own normal map: the slope's normal in closed form is the truth, in both tangent
// conventions, whatever the methods bake (p1 here writes no bent_normal).
TEST(TextureCli, HeightNormalMapIsTheFieldsNormal) {
  TempFolder dir;
  const fs::path out = dir / "out";
  json j =
      job(out, json::array({{{"layers", {"normal"}}, {"bits", 16}},
                            {{"layers", {"normal"}}, {"y", "directx"}, {"format", "tif"}, {"bits", 16}}}));
  j["bake"][0]["layers"] = {"ao"};
  const auto r = run_hfbake(dir.path(), "bake --quiet " + write(dir, "j.json", j).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Pixels gl = read(out / "textures" / "slope.height.normal.png");
  const Pixels dx = read(out / "textures" / "slope.height.normal.tif");
  ASSERT_EQ(gl.channels, 3);
  ASSERT_EQ(gl.width, 33);
  ASSERT_EQ(dx.values.size(), gl.values.size());
  const double ny = std::sin(30 * kPi / 180), nz = std::cos(30 * kPi / 180);
  for (const std::size_t texel : {std::size_t(0), std::size_t(16 * 33 + 16), std::size_t(33 * 33 - 1)}) {
    const std::size_t t = texel * 3;
    EXPECT_NEAR(gl.values[t + 0], 0.5, 1e-4);
    EXPECT_NEAR(gl.values[t + 1], 0.5 - 0.5 * ny, 1e-4);  // OpenGL: G = image up, the slope faces +y (down)
    EXPECT_NEAR(gl.values[t + 2], 0.5 + 0.5 * nz, 1e-4);
    EXPECT_NEAR(dx.values[t + 1], 0.5 + 0.5 * ny, 1e-4);  // DirectX: G = image down
  }
  // The bake's summary names the folder holding every output (the normal map, written first, is in its
  // textures/).
  const auto said = run_hfbake(dir.path(), "bake " + (dir / "j.json").string());
  ASSERT_EQ(said.exit_code, 0) << said.err;
  EXPECT_NE(said.err.find("outputs in " + out.string() + "\n"), std::string::npos) << said.err;
}

// A repeat tile's textures keep the field's size with padding asked for (no 2 p border that would end the
// tiling), and they tile: across the wrap seam the texture steps no more than between neighbours inside.
TEST(TextureCli, RepeatTileTexturesKeepTheirSizeAndTile) {
  TempFolder dir;
  const json tile = {
      {"kind", "fractal"}, {"size", {64, 48}}, {"seed", 3}, {"amplitude", 12}, {"feature_size", 16}};
  auto tiled_job = [&](const fs::path& out, const json& textures) {
    json j = job(out, textures, tile);
    j["height"]["wrap"] = "repeat";
    return j;
  };
  const fs::path padded = dir / "padded", plain = dir / "plain";
  const auto r = run_hfbake(
      dir.path(),
      "bake " + write(dir, "a.json", tiled_job(padded, json::array({{{"layers", {"ao"}}, {"padding", 8}}})))
                    .string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("textures/slope.p1.ao.png: no padding added (the field repeats"), std::string::npos)
      << r.err;
  const auto q = run_hfbake(
      dir.path(),
      "bake --quiet " + write(dir, "b.json", tiled_job(plain, json::array({{{"layers", {"ao"}}}}))).string());
  ASSERT_EQ(q.exit_code, 0) << q.err;
  const Pixels a = read(padded / "textures" / "slope.p1.ao.png");
  const Pixels b = read(plain / "textures" / "slope.p1.ao.png");
  ASSERT_EQ(a.width, 64);
  ASSERT_EQ(a.height, 48);
  EXPECT_EQ(a.values, b.values);
  // The seam: column 63 next to column 0 and row 47 next to row 0, against the largest step inside.
  auto at = [&](int x, int y) { return double(a.values[std::size_t(y) * 64 + x]); };
  double inside = 0, seam = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      if (x + 1 < 64) inside = std::max(inside, std::abs(at(x + 1, y) - at(x, y)));
      if (y + 1 < 48) inside = std::max(inside, std::abs(at(x, y + 1) - at(x, y)));
    }
  for (int y = 0; y < 48; ++y) seam = std::max(seam, std::abs(at(63, y) - at(0, y)));
  for (int x = 0; x < 64; ++x) seam = std::max(seam, std::abs(at(x, 47) - at(x, 0)));
  EXPECT_GT(inside, 0.01);  // the field has relief
  EXPECT_LE(seam, inside);
}

// A horizon_distance with no caster (+inf, on the slope's uphill border looking uphill, and wherever a ray
// leaves the field unblocked) is stored as 1 by the texture rule: no clipping is reported for it, while a
// finite distance above 1 is.
TEST(TextureCli, AnInfiniteDistanceIsStoredAsOneWithoutAClippingWarning) {
  TempFolder dir;
  const fs::path out = dir / "out";
  json j = job(out, json::array({{{"pack", "far"}, {"channels", {{"R", "horizon_distance.004"}}}}}));
  j["bake"][0]["layers"] = {"horizon_distance"};
  j["bake"][0]["directions"] = 8;
  const auto r = run_hfbake(dir.path(), "bake " + write(dir, "j.json", j).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Pixels exr = read(out / "slope.p1.exr", "horizon_distance.004");
  const Pixels png = read(out / "textures" / "slope.p1.far.png");
  ASSERT_EQ(exr.channels, 1);
  ASSERT_GT(png.channels, 0);
  ASSERT_EQ(png.values.size(), exr.values.size() * std::size_t(png.channels));
  std::size_t infinite = 0, finite_above = 0;
  for (std::size_t i = 0; i < exr.values.size(); ++i) {
    const float d = exr.values[i];
    infinite += std::isinf(d);
    finite_above += std::isfinite(d) && d > 1;
    if (std::isinf(d)) {
      EXPECT_EQ(png.values[i * std::size_t(png.channels)], 1.0f) << i;
    }
  }
  ASSERT_GT(infinite, 0u);
  if (finite_above == 0) {
    EXPECT_EQ(r.err.find("clipped"), std::string::npos) << r.err;
  } else {
    char share[32];
    std::snprintf(share, sizeof share, "%.1f %%", 100.0 * double(finite_above) / double(exr.values.size()));
    EXPECT_NE(r.err.find("slope.p1.far.png: " + std::string(share) + " of its values were above 1"),
              std::string::npos)
        << r.err;
  }
}

// A light map whose values exceed 1 is written clipped only with a warning giving the clipped share (the
// EXR's values are the truth); "exposure" scales the values first and, when they fit, nothing is said; an
// "exr" texture keeps them as half floats.
TEST(TextureCli, LightMapAboveOneIsNotClippedSilently) {
  TempFolder dir;
  auto lit = [&](const fs::path& out, const json& texture) {
    json j = job(out, json::array({texture}));
    j["bake"][0]["layers"] = {"direct"};
    j["lights"] = {{{"directional", {{"direction", {0.2, 0.5, 1}}, {"irradiance", 12}}}}};
    return j;
  };
  const fs::path hot = dir / "hot";
  auto r = run_hfbake(
      dir.path(), "bake " + write(dir, "a.json", lit(hot, {{"layers", {"direct"}}, {"bits", 16}})).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Pixels exr = read(hot / "slope.p1.exr", "direct.");
  ASSERT_EQ(exr.channels, 3);
  std::size_t above = 0;
  float largest = 0;
  for (const float v : exr.values) {
    above += v > 1;
    largest = std::max(largest, v);
  }
  ASSERT_GT(above, 0u) << "the light must be strong enough to clip";
  char share[32];
  std::snprintf(share, sizeof share, "%.1f %%", 100.0 * double(above) / double(exr.values.size()));
  EXPECT_NE(r.err.find("warning: textures/slope.p1.direct.png: " + std::string(share) +
                       " of its values were above 1 and clipped to 1"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("\"exposure\": "), std::string::npos) << r.err;

  // A pack of ao (a mask) beside the light: an exposure would scale the ao too, so none is advised.
  json pack = lit(dir / "packed", {{"pack", "orm"}, {"channels", {{"R", "ao"}, {"G", "direct.G"}}}});
  pack["bake"][0]["layers"] = {"ao", "direct"};
  r = run_hfbake(dir.path(), "bake " + write(dir, "p.json", pack).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("clipped to 1"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("\"exposure\": "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("would scale its ao channel too"), std::string::npos) << r.err;
  // Given an exposure, the pack is told that its exposure scaled the ao, not that one would.
  pack["output"]["textures"][0]["exposure"] = 2;
  r = run_hfbake(dir.path(), "bake " + write(dir, "p.json", pack).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("its \"exposure\" of 2 scales its ao channel too"), std::string::npos) << r.err;

  // With an exposure that fits the largest value: the texture is exposure x the EXR, and no warning.
  const double exposure = 0.9 / largest;
  const fs::path fitted = dir / "fitted";
  r = run_hfbake(dir.path(),
                 "bake " + write(dir, "b.json",
                                 lit(fitted, {{"layers", {"direct"}}, {"bits", 16}, {"exposure", exposure}}))
                               .string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("clipped"), std::string::npos) << r.err;
  const Pixels png = read(fitted / "textures" / "slope.p1.direct.png");
  const Pixels exr2 = read(fitted / "slope.p1.exr", "direct.");
  ASSERT_EQ(png.values.size(), exr2.values.size());
  for (std::size_t i = 0; i < png.values.size(); ++i)
    ASSERT_EQ(std::lround(png.values[i] * 65535), std::lround(double(exr2.values[i]) * exposure * 65535))
        << i;

  // An "exr" texture keeps the light above 1: half floats of the EXR's values (within half's rounding,
  // 2^-11 relative), nothing clipped and nothing to warn about.
  const fs::path hdr = dir / "hdr";
  r = run_hfbake(
      dir.path(),
      "bake " + write(dir, "c.json", lit(hdr, {{"layers", {"direct"}}, {"format", "exr"}})).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("clipped"), std::string::npos) << r.err;
  const Pixels tex = read(hdr / "textures" / "slope.p1.direct.exr");
  EXPECT_EQ(tex.type, OIIO::TypeDesc::HALF);
  ASSERT_EQ(tex.channels, 3);
  ASSERT_EQ(tex.values.size(), exr.values.size());
  float tex_largest = 0;
  for (std::size_t i = 0; i < tex.values.size(); ++i) {
    ASSERT_NEAR(tex.values[i], exr.values[i], std::abs(exr.values[i]) * 0x1p-11 + 1e-7) << i;
    tex_largest = std::max(tex_largest, tex.values[i]);
  }
  EXPECT_GT(tex_largest, 1.0f);
  // Light beyond half's range (65504): the texture is float, with the EXR's values, never infinity.
  const fs::path bright = dir / "bright";
  json sun = lit(bright, {{"layers", {"direct"}}, {"format", "exr"}});
  sun["lights"][0]["directional"]["irradiance"] = 1e6;
  r = run_hfbake(dir.path(), "bake " + write(dir, "f.json", sun).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Pixels big = read(bright / "textures" / "slope.p1.direct.exr");
  const Pixels big_exr = read(bright / "slope.p1.exr", "direct.");
  EXPECT_EQ(big.type, OIIO::TypeDesc::FLOAT);
  ASSERT_EQ(big.values.size(), big_exr.values.size());
  EXPECT_GT(*std::max_element(big_exr.values.begin(), big_exr.values.end()), 65504.0f);
  for (std::size_t i = 0; i < big.values.size(); ++i) ASSERT_EQ(big.values[i], big_exr.values[i]) << i;
  // bits and the sRGB curve do not apply to it: refused before baking, at their pointers.
  r = run_hfbake(
      dir.path(),
      "validate " +
          write(dir, "d.json", lit(hdr, {{"layers", {"direct"}}, {"format", "exr"}, {"bits", 16}})).string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/output/textures/0/bits: an \"exr\" texture is half float"), std::string::npos)
      << r.err;
  r = run_hfbake(
      dir.path(),
      "validate " +
          write(dir, "e.json", lit(hdr, {{"layers", {"direct"}}, {"format", "exr"}, {"transfer", "srgb"}}))
              .string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/output/textures/0/transfer: an \"exr\" texture holds linear values"),
            std::string::npos)
      << r.err;
}

// A pack of a signed channel (a bent normal's X) clips its negative half to 0: with a warning giving the
// share, counted here from the EXR; an unsigned pack (ao) says nothing.
// Values a hair above 1 (the brightest 1.0003): the warning says the largest as more than 1 and advises an
// exposure other than the one given, rounded down so that it does bring every value into range.
TEST(TextureCli, TheAdviceForValuesAHairAboveOneIsAnExposureThatFits) {
  TempFolder dir;
  auto lit = [&](const fs::path& out, double irradiance, double exposure) {
    json j = job(out, json::array({{{"layers", {"direct"}}, {"bits", 16}, {"exposure", exposure}}}));
    j["bake"][0]["layers"] = {"direct"};
    j["environment"] = {{"uniform", 0}};  // the light alone: the values scale with its irradiance
    j["lights"] = {{{"directional", {{"direction", {0.2, 0.5, 1}}, {"irradiance", irradiance}}}}};
    return j;
  };
  auto r = run_hfbake(dir.path(), "bake --quiet " + write(dir, "a.json", lit(dir / "a", 1, 1)).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  float largest = 0;
  for (const float v : read(dir / "a" / "slope.p1.exr", "direct.").values) largest = std::max(largest, v);
  ASSERT_GT(largest, 0.0f);
  r = run_hfbake(dir.path(),
                 "bake --quiet " + write(dir, "b.json", lit(dir / "b", 1.0003 / largest, 1)).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::size_t at = r.err.find("\"exposure\": ");
  ASSERT_NE(at, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("(largest 1)"), std::string::npos) << r.err;
  const double advised = std::strtod(r.err.c_str() + at + 12, nullptr);
  EXPECT_LT(advised, 1.0) << r.err;
  r = run_hfbake(dir.path(),
                 "bake --quiet " + write(dir, "c.json", lit(dir / "c", 1.0003 / largest, advised)).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("clipped"), std::string::npos) << r.err;
}

TEST(TextureCli, APackedSignedChannelIsNotClippedSilently) {
  TempFolder dir;
  const fs::path out = dir / "signed";
  json j = job(out, json::array({{{"pack", "bn"}, {"channels", {{"R", "bent_normal.X"}, {"G", "ao"}}}}}),
               {{"kind", "fractal"}, {"size", {33, 33}}});
  j["bake"][0]["layers"] = {"ao", "bent_normal"};
  auto r = run_hfbake(dir.path(), "bake " + write(dir, "a.json", j).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Pixels exr = read(out / "slope.p1.exr", "bent_normal.");
  ASSERT_EQ(exr.channels, 3);
  std::size_t below = 0;
  for (std::size_t t = 0; t < exr.values.size(); t += 3) below += exr.values[t] < -1e-6f;
  ASSERT_GT(below, 0u) << "the field must have bent normals leaning to -x";
  char share[32];
  std::snprintf(share, sizeof share, "%.1f %%", 100.0 * double(below) / double(2 * exr.values.size() / 3));
  EXPECT_NE(r.err.find("warning: textures/slope.p1.bn.png: " + std::string(share) +
                       " of its values were below 0 and clipped to 0"),
            std::string::npos)
      << r.err;
  j["output"]["textures"][0]["channels"] = {{"R", "ao"}};
  j["output"]["dir"] = (dir / "unsigned").string();
  r = run_hfbake(dir.path(), "bake " + write(dir, "b.json", j).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("clipped"), std::string::npos) << r.err;
}

// Previews (display-encoded, for looking at) and textures (data) never share a file name.
TEST(TextureCli, PreviewsAndTexturesHaveDistinctNames) {
  TempFolder dir;
  const fs::path out = dir / "out";
  json j = job(out, json::array({{{"layers", {"ao"}}}}));
  j["output"]["previews"] = true;
  const auto r = run_hfbake(dir.path(), "bake --quiet " + write(dir, "j.json", j).string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "slope.p1.ao.preview.png"));
  EXPECT_TRUE(fs::exists(out / "textures" / "slope.p1.ao.png"));
  EXPECT_FALSE(fs::exists(out / "slope.p1.ao.png"));
}

TEST(TextureCli, BadTextureEntriesAreOneLineErrorsAtTheirPointer) {
  const struct {
    json texture;
    std::string pointer, words;
  } cases[] = {
      {{{"layers", {"ao"}}, {"bits", 16}, {"format", "tga"}}, "/output/textures/0/bits", "TGA holds 8 bits"},
      {{{"layers", {"obscurance"}}}, "/output/textures/0", "no bake entry writes \"obscurance\", which"},
      // A string where a number was meant: named as the layer no output writes.
      {{{"pack", "x"}, {"channels", {{"R", "ao"}, {"G", "1"}}}}, "/output/textures/0", "writes \"1\", which"},
      {{{"layers", {"bent_normal"}}, {"space", "world"}, {"y", "opengl"}},
       "/output/textures/0/y",
       "world space"},
      {{{"layers", {"ao"}}, {"y", "opengl"}}, "/output/textures/0/y", "bent_normal"},
      {{{"layers", {"ao"}}, {"methods", {"lsao"}}}, "/output/textures/0/methods/0", "no bake output"},
      {{{"pack", "x"}, {"channels", {{"R", "bent_normal.Q"}}}},
       "/output/textures/0/channels/R",
       "has no channel"},
      {{{"layers", {"ao"}}, {"bits", 12}}, "/output/textures/0/bits", ""},
      {{{"layers", {"normal"}}, {"exposure", 2}}, "/output/textures/0/exposure", "not to normal maps"},
      {{{"layers", {"ao"}}, {"exposure", 0}}, "/output/textures/0/exposure", ""},
      {{{"layers", {"ao"}}, {"pack", "x"}}, "/output/textures/0", ""},
  };
  for (const auto& c : cases) {
    TempFolder dir;
    const fs::path out = dir / "out";
    const fs::path f = write(dir, "j.json", job(out, json::array({c.texture})));
    for (const char* cmd : {"validate ", "bake --quiet "}) {
      const auto r = run_hfbake(dir.path(), cmd + f.string());
      EXPECT_EQ(r.exit_code, 2) << c.texture.dump() << r.err;
      const auto lines = r.error_lines();
      ASSERT_EQ(lines.size(), 1u) << c.texture.dump() << "\n" << r.err;
      EXPECT_NE(lines[0].find(f.string() + ": " + c.pointer), std::string::npos) << lines[0];
      EXPECT_NE(lines[0].find(c.words), std::string::npos) << lines[0];
    }
    EXPECT_FALSE(fs::exists(out / "textures")) << c.texture.dump();
  }
}

// A pack of constants alone reads no layer: it is every bake entry's (by default), not also the height
// field's, whose output is its normal.
TEST(TextureCli, APackOfConstantsIsTheBakeEntriesAlone) {
  TempFolder dir;
  const fs::path out = dir / "out";
  const auto r = run_hfbake(
      dir.path(),
      "bake --quiet " + write(dir, "j.json",
                              job(out, json::array({{{"pack", "mask"}, {"channels", {{"R", 0}, {"G", 1}}}}})))
                            .string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(out / "textures"))
    if (e.path().filename().string()[0] != '.') files.push_back(e.path().filename().string());  // the record
  EXPECT_EQ(files, std::vector<std::string>{"slope.p1.mask.png"});
}

TEST(TextureCli, TwoEntriesWritingOneFileAreRefused) {
  TempFolder dir;
  const fs::path f = write(
      dir, "j.json",
      job(dir / "out", json::array({{{"layers", {"ao"}}}, {{"layers", {"ao", "vsky"}}, {"bits", 16}}})));
  const auto r = run_hfbake(dir.path(), "validate " + f.string());
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.err.find("/output/textures/1: writes textures/slope.p1.ao.png, which /output/textures/0"),
            std::string::npos)
      << r.err;
}

}  // namespace
