#include "reference/sh_environment.hpp"

namespace hfbake::reference {

std::array<double, kShCoefficients> sh_basis(Vec3 d) {
  const double x = d.x, y = d.y, z = d.z;
  return {0.28209479177387814,
          0.4886025119029199 * y,
          0.4886025119029199 * z,
          0.4886025119029199 * x,
          1.0925484305920792 * x * y,
          1.0925484305920792 * y * z,
          0.31539156525252005 * (3 * z * z - 1),
          1.0925484305920792 * x * z,
          0.5462742152960396 * (x * x - y * y),
          0.5900435899266435 * y * (3 * x * x - y * y),
          2.890611442640554 * x * y * z,
          0.4570457994644658 * y * (5 * z * z - 1),
          0.3731763325901154 * z * (5 * z * z - 3),
          0.4570457994644658 * x * (5 * z * z - 1),
          1.445305721320277 * z * (x * x - y * y),
          0.5900435899266435 * x * (x * x - 3 * y * y)};
}

std::array<Rgb, kShCoefficients> project_sh(const Environment& env) {
  std::array<double, 3 * kShCoefficients> acc{};
  if (env.is_uniform()) {
    std::array<Rgb, kShCoefficients> c{};
    const float k = float(4 * kPi * 0.28209479177387814);
    c[0] = env.uniform_radiance * k;
    return c;
  }
  const Environment::Level& l0 = env.levels[0];
  for (int r = 0; r < l0.height; ++r) {
    const double omega = env.texel_solid_angle(r);
    for (int c = 0; c < l0.width; ++c) {
      const auto y = sh_basis(env.texel_direction(c, r));
      const Rgb v = l0.texels[std::size_t(r) * l0.width + c];
      for (int k = 0; k < kShCoefficients; ++k) {
        acc[3 * k] += v.r * y[k] * omega;
        acc[3 * k + 1] += v.g * y[k] * omega;
        acc[3 * k + 2] += v.b * y[k] * omega;
      }
    }
  }
  std::array<Rgb, kShCoefficients> c{};
  for (int k = 0; k < kShCoefficients; ++k)
    c[k] = {float(acc[3 * k]), float(acc[3 * k + 1]), float(acc[3 * k + 2])};
  return c;
}

Environment band_limited_environment(const Environment& env) {
  if (env.is_uniform()) return env;
  const auto coeffs = project_sh(env);
  const Environment::Level& l0 = env.levels[0];
  std::vector<Rgb> texels(std::size_t(l0.width) * l0.height);
  for (int r = 0; r < l0.height; ++r)
    for (int c = 0; c < l0.width; ++c) {
      const auto y = sh_basis(env.texel_direction(c, r));
      double v[3] = {0, 0, 0};
      for (int k = 0; k < kShCoefficients; ++k) {
        v[0] += coeffs[k].r * y[k];
        v[1] += coeffs[k].g * y[k];
        v[2] += coeffs[k].b * y[k];
      }
      texels[std::size_t(r) * l0.width + c] = {float(v[0]), float(v[1]), float(v[2])};
    }
  return make_latlong_environment(l0.width, l0.height, std::move(texels));
}

}  // namespace hfbake::reference
