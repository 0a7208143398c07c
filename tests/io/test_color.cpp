// OpenColorIO conversions with the built-in config, against the published transfer functions.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>

#include "core/error.hpp"
#include "io/color.hpp"

namespace hfbake {
namespace {

// IEC 61966-2-1 sRGB decode, written out here as the independent truth.
double srgb_to_linear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

TEST(Color, BuiltInConfigIsActiveWithoutOcio) {
  EXPECT_EQ(ocio_config_description(), "built-in");
}

TEST(Color, SrgbHalfIsPoint214) {
  std::vector<float> px = {0.5f, 0.5f, 0.5f};
  convert_to_linear(px, 3, "sRGB", {});
  EXPECT_NEAR(px[0], 0.214, 0.0005);
  EXPECT_NEAR(px[0], srgb_to_linear(0.5), 1e-5);
  // The linear toe and the ends, through every alias.
  for (const char* name : {"srgb", "sRGB - Texture", "srgb_texture", "srgb_tx"}) {
    std::vector<float> q = {0.0f, 0.02f, 1.0f, 0.8f, 0.3f, 0.04f};
    convert_to_linear(q, 3, name, {});
    const double in[6] = {0.0, 0.02, 1.0, 0.8, 0.3, 0.04};
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(q[i], srgb_to_linear(in[i]), 2e-5) << name << " " << in[i];
  }
  // Grey images (1 channel) and RGBA (alpha untouched).
  std::vector<float> grey = {0.5f, 0.25f};
  convert_to_linear(grey, 1, "sRGB", {});
  EXPECT_NEAR(grey[0], srgb_to_linear(0.5), 1e-5);
  EXPECT_NEAR(grey[1], srgb_to_linear(0.25), 1e-5);
  std::vector<float> rgba = {0.5f, 0.5f, 0.5f, 0.5f};
  convert_to_linear(rgba, 4, "sRGB", {});
  EXPECT_NEAR(rgba[2], srgb_to_linear(0.5), 1e-5);
  EXPECT_FLOAT_EQ(rgba[3], 0.5f);
}

TEST(Color, LinearRawAndOtherSpaces) {
  for (const char* name : {"linear", "scene_linear", "Linear Rec.709 (sRGB)", "raw", "data"}) {
    std::vector<float> px = {0.5f, 2.0f, -0.1f};
    convert_to_linear(px, 3, name, {});
    EXPECT_FLOAT_EQ(px[0], 0.5f) << name;
    EXPECT_FLOAT_EQ(px[1], 2.0f) << name;
    EXPECT_FLOAT_EQ(px[2], -0.1f) << name;
  }
  std::vector<float> g = {0.5f, 0.5f, 0.5f};
  convert_to_linear(g, 3, "gamma22", {});
  EXPECT_NEAR(g[0], std::pow(0.5, 2.2), 1e-5);
  // Equal-energy grey stays grey through AP1 -> Rec.709 (both D60/D65-adapted white maps to white)
  // and a pure AP1 red goes out of the Rec.709 gamut (negative green/blue).
  std::vector<float> w = {1.0f, 1.0f, 1.0f, 1.0f, 0.0f, 0.0f};
  convert_to_linear(w, 3, "ACEScg", {});
  EXPECT_NEAR(w[0], 1.0, 1e-3);
  EXPECT_NEAR(w[1], 1.0, 1e-3);
  EXPECT_NEAR(w[2], 1.0, 1e-3);
  EXPECT_GT(w[3], 1.0f);
  EXPECT_LT(w[4], 0.0f);
}

TEST(Color, DisplayViewEncodesSrgb) {
  std::vector<float> px = {float(srgb_to_linear(0.5)), 0.0f, 1.0f};
  convert_to_display(px, "", "", {});  // defaults: display sRGB, view Standard
  EXPECT_NEAR(px[0], 0.5, 1e-4);
  EXPECT_NEAR(px[1], 0.0, 1e-6);
  EXPECT_NEAR(px[2], 1.0, 1e-5);
  std::vector<float> raw = {0.25f, 0.25f, 0.25f};
  convert_to_display(raw, "sRGB", "Raw", {});
  EXPECT_FLOAT_EQ(raw[0], 0.25f);
}

TEST(Color, UnknownNamesAreInputErrors) {
  std::vector<float> px = {0.5f, 0.5f, 0.5f};
  try {
    convert_to_linear(px, 3, "no such space", {"job.json", "/environment/colorspace"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line().rfind(
                  "job.json: /environment/colorspace: unknown OpenColorIO colour space \"no such space\"", 0),
              0u)
        << e.line();
  }
  EXPECT_THROW(convert_to_display(px, "nope", "", {"job.json", "/output/preview_display"}), InputError);
  // The checks `hfbake validate` uses, with the pointer of the offending key.
  EXPECT_NO_THROW(check_colorspace("srgb", {}));
  EXPECT_NO_THROW(check_display_view("", "", {}, {}));
  EXPECT_NO_THROW(check_display_view("sRGB", "Raw", {}, {}));
  try {
    check_display_view("sRGB", "Filmic", {"j.json", "/output/preview_display"},
                       {"j.json", "/output/preview_view"});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(
        e.line(),
        "j.json: /output/preview_view: unknown OpenColorIO view \"Filmic\" of display \"sRGB\" (it has: "
        "Standard, Raw)");
  }
  try {
    check_display_view("P3", "", {"j.json", "/output/preview_display"}, {"j.json", "/output/preview_view"});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), "j.json: /output/preview_display: unknown OpenColorIO display \"P3\" (it has: sRGB)");
  }
  EXPECT_THROW(convert_to_display(px, "", "nope", {"job.json", "/output/preview_view"}), InputError);
}

TEST(Color, BuiltInConfigTextIsAValidConfig) {
  // The compiled-in text is the shipped file, byte for byte; it names the documented spaces and display.
  const std::string& text = builtin_ocio_config();
  std::ifstream in(HFBAKE_SOURCE_DIR "/baker/io/ocio/hfbake.ocio", std::ios::binary);
  ASSERT_TRUE(in);
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, file);
  EXPECT_NE(text.find("name: sRGB - Texture"), std::string::npos);
  EXPECT_NE(text.find("sRGB:"), std::string::npos);
}

}  // namespace
}  // namespace hfbake
