#include "field/triangulation.hpp"

#include "field/height_field.hpp"

namespace hfbake {

void facet_normals(const HeightField& f, int i, int j, Vec3f out[2]) {
  const double z = f.at(i, j), inv_x = 1 / f.dx(), inv_y = 1 / f.dy();
  const double fx = (f.at(i + 1, j) - z) * inv_x, fy = (f.at(i, j + 1) - z) * inv_y;  // forward
  const double bx = (z - f.at(i - 1, j)) * inv_x, by = (z - f.at(i, j - 1)) * inv_y;  // backward
  out[0] = Vec3f::from(normalize(Vec3{-fx, -fy, 1}));
  out[1] = Vec3f::from(normalize(Vec3{-bx, -by, 1}));
}

void corner_facet_normals(const HeightField& f, int i, int j, Vec3f out[kCornerFacets]) {
  facet_normals(f, i, j, out);
  for (int c = 2; c < kCornerFacets; ++c) {
    Vec3f fn[2];
    facet_normals(f, i + kCornerFacet[c].di, j + kCornerFacet[c].dj, fn);
    out[c] = fn[kCornerFacet[c].q];
  }
}

}  // namespace hfbake
