// Pins hfbake's image-to-world mapping of environments against OpenEXR's own environment-map functions
// (ImfEnvmap.h) composed with the documented axis change world = exr (z, x, y).
#include <gtest/gtest.h>

#include <ImathBox.h>
#include <ImfEnvmap.h>

#include <cmath>
#include <random>

#include "env/env_mapping.hpp"

namespace hfbake {
namespace {

Imath::V3f to_v3f(Vec3 d) {
  return {float(d.x), float(d.y), float(d.z)};
}

std::vector<Vec3> random_directions(int n) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  std::vector<Vec3> v;
  while (int(v.size()) < n) v.push_back(normalize({g(rng), g(rng), g(rng)}));
  return v;
}

TEST(EnvMapping, AxisChangeIsARightHandedRotation) {
  const Vec3 x = world_from_openexr({1, 0, 0}), y = world_from_openexr({0, 1, 0}),
             z = world_from_openexr({0, 0, 1});
  EXPECT_NEAR(dot(cross(x, y), z), 1, 1e-15);
  // The image's up axis (+y in OpenEXR) is world up.
  EXPECT_EQ(y.z, 1);
  const Vec3 d{0.3, -0.5, 0.8};
  const Vec3 r = openexr_from_world(world_from_openexr(d));
  EXPECT_EQ(r.x, d.x);
  EXPECT_EQ(r.y, d.y);
  EXPECT_EQ(r.z, d.z);
}

TEST(EnvMapping, LatLongAgreesWithOpenExr) {
  const int w = 64, h = 32;
  const Imath::Box2i dw({0, 0}, {w - 1, h - 1});
  for (const Vec3& e : random_directions(200)) {
    // OpenEXR places pixel centers 0 and w-1 on longitudes +pi and -pi (center to center); hfbake's
    // pixels tile the sphere (edge to edge): the fractions of the image agree.
    const Imath::V2f p = Imf::LatLongMap::pixelPosition(dw, to_v3f(e));
    double u, v;
    latlong_pixel_of(world_from_openexr(e), w, h, u, v);
    EXPECT_NEAR(u / w, p.x / (w - 1), 1e-5);
    EXPECT_NEAR(v / h, p.y / (h - 1), 1e-5);
    const Vec3 back = latlong_direction_of(u, v, w, h);
    const Vec3 want = world_from_openexr(e);
    EXPECT_NEAR(dot(back, want), 1, 1e-9);
  }
}

TEST(EnvMapping, LatLongLandmarks) {
  // The table of docs/environment.md: center column +x, a quarter from the left +y, top row the zenith.
  const int w = 360, h = 180;
  double u, v;
  latlong_pixel_of({1, 0, 0}, w, h, u, v);
  EXPECT_NEAR(u, 180, 1e-9);
  EXPECT_NEAR(v, 90, 1e-9);
  latlong_pixel_of({0, 1, 0}, w, h, u, v);
  EXPECT_NEAR(u, 90, 1e-9);
  latlong_pixel_of({0, -1, 0}, w, h, u, v);
  EXPECT_NEAR(u, 270, 1e-9);
  latlong_pixel_of({0, 0.01, 1}, w, h, u, v);
  EXPECT_LT(v, 1);
}

TEST(EnvMapping, CubeFacesAgreeWithOpenExr) {
  const int n = 16;
  const Imath::Box2i dw({0, 0}, {n - 1, 6 * n - 1});
  for (const Vec3& e : random_directions(300)) {
    Imf::CubeMapFace face;
    Imath::V2f pif;
    Imf::CubeMap::faceAndPixelPosition(to_v3f(e), dw, face, pif);
    const Imath::V2f strip = Imf::CubeMap::pixelPosition(face, dw, pif);
    // hfbake: the face whose center is nearest, and the position in it (edge to edge).
    const Vec3 d = world_from_openexr(e);
    int best = 0;
    for (int f = 1; f < 6; ++f)
      if (dot(d, openexr_cube_face(f).center) > dot(d, openexr_cube_face(best).center)) best = f;
    ASSERT_EQ(best, int(face));
    double x, y;
    face_pixel_of(openexr_cube_face(best), d, n, x, y);
    // OpenEXR's strip position: x across the face, y = face * n + row within the face, center to center.
    EXPECT_NEAR(x / n, (strip.x - dw.min.x) / (n - 1), 1e-4);
    EXPECT_NEAR(y / n, (strip.y - dw.min.y - best * n) / (n - 1), 1e-4);
  }
}

TEST(EnvMapping, FacesAreSeenFromInside) {
  // right x up = -center for every face (image right, image up, looking outward), cube and cross.
  const auto check = [](const FaceFrame& f) {
    const Vec3 c = cross(f.right, f.up);
    EXPECT_NEAR(dot(c, f.center), -1, 1e-15);
  };
  for (int f = 0; f < 6; ++f) check(openexr_cube_face(f));
  for (auto layout : {CrossLayout::horizontal, CrossLayout::vertical})
    for (const CrossFace& f : cross_faces(layout)) check(f.frame);
  // The cross front looks where the lat-long center looks: world +x.
  EXPECT_EQ(cross_faces(CrossLayout::horizontal)[0].frame.center.x, 1);
}

TEST(EnvMapping, CrossNeighboursShareEdges) {
  // Walking off a face's edge in the cross lands on the adjacent cell's face: the direction at the
  // shared edge midpoint is the same seen from both faces.
  for (auto layout : {CrossLayout::horizontal, CrossLayout::vertical}) {
    const auto faces = cross_faces(layout);
    for (const CrossFace& a : faces)
      for (const CrossFace& b : faces) {
        const int dc = b.col - a.col, dr = b.row - a.row;
        if (std::abs(dc) + std::abs(dr) != 1) continue;
        // Midpoint of the shared edge as seen from a: a = +-1 along right (dc) or b = -+1 along up (dr).
        const Vec3 da = normalize(a.frame.center + double(dc) * a.frame.right - double(dr) * a.frame.up);
        const Vec3 db = normalize(b.frame.center - double(dc) * b.frame.right + double(dr) * b.frame.up);
        EXPECT_NEAR(dot(da, db), 1, 1e-12) << a.col << "," << a.row << " -> " << b.col << "," << b.row;
      }
  }
}

}  // namespace
}  // namespace hfbake
