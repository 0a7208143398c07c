// The environment tables of docs/environment.md end to end (the hfbake binary): a bright patch a few degrees
// above the horizon in the image region docs/environment.md says looks north on a north-up raster (world -y)
// lights the 20-degree slope that faces north and not the one that faces south (whose plane hides everything
// below 20 degrees to the north), for a lat-long, a cube map and a cross. The truth is geometry: only the
// slope facing the patch can see it.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "../cli/run_hfbake.hpp"
#include "../io/image_fixtures.hpp"
#include "../io/temp_folder.hpp"

namespace {
namespace fs = std::filesystem;
using hfbake::cli_test::run_hfbake;
using hfbake::test::TempFolder;
using hfbake::test::write_test_image;
using nlohmann::json;

// Black RGB image with a block of radiance 200 at columns [x0, x1), rows [y0, y1).
std::vector<float> patch(int w, int h, int x0, int x1, int y0, int y1) {
  std::vector<float> px(std::size_t(w) * h * 3, 0.0f);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      for (int c = 0; c < 3; ++c) px[(std::size_t(y) * w + x) * 3 + c] = 200;
  return px;
}

// The centre texel's direct light (green) of a 33 x 33 slope of 20 degrees facing compass `facing` on a
// north-up field: aspect (hfbake phi) = compass - 90.
double direct_on_slope(const TempFolder& dir, const json& environment, double facing) {
  const std::string name = facing < 90 ? "north" : "south";
  const json job = {
      {"version", 1},
      {"name", name},
      {"height",
       {{"procedural",
         {{"kind", "slope"}, {"size", {33, 33}}, {"angle_deg", 20}, {"aspect_deg", facing - 90}}}}},
      {"environment", environment},
      {"bake", {{{"method", "p1"}, {"directions", 32}, {"layers", {"direct"}}}}},
      {"output", {{"dir", (dir / "out").string()}, {"pixel_type", "float"}}}};
  const fs::path f = dir / (name + ".json");
  std::ofstream(f) << job.dump();
  const auto r = run_hfbake(dir.path(), "bake --quiet " + f.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  auto in = OIIO::ImageInput::open((dir / "out" / (name + ".p1.exr")).string());
  if (!in) return -1;
  const OIIO::ImageSpec& spec = in->spec();
  int g = -1;
  for (int c = 0; c < spec.nchannels; ++c)
    if (spec.channelnames[c] == "direct.G") g = c;
  std::vector<float> px(std::size_t(spec.width) * spec.height);
  in->read_image(0, 0, g, g + 1, OIIO::TypeDesc::FLOAT, px.data());
  return px[16 * 33 + 16];
}

void expect_lights_north(const TempFolder& dir, const json& environment, const char* what) {
  const double north = direct_on_slope(dir, environment, 0), south = direct_on_slope(dir, environment, 180);
  EXPECT_GT(north, 0.5) << what;           // the patch: 200 x about 0.008 sr x cos
  EXPECT_LT(south, 1e-2 * north) << what;  // below the south-facing plane's horizon to the north
}

TEST(EnvCompass, LatLongThreeQuarterColumnIsNorth) {
  TempFolder dir;
  // 64 x 32: columns 46..49 straddle 3/4 of the width (phi = -90 deg, world -y); rows 13..14 span
  // elevations 5.6 to 16.9 degrees.
  write_test_image(dir / "sky.exr", 64, 32, 3, patch(64, 32, 46, 50, 13, 15));
  expect_lights_north(dir, {{"latlong", "sky.exr"}}, "latlong");
}

TEST(EnvCompass, CubeSlotMinusXIsNorth) {
  TempFolder dir;
  const char* names[6] = {"px.exr", "nx.exr", "py.exr", "ny.exr", "pz.exr", "nz.exr"};
  json files = json::array();
  for (int f = 0; f < 6; ++f) {
    // Slot 1 (OpenEXR -x) looks at world -y, image up = +z: rows 5..7 of 16 are 4 to 17 degrees up.
    write_test_image(dir / names[f], 16, 16, 3,
                     f == 1 ? patch(16, 16, 6, 10, 5, 8) : patch(16, 16, 0, 0, 0, 0));
    files.push_back(names[f]);
  }
  expect_lights_north(dir, {{"cubemap", files}}, "cubemap");
}

TEST(EnvCompass, CrossRightCellIsNorth) {
  TempFolder dir;
  // Horizontal cross 64 x 48, cells of 16: the right cell (column 2, row 1) looks at world -y.
  write_test_image(dir / "cross.exr", 64, 48, 3, patch(64, 48, 32 + 6, 32 + 10, 16 + 6, 16 + 9));
  expect_lights_north(dir, {{"cross", "cross.exr"}}, "cross");
}

}  // namespace
