#include <tbb/parallel_for.h>

#include "field/height_field.hpp"

namespace hfbake {

// P1 (Section 7): "normals are created from the height data by summing unnormalized normals from each of
// the four quads connected to the height sample". A quad's unnormalised normal is the cross product of its
// diagonals (twice its projected-area-weighted normal), so the sum is exact for any plane. In clamp mode,
// quads outside the field do not exist and are skipped; in repeat mode the field tiles.
Vec3f normal_at(const HeightField& f, int i, int j) {
  const double sx = f.dx(), sy = f.dy();
  const bool repeat = f.wrap == Wrap::repeat;
  Vec3 sum{0, 0, 0};
  for (int qj = j - 1; qj <= j; ++qj) {
    for (int qi = i - 1; qi <= i; ++qi) {
      if (!repeat && (qi < 0 || qj < 0 || qi + 1 >= f.width || qj + 1 >= f.height)) continue;
      const double h00 = f.at(qi, qj), h10 = f.at(qi + 1, qj);
      const double h01 = f.at(qi, qj + 1), h11 = f.at(qi + 1, qj + 1);
      // Diagonals d1 = P11 - P00 = (sx, sy, a), d2 = P01 - P10 = (-sx, sy, b); n = d1 x d2.
      const double a = h11 - h00, b = h01 - h10;
      sum += Vec3{sy * (b - a), -sx * (a + b), 2 * sx * sy};
    }
  }
  return Vec3f::from(normalize(sum));
}

std::vector<Vec3f> compute_normals(const HeightField& f) {
  std::vector<Vec3f> normals(f.texel_count());
  tbb::parallel_for(0, f.height, [&](int j) {
    for (int i = 0; i < f.width; ++i) normals[f.index(i, j)] = normal_at(f, i, j);
  });
  return normals;
}

}  // namespace hfbake
