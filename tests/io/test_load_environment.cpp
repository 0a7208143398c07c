// Loading environments from job JSON: the orientation pin (a single bright patch in a lat-long, a cube
// face and a cross lands at the documented world direction), colour, intensity, rotation, and errors.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "image_fixtures.hpp"
#include "io/load_environment.hpp"
#include "temp_folder.hpp"

namespace hfbake {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;
using test::TempFolder;
using test::write_test_image;

const EnvironmentLoadOptions kOpts{"job.json", "/environment", 1024};

// Radiance-weighted mean direction of an environment (where its light comes from).
Vec3 light_centroid(const Environment& env) {
  const auto& l = env.levels[0];
  Vec3 sum;
  for (int r = 0; r < l.height; ++r)
    for (int c = 0; c < l.width; ++c)
      sum +=
          env.texel_direction(c, r) * (l.texels[std::size_t(r) * l.width + c].r * env.texel_solid_angle(r));
  return normalize(sum);
}

Vec3 from_angles_deg(double theta, double phi) {
  const double t = theta * kPi / 180, p = phi * kPi / 180;
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

double angle_deg(Vec3 a, Vec3 b) {
  return std::acos(std::clamp(dot(normalize(a), normalize(b)), -1.0, 1.0)) * 180 / kPi;
}

std::string error_line(const json& j, const fs::path& base) {
  try {
    load_environment(j, base, kOpts);
  } catch (const InputError& e) {
    return e.line();
  }
  return "(no InputError)";
}

// A 64 x 32 lat-long, black with a 2 x 2 patch centered on image position (16, 11): a quarter of the
// width from the left edge (azimuth +90 deg: world +y) and 11/32 of the height down (theta 61.875 deg).
void write_latlong_patch(const fs::path& file) {
  std::vector<float> px(64 * 32 * 3, 0.0f);
  for (int y = 10; y < 12; ++y)
    for (int x = 15; x < 17; ++x)
      for (int c = 0; c < 3; ++c) px[(std::size_t(y) * 64 + x) * 3 + c] = 100;
  write_test_image(file, 64, 32, 3, px);
}

TEST(LoadEnvironment, LatLongPatchLandsAtTheDocumentedDirection) {
  TempFolder dir;
  write_latlong_patch(dir / "sky.exr");
  const EnvironmentLighting lit = load_environment(json{{"latlong", "sky.exr"}}, dir.path(), kOpts);
  const Environment& env = lit.environment;
  EXPECT_FALSE(env.uniform);
  EXPECT_TRUE(lit.lights.empty());
  const Vec3 want = from_angles_deg(61.875, 90);  // the patch: +y, 28 deg above the horizon
  EXPECT_LT(angle_deg(light_centroid(env), want), 0.5);
  EXPECT_NEAR(env.radiance(want).r, 100, 1e-3);
  EXPECT_EQ(env.radiance(-want).r, 0);
  EXPECT_EQ(env.radiance(from_angles_deg(61.875, -90)).r, 0);       // not mirrored
  EXPECT_EQ(env.radiance(from_angles_deg(180 - 61.875, 90)).r, 0);  // not upside down
  // The power is conserved by the resampling: 4 texels of 100.
  const double patch = 100 * 2 * (std::cos(kPi * 10 / 32) - std::cos(kPi * 12 / 32)) * 2 * kPi / 64;
  EXPECT_NEAR(integrate_sphere(env).g, patch, 1e-4 * patch);
}

TEST(LoadEnvironment, RotationIntensityAndUniform) {
  TempFolder dir;
  write_latlong_patch(dir / "sky.exr");
  const json j = {{"latlong", "sky.exr"}, {"rotation_deg", 90}, {"intensity", 2}};
  const Environment env = load_environment(j, dir.path(), kOpts).environment;
  // Turned 90 deg about +z (counter-clockwise from above): +y -> -x.
  EXPECT_LT(angle_deg(light_centroid(env), from_angles_deg(61.875, 180)), 0.5);
  EXPECT_NEAR(env.radiance(from_angles_deg(61.875, 180)).b, 200, 1e-2);

  const Environment u =
      load_environment(json{{"uniform", {0.1, 0.2, 0.3}}, {"intensity", 10}}, dir.path(), kOpts).environment;
  EXPECT_TRUE(u.uniform);
  EXPECT_FLOAT_EQ(u.radiance({0, 0, 1}).b, 3.0f);
  const Environment grey = load_environment(json{{"uniform", 0.5}}, dir.path(), kOpts).environment;
  EXPECT_FLOAT_EQ(grey.radiance({1, 0, 0}).g, 0.5f);
}

TEST(LoadEnvironment, SkyWithSun) {
  const json j = json::parse(R"({"sky": {"zenith": 0.5, "horizon": [1, 1, 1], "ground": 0.1,
      "sun": {"elevation_deg": 30, "azimuth_deg": 90, "angular_diameter_deg": 1, "irradiance": 5}},
      "intensity": 2, "rotation_deg": 90})");
  const EnvironmentLighting lit = load_environment(j, ".", kOpts);
  ASSERT_EQ(lit.lights.size(), 1u);
  const Vec3 d = lit.lights[0].direction;  // azimuth 90 + 90
  EXPECT_NEAR(d.x, -std::cos(kPi / 6), 1e-12);
  EXPECT_NEAR(d.y, 0, 1e-12);
  EXPECT_NEAR(d.z, 0.5, 1e-12);
  EXPECT_FLOAT_EQ(lit.lights[0].irradiance.g, 10.0f);
  EXPECT_NEAR(lit.lights[0].angular_diameter, kPi / 180, 1e-12);
  EXPECT_NEAR(lit.environment.radiance({0, 0, -1}).r, 0.2f, 1e-6);
  // The sun is a light, not texels: the brightest sky texel is the horizon colour, 2 x 1.
  float brightest = 0;
  for (const Rgb& t : lit.environment.levels[0].texels) brightest = std::max(brightest, t.r);
  EXPECT_LE(brightest, 2.0f);
}

// Six 16 x 16 faces in OpenEXR order; face `lit` has a 4 x 4 patch at x in [10, 14), y in [2, 6)
// (center x = 12, y = 4: a = +0.5 right, b = +0.5 up).
std::vector<std::vector<float>> cube_faces(int lit) {
  std::vector<std::vector<float>> faces(6, std::vector<float>(16 * 16 * 3, 0.0f));
  for (int y = 2; y < 6; ++y)
    for (int x = 10; x < 14; ++x)
      for (int c = 0; c < 3; ++c) faces[lit][(std::size_t(y) * 16 + x) * 3 + c] = 50;
  return faces;
}

json write_cube(const TempFolder& dir, const std::vector<std::vector<float>>& faces) {
  json files = json::array();
  const char* names[6] = {"px.exr", "nx.exr", "py.exr", "ny.exr", "pz.exr", "nz.exr"};
  for (int f = 0; f < 6; ++f) {
    write_test_image(dir / names[f], 16, 16, 3, faces[f]);
    files.push_back(names[f]);
  }
  return json{{"cubemap", files}};
}

TEST(LoadEnvironment, CubeFacePatchLandsAtTheDocumentedDirection) {
  // docs/environment.md's table, per face: the world direction it looks at, image right, image up. The patch
  // covers a, b in [0.25, 0.75] (right, up) of the face; its light centroid is the solid-angle-weighted mean
  // of normalize(center + a right + b up) over that square, integrated here on a fine grid.
  const struct {
    int face;
    Vec3 center, right, up;
  } cases[] = {{0, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}},    // OpenEXR +x
               {4, {1, 0, 0}, {0, -1, 0}, {0, 0, 1}},   // OpenEXR +z
               {2, {0, 0, 1}, {0, 1, 0}, {1, 0, 0}},    // OpenEXR +y
               {3, {0, 0, -1}, {0, 1, 0}, {-1, 0, 0}},  // OpenEXR -y
               {1, {0, -1, 0}, {-1, 0, 0}, {0, 0, 1}},  // OpenEXR -x
               {5, {-1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};  // OpenEXR -z
  for (const auto& c : cases) {
    TempFolder dir;
    const Environment env =
        load_environment(write_cube(dir, cube_faces(c.face)), dir.path(), kOpts).environment;
    EXPECT_EQ(env.levels[0].height, 32);  // twice the face size
    Vec3 sum;
    for (int j = 0; j < 200; ++j)
      for (int i = 0; i < 200; ++i) {
        const double a = 0.25 + 0.5 * (i + 0.5) / 200, b = 0.25 + 0.5 * (j + 0.5) / 200,
                     q = 1 + a * a + b * b;
        sum += normalize(c.center + a * c.right + b * c.up) * (1 / (q * std::sqrt(q)));
      }
    EXPECT_LT(angle_deg(light_centroid(env), sum), 0.3) << "face " << c.face;
    EXPECT_NEAR(env.radiance(normalize(c.center + 0.5 * c.right + 0.5 * c.up)).r, 50, 0.5)
        << "face " << c.face;
  }
}

// Copies face f (16 x 16 RGB) into cell (col, row) of a cross image, optionally turned 180 degrees.
void blit(std::vector<float>& cross, int cross_w, const std::vector<float>& face, int col, int row,
          bool turn) {
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const int sx = turn ? 15 - x : x, sy = turn ? 15 - y : y;
      for (int c = 0; c < 3; ++c)
        cross[(std::size_t(row * 16 + y) * cross_w + col * 16 + x) * 3 + c] =
            face[(std::size_t(sy) * 16 + sx) * 3 + c];
    }
}

TEST(LoadEnvironment, CrossesMatchTheCubeMap) {
  for (int lit : {0, 2, 3, 5}) {
    TempFolder dir;
    const auto faces = cube_faces(lit);
    const Environment cube = load_environment(write_cube(dir, faces), dir.path(), kOpts).environment;
    // The documented layouts: sides are OpenEXR +x (left), +z (front), -x (right), -z (back) as they
    // are; top/bottom are +y/-y turned 180 deg; the vertical cross stores the back turned 180 deg.
    std::vector<float> h(64 * 48 * 3, 0.0f), v(48 * 64 * 3, 0.0f);
    blit(h, 64, faces[0], 0, 1, false);
    blit(h, 64, faces[4], 1, 1, false);
    blit(h, 64, faces[1], 2, 1, false);
    blit(h, 64, faces[5], 3, 1, false);
    blit(h, 64, faces[2], 1, 0, true);
    blit(h, 64, faces[3], 1, 2, true);
    blit(v, 48, faces[0], 0, 1, false);
    blit(v, 48, faces[4], 1, 1, false);
    blit(v, 48, faces[1], 2, 1, false);
    blit(v, 48, faces[2], 1, 0, true);
    blit(v, 48, faces[3], 1, 2, true);
    blit(v, 48, faces[5], 1, 3, true);
    write_test_image(dir / "h.exr", 64, 48, 3, h);
    write_test_image(dir / "v.exr", 48, 64, 3, v);
    for (const char* name : {"h.exr", "v.exr"}) {
      const Environment cross = load_environment(json{{"cross", name}}, dir.path(), kOpts).environment;
      ASSERT_EQ(cross.levels[0].texels.size(), cube.levels[0].texels.size());
      double max_diff = 0;
      for (std::size_t i = 0; i < cube.levels[0].texels.size(); ++i)
        max_diff =
            std::max(max_diff, double(std::abs(cross.levels[0].texels[i].r - cube.levels[0].texels[i].r)));
      EXPECT_LT(max_diff, 1e-4) << name << " face " << lit;
    }
  }
}

TEST(LoadEnvironment, EightBitImagesDefaultToSrgb) {
  TempFolder dir;
  write_test_image(dir / "grey.png", 16, 8, 3, std::vector<float>(16 * 8 * 3, 128 / 255.f),
                   OIIO::TypeDesc::UINT8);
  const Environment s = load_environment(json{{"latlong", "grey.png"}}, dir.path(), kOpts).environment;
  EXPECT_NEAR(s.radiance({0, 1, 0}).r, std::pow((128 / 255.0 + 0.055) / 1.055, 2.4), 1e-5);
  const Environment l =
      load_environment(json{{"latlong", "grey.png"}, {"colorspace", "linear"}}, dir.path(), kOpts)
          .environment;
  EXPECT_NEAR(l.radiance({0, 1, 0}).r, 128 / 255.0, 1e-6);
}

TEST(LoadEnvironment, BadInputIsOneLineAtTheRightPointer) {
  TempFolder dir;
  write_test_image(dir / "wide.exr", 30, 20, 3, std::vector<float>(30 * 20 * 3, 1.0f));
  EXPECT_EQ(error_line(json{{"latlong", "wide.exr"}}, dir.path()),
            "job.json: /environment/latlong: " + (dir / "wide.exr").string() +
                ": a lat-long needs a 2:1 image, this one is 30x20");
  EXPECT_EQ(error_line(json{{"cross", "wide.exr"}}, dir.path()),
            "job.json: /environment/cross: " + (dir / "wide.exr").string() +
                ": a cube cross must be 4:3 (horizontal) or 3:4 (vertical), this one is 30x20");
  json cube = write_cube(dir, cube_faces(0));
  cube["cubemap"][3] = "missing.exr";
  EXPECT_EQ(error_line(cube, dir.path()),
            "job.json: /environment/cubemap/3: " + (dir / "missing.exr").string() + ": no such file");
  write_test_image(dir / "small.exr", 8, 8, 3, std::vector<float>(8 * 8 * 3, 1.0f));
  cube["cubemap"][3] = "small.exr";
  EXPECT_EQ(error_line(cube, dir.path()),
            "job.json: /environment/cubemap/3: " + (dir / "small.exr").string() +
                ": all cube faces must be the same size: this one is 8, the first is 16");
  cube["cubemap"][3] = "wide.exr";
  EXPECT_EQ(error_line(cube, dir.path()), "job.json: /environment/cubemap/3: " + (dir / "wide.exr").string() +
                                              ": a cube face must be square, this one is 30x20");
  EXPECT_EQ(
      error_line(json{{"uniform", 1}, {"sky", json::object()}}, dir.path()),
      "job.json: /environment: give one of uniform, cubemap, cross, latlong, sky (this gives uniform, sky)");
  write_latlong_patch(dir / "ok.exr");
  const std::string line = error_line(json{{"latlong", "ok.exr"}, {"colorspace", "sRGB2"}}, dir.path());
  EXPECT_EQ(line.rfind("job.json: /environment/colorspace: unknown OpenColorIO colour space \"sRGB2\"", 0),
            0u)
      << line;
  { std::ofstream(dir / "corrupt.exr") << "not an image at all"; }
  const std::string corrupt = error_line(json{{"latlong", "corrupt.exr"}}, dir.path());
  EXPECT_EQ(
      corrupt.rfind("job.json: /environment/latlong: " + (dir / "corrupt.exr").string() + ": cannot read", 0),
      0u)
      << corrupt;
}

TEST(LoadEnvironment, NonFinitePixelsAreRejected) {
  TempFolder dir;
  std::vector<float> px(16 * 8 * 3, 1.0f);
  px[(3 * 16 + 5) * 3 + 1] = std::numeric_limits<float>::infinity();
  write_test_image(dir / "inf.exr", 16, 8, 3, px);
  EXPECT_EQ(error_line(json{{"latlong", "inf.exr"}}, dir.path()),
            "job.json: /environment/latlong: " + (dir / "inf.exr").string() +
                ": pixel (5, 3) is not finite (NaN or Inf); an environment must be finite everywhere");
}

TEST(LoadEnvironment, NegativePixelsAndOverflowingIntensitiesAreRejected) {
  TempFolder dir;
  std::vector<float> px(16 * 8 * 3, 1.0f);
  px[(2 * 16 + 7) * 3 + 0] = -5.0f;
  write_test_image(dir / "neg.exr", 16, 8, 3, px);
  const std::string line = error_line(json{{"latlong", "neg.exr"}}, dir.path());
  EXPECT_EQ(line.rfind("job.json: /environment/latlong: " + (dir / "neg.exr").string() +
                           ": pixel (7, 2) is negative (-5, 1, 1 in linear RGB); radiance must be >= 0",
                       0),
            0u)
      << line;
  // A finite float pixel times an allowed intensity beyond float's range.
  std::vector<float> big(16 * 8 * 3, 1.0f);
  big[0] = 1e30f;
  write_test_image(dir / "big.exr", 16, 8, 3, big);
  EXPECT_EQ(error_line(json{{"latlong", "big.exr"}, {"intensity", 1e9}}, dir.path()),
            "job.json: /environment/latlong: " + (dir / "big.exr").string() +
                ": pixel (0, 0) is not finite (NaN or Inf times the intensity 1000000000.000000); an "
                "environment must be finite everywhere");
  // A finite radiance beyond a uniform environment's ceiling, 1e9, alone or times the intensity: its sums
  // would overflow the bakes' floats.
  std::vector<float> huge(16 * 8 * 3, 1.0f);
  huge[(1 * 16 + 2) * 3 + 2] = 3e38f;
  write_test_image(dir / "huge.exr", 16, 8, 3, huge);
  EXPECT_EQ(
      error_line(json{{"latlong", "huge.exr"}}, dir.path()),
      "job.json: /environment/latlong: " + (dir / "huge.exr").string() +
          ": pixel (2, 1) is (1, 1, 3e+38) in linear RGB; an environment's radiance lies in [0, 1e9], as a "
          "uniform one does");
  // A cube face as well as a lat-long.
  std::vector<float> face(8 * 8 * 3, 1.0f);
  write_test_image(dir / "f.exr", 8, 8, 3, face);
  face[3] = -0.25f;
  write_test_image(dir / "fneg.exr", 8, 8, 3, face);
  const json cube{{"cubemap", {"f.exr", "f.exr", "f.exr", "f.exr", "fneg.exr", "f.exr"}}};
  const std::string cube_line = error_line(cube, dir.path());
  EXPECT_EQ(cube_line.rfind("job.json: /environment/cubemap/4: " + (dir / "fneg.exr").string() +
                                ": pixel (1, 0) is negative",
                            0),
            0u)
      << cube_line;
}

TEST(LoadEnvironment, LargeInputsAreResampledToTheCap) {
  TempFolder dir;
  write_latlong_patch(dir / "sky.exr");
  EnvironmentLoadOptions small = kOpts;
  small.max_height = 8;
  const Environment env = load_environment(json{{"latlong", "sky.exr"}}, dir.path(), small).environment;
  EXPECT_EQ(env.levels[0].height, 8);
  EXPECT_EQ(env.levels[0].width, 16);
  // Supersampled, so the patch's power survives the reduction (approximately: 4 x 4 samples per texel).
  const double patch = 100 * 2 * (std::cos(kPi * 10 / 32) - std::cos(kPi * 12 / 32)) * 2 * kPi / 64;
  EXPECT_NEAR(integrate_sphere(env).r, patch, 0.1 * patch);
  EXPECT_LT(angle_deg(light_centroid(env), from_angles_deg(61.875, 90)), 12.0);
}

}  // namespace
}  // namespace hfbake
