// Engine-ready textures (io/texture_output): the quantised values against the formulas computed
// here (round(v * 255), round(v * 65535), 0.5 + 0.5 n, the sRGB curve), read back from the files with
// OpenImageIO; normal-map conventions on closed-form directions; edge padding.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/vec.hpp"
#include "io/texture_output.hpp"
#include "temp_folder.hpp"

namespace {
using namespace hfbake;
using hfbake::test::TempFolder;

struct Image {
  int width = 0, height = 0, channels = 0;
  std::string format;
  OIIO::TypeDesc type;
  std::vector<std::uint16_t> values;  // as stored (8-bit files read as 0..255)
};

Image read_back(const std::filesystem::path& file) {
  Image im;
  auto in = OIIO::ImageInput::open(file.string());
  if (!in) return im;
  const OIIO::ImageSpec& spec = in->spec();
  im.width = spec.width;
  im.height = spec.height;
  im.channels = spec.nchannels;
  im.type = spec.format;
  im.format = in->format_name();
  im.values.resize(std::size_t(im.width) * im.height * im.channels);
  if (spec.format == OIIO::TypeDesc::UINT8) {
    std::vector<std::uint8_t> b(im.values.size());
    in->read_image(0, 0, 0, im.channels, OIIO::TypeDesc::UINT8, b.data());
    im.values.assign(b.begin(), b.end());
  } else {
    in->read_image(0, 0, 0, im.channels, OIIO::TypeDesc::UINT16, im.values.data());
  }
  return im;
}

LayerSet ao_layer(int w, int h) {
  LayerSet s;
  s.width = w;
  s.height = h;
  Layer& ao = s.add("ao", mono_channels());
  std::uint64_t x = 99;
  for (float& v : ao.data) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    v = float((x >> 40) % 100001) / 100000.0f;  // [0, 1], ends included
  }
  ao.data[0] = 0;
  ao.data[1] = 1;
  ao.data[2] = 1.5f;  // clamped
  ao.data[3] = -0.25f;
  ao.data[4] = std::nanf("");
  ao.data[5] = std::numeric_limits<float>::infinity();  // a horizon_distance with no caster: as far as any
  ao.data[6] = -std::numeric_limits<float>::infinity();
  return s;
}

TEST(Texture, EightAndSixteenBitGreyEqualRoundedValues) {
  TempFolder dir;
  const LayerSet s = ao_layer(37, 23);
  for (const char* ext : {"png", "tif", "tga"})
    for (int bits : {8, 16}) {
      if (bits == 16 && std::string(ext) == "tga") continue;
      TextureSpec spec;
      spec.channels = {{"ao", 0, 0}};
      spec.bits = bits;
      const auto file = dir / (std::string("ao") + std::to_string(bits) + "." + ext);
      write_texture(file, s, spec);
      const Image im = read_back(file);
      ASSERT_EQ(im.width, 37);
      ASSERT_EQ(im.height, 23);
      ASSERT_EQ(im.channels, 1) << ext << ": greyscale";
      EXPECT_EQ(im.type, bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16) << ext;
      const double top = bits == 8 ? 255 : 65535;
      const std::vector<float>& ao = s.find("ao")->data;
      for (std::size_t i = 0; i < ao.size(); ++i) {
        const double v = std::isnan(ao[i]) ? 0 : std::min(1.0, std::max(0.0, double(ao[i])));
        ASSERT_EQ(im.values[i], std::uint16_t(std::round(v * top))) << ext << bits << " texel " << i;
      }
    }
}

// An exr texture holds the values as they are, in half: infinities stay infinities, NaN becomes 0.
TEST(Texture, ExrKeepsInfinitiesAndZeroesNaN) {
  TempFolder dir;
  const LayerSet s = ao_layer(37, 23);
  TextureSpec spec;
  spec.channels = {{"ao", 0, 0}};
  const auto file = dir / "ao.exr";
  write_texture(file, s, spec);
  auto in = OIIO::ImageInput::open(file.string());
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().format, OIIO::TypeDesc::HALF);
  std::vector<float> v(37 * 23);
  ASSERT_TRUE(in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, v.data()));
  EXPECT_EQ(v[4], 0.0f);
  EXPECT_EQ(v[5], std::numeric_limits<float>::infinity());
  EXPECT_EQ(v[6], -std::numeric_limits<float>::infinity());
  EXPECT_EQ(v[2], 1.5f);
}

TEST(Texture, LinearFilesCarryNoColourCurveAndSrgbIsTheStandardCurve) {
  TempFolder dir;
  LayerSet s;
  s.width = 4;
  s.height = 1;
  s.add("direct", rgb_channels()).data = {0.0f,  0.5f,  1.0f,  0.002f, 0.2f, 0.8f,
                                          0.25f, 0.75f, 0.04f, 0.5f,   0.5f, 0.5f};
  TextureSpec spec;
  spec.channels = {{"direct", 0, 0}, {"direct", 1, 0}, {"direct", 2, 0}};
  spec.transfer = Transfer::srgb;
  write_texture(dir / "d.png", s, spec);
  const Image im = read_back(dir / "d.png");
  ASSERT_EQ(im.channels, 3);
  for (std::size_t i = 0; i < 12; ++i) {
    const double v = s.find("direct")->data[i];
    const double e = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;  // IEC 61966-2-1
    EXPECT_EQ(im.values[i], std::round(e * 255)) << i;
  }
  EXPECT_EQ(im.values[1], 188);  // 0.5 -> 188 in sRGB (128 linear)
  auto in = OIIO::ImageInput::open((dir / "d.png").string());
  EXPECT_EQ(in->spec().get_string_attribute("oiio:ColorSpace"), "sRGB");
}

// A direction layer of a few closed-form directions: flat up, and tilted towards +x, +y.
LayerSet bent(const std::vector<Vec3>& dirs) {
  LayerSet s;
  s.width = int(dirs.size());
  s.height = 1;
  Layer& b = s.add("bent_normal", xyz_channels());
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    const Vec3 d = normalize(dirs[i]);
    b.data[3 * i] = float(d.x);
    b.data[3 * i + 1] = float(d.y);
    b.data[3 * i + 2] = float(d.z);
  }
  return s;
}

TEST(Texture, NormalMapConventions) {
  TempFolder dir;
  const LayerSet s = bent({{0, 0, 1}, {0.5, 0, 1}, {0, 0.5, 1}});
  const float ys = s.find("bent_normal")->data[7], zs = s.find("bent_normal")->data[8];  // (0, 0.5, 1) / |.|
  auto encode = [](double n, double top) { return std::uint16_t(std::round((0.5 + 0.5 * n) * top)); };
  for (int bits : {8, 16}) {
    const double top = bits == 8 ? 255 : 65535;
    for (NormalSpace space : {NormalSpace::tangent, NormalSpace::world})
      for (GreenAxis g : {GreenAxis::opengl, GreenAxis::directx}) {
        if (space == NormalSpace::world && g == GreenAxis::opengl) continue;  // world has one frame
        TextureSpec spec;
        spec.channels = {{"bent_normal", 0, 0}, {"bent_normal", 1, 0}, {"bent_normal", 2, 0}};
        spec.normal_map = true;
        spec.space = space;
        spec.green = g;
        spec.bits = bits;
        write_texture(dir / "n.png", s, spec);
        const Image im = read_back(dir / "n.png");
        ASSERT_EQ(im.channels, 3);
        // Flat: (0.5, 0.5, 1.0) in every convention.
        EXPECT_EQ(im.values[0], encode(0, top));
        EXPECT_EQ(im.values[1], encode(0, top));
        EXPECT_EQ(im.values[2], top);
        // Tilted towards +x: red above the middle in all of them.
        EXPECT_GT(im.values[3], encode(0, top));
        EXPECT_EQ(im.values[4], encode(0, top));
        // Tilted towards +y (image down): green below the middle in OpenGL's (G = image up), above in
        // DirectX's and in world space (G = +y).
        const bool up = space == NormalSpace::tangent && g == GreenAxis::opengl;
        EXPECT_EQ(im.values[7], encode(up ? -ys : ys, top)) << bits;
        EXPECT_EQ(im.values[8], encode(zs, top));
      }
  }
}

TEST(Texture, PaddingRepeatsTheEdgeOrContinuesTheTile) {
  LayerSet s;
  s.width = 3;
  s.height = 2;
  s.add("ao", mono_channels()).data = {0.0f, 0.2f, 0.4f, 0.6f, 0.8f, 1.0f};
  TextureSpec spec;
  spec.channels = {{"ao", 0, 0}};
  spec.padding = 2;
  const TexturePixels clamp = texture_pixels(s, spec);
  ASSERT_EQ(clamp.width, 7);
  ASSERT_EQ(clamp.height, 6);
  auto at = [](const TexturePixels& p, int x, int y) { return p.values[std::size_t(y) * p.width + x]; };
  EXPECT_EQ(at(clamp, 0, 0), 0);                      // corner: texel (0, 0)
  EXPECT_EQ(at(clamp, 6, 5), 255);                    // corner: texel (2, 1)
  EXPECT_EQ(at(clamp, 3, 2), std::round(0.2 * 255));  // texel (1, 0)
  EXPECT_EQ(at(clamp, 3, 0), std::round(0.2 * 255));  // above it: the edge repeated
  spec.repeat = true;
  const TexturePixels tile = texture_pixels(s, spec);
  EXPECT_EQ(at(tile, 0, 2), std::round(0.2 * 255));  // two left of texel (0, 0): texel (1, 0)
  EXPECT_EQ(at(tile, 3, 1), std::round(0.8 * 255));  // one above texel (1, 0): texel (1, 1)
  EXPECT_EQ(at(tile, 6, 5), std::round(0.8 * 255));  // texel (4, 3) = (1, 1)
}

TEST(Texture, PacksTakeChannelsAndConstants) {
  TempFolder dir;
  LayerSet s = ao_layer(5, 4);
  s.add("vsky", mono_channels()).data.assign(20, 0.25f);
  TextureSpec spec;
  spec.channels = {{"ao", 0, 0}, {"vsky", 0, 0}, {"", 0, 0}, {"", 0, 1.0f}};
  write_texture(dir / "p.tga", s, spec);
  const Image im = read_back(dir / "p.tga");
  ASSERT_EQ(im.channels, 4);
  for (std::size_t i = 7; i < 20; ++i) {  // the values in [0, 1]
    EXPECT_EQ(im.values[4 * i], std::round(s.find("ao")->data[i] * 255));
    EXPECT_EQ(im.values[4 * i + 1], 64);  // round(0.25 * 255)
    EXPECT_EQ(im.values[4 * i + 2], 0);
    EXPECT_EQ(im.values[4 * i + 3], 255);
  }
}

}  // namespace
