#include "methods/nlp/sh_lighting.hpp"

#include <cmath>
#include <vector>

#include "methods/nlp/quadrature.hpp"

namespace hfbake::nlp {

std::array<sh::Coeffs, 3> project_environment(const Environment& env) {
  std::array<sh::Coeffs, 3> out{};
  if (env.levels.empty()) {  // a default-constructed environment: uniform, no stand-in texels
    const double y0 = 0.28209479177387814 * 4 * kPi;
    out[0][0] = y0 * env.uniform_radiance.r;
    out[1][0] = y0 * env.uniform_radiance.g;
    out[2][0] = y0 * env.uniform_radiance.b;
    return out;
  }
  std::size_t li = 0;
  while (li + 1 < env.levels.size() && env.levels[li].height > 128) ++li;
  const Environment::Level& lv = env.levels[li];
  const int w = lv.width, h = lv.height;
  const QuadratureRule g = gauss_legendre(3, 0, 1);
  // Per column: cos/sin of the quadrature azimuths; per row: the quadrature polar angles.
  std::vector<double> cph(std::size_t(w) * 3), sph(std::size_t(w) * 3);
  for (int c = 0; c < w; ++c)
    for (int q = 0; q < 3; ++q) {
      const double phi = 2 * kPi * (c + g.x[q]) / w;
      cph[c * 3 + q] = std::cos(phi);
      sph[c * 3 + q] = std::sin(phi);
    }
  const double dphi = 2 * kPi / w, dth = kPi / h;
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      double integral[sh::kCount] = {};  // integral of Y_i over the texel
      for (int a = 0; a < 3; ++a) {
        const double th = dth * (r + g.x[a]), st = std::sin(th), ct = std::cos(th);
        for (int b = 0; b < 3; ++b) {
          const double wgt = g.w[a] * g.w[b] * dth * dphi * st;
          double y[sh::kCount];
          sh::eval(st * cph[c * 3 + b], st * sph[c * 3 + b], ct, y);
          for (int i = 0; i < sh::kCount; ++i) integral[i] += wgt * y[i];
        }
      }
      const Rgb& t = lv.texels[std::size_t(r) * w + c];
      for (int i = 0; i < sh::kCount; ++i) {
        out[0][i] += t.r * integral[i];
        out[1][i] += t.g * integral[i];
        out[2][i] += t.b * integral[i];
      }
    }
  }
  return out;
}

}  // namespace hfbake::nlp
