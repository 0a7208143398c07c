#include "env/env_mapping.hpp"

#include <algorithm>
#include <cmath>

namespace hfbake {

Vec3 rotate_about_z(Vec3 d, double radians) {
  const double c = std::cos(radians), s = std::sin(radians);
  return {c * d.x - s * d.y, s * d.x + c * d.y, d.z};
}

void latlong_pixel_of(Vec3 d, int w, int h, double& u, double& v) {
  d = normalize(d);
  const double theta = std::acos(std::clamp(d.z, -1.0, 1.0));
  const double phi = std::atan2(d.y, d.x);  // (-pi, pi]
  u = (kPi - phi) / (2 * kPi) * w;
  v = theta / kPi * h;
}

Vec3 latlong_direction_of(double u, double v, int w, int h) {
  const double phi = kPi - 2 * kPi * u / w, theta = kPi * v / h;
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

FaceFrame openexr_cube_face(int face) {
  // Faces in OpenEXR's frame (ImfEnvmap.h diagram: seen from inside, +x face: right +z, up +y; ...),
  // then mapped to the world.
  static const double k[6][3][3] = {
      {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}},    // +x: right +z, up +y
      {{-1, 0, 0}, {0, 0, -1}, {0, 1, 0}},  // -x: right -z, up +y
      {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},    // +y: right +x, up +z
      {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}},  // -y: right +x, up -z
      {{0, 0, 1}, {-1, 0, 0}, {0, 1, 0}},   // +z: right -x, up +y
      {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}},   // -z: right +x, up +y
  };
  const auto v = [&](int i) { return world_from_openexr({k[face][i][0], k[face][i][1], k[face][i][2]}); };
  return {v(0), v(1), v(2)};
}

std::array<CrossFace, 6> cross_faces(CrossLayout layout) {
  const Vec3 px{1, 0, 0}, nx{-1, 0, 0}, py{0, 1, 0}, ny{0, -1, 0}, pz{0, 0, 1}, nz{0, 0, -1};
  std::array<CrossFace, 6> f;
  f[0] = {1, 1, {px, ny, pz}};  // front
  f[1] = {0, 1, {py, px, pz}};  // left
  f[2] = {2, 1, {ny, nx, pz}};  // right
  f[4] = {1, 0, {pz, ny, nx}};  // top
  f[5] = {1, 2, {nz, ny, px}};  // bottom
  if (layout == CrossLayout::horizontal)
    f[3] = {3, 1, {nx, py, pz}};  // back
  else
    f[3] = {1, 3, {nx, ny, nz}};  // back, upside down below the bottom face
  return f;
}

void face_pixel_of(const FaceFrame& f, Vec3 d, int n, double& x, double& y) {
  const double c = dot(d, f.center);
  const double a = dot(d, f.right) / c, b = dot(d, f.up) / c;
  x = (a + 1) * 0.5 * n;
  y = (1 - b) * 0.5 * n;
}

}  // namespace hfbake
