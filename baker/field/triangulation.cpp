#include "field/triangulation.hpp"

#include "field/height_field.hpp"

namespace hfbake {

void facet_normals(const HeightField& f, int i, int j, Vec3f out[2]) {
  const double z = f.at(i, j), inv = 1 / f.texel_size;
  const double fx = (f.at(i + 1, j) - z) * inv, fy = (f.at(i, j + 1) - z) * inv;  // forward
  const double bx = (z - f.at(i - 1, j)) * inv, by = (z - f.at(i, j - 1)) * inv;  // backward
  out[0] = Vec3f::from(normalize(Vec3{-fx, -fy, 1}));
  out[1] = Vec3f::from(normalize(Vec3{-bx, -by, 1}));
}

}  // namespace hfbake
