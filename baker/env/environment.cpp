#include "env/environment.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>

namespace hfbake {

namespace {

constexpr double kTwoPi = 2 * kPi;
constexpr int kUniformHeight = 8;  // the small constant lat-long a uniform environment carries

// atan2 to within 1e-5 rad (Abramowitz & Stegun 4.4.49 on [0, 1], then octant symmetry): a texel of a
// 1024-row lat-long is 3e-3 rad, so the error is far below anything a lookup can show, and lookups are
// ~2x faster than with std::atan2. Deterministic (plain arithmetic).
float fast_atan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float mx = std::max(ax, ay), mn = std::min(ax, ay);
  if (mx == 0) return 0;
  const float a = mn / mx, s = a * a;
  float r = a * (0.9998660f + s * (-0.3302995f + s * (0.1801410f + s * (-0.0851330f + s * 0.0208351f))));
  if (ay > ax) r = float(kPi / 2) - r;
  if (x < 0) r = float(kPi) - r;
  return y < 0 ? -r : r;
}

// Bilinear lookup in a lat-long level at continuous texel coordinates (u, v) measured in texels from
// the image's top-left corner (texel centers at + 0.5), u in [0, width]. Wraps in azimuth, clamps at the
// poles.
Rgb bilinear(const Environment::Level& level, float u, float v) {
  const float x = u - 0.5f, y = v - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  int c0 = int(fx);
  if (c0 < 0) c0 += level.width;
  if (c0 >= level.width) c0 -= level.width;
  const int c1 = c0 + 1 == level.width ? 0 : c0 + 1;
  const int r0 = std::clamp(int(fy), 0, level.height - 1);
  const int r1 = std::min(int(fy) + 1, level.height - 1);
  const Rgb* row0 = &level.texels[std::size_t(r0) * level.width];
  const Rgb* row1 = &level.texels[std::size_t(std::max(r1, 0)) * level.width];
  return (row0[c0] * (1 - tx) + row0[c1] * tx) * (1 - ty) + (row1[c0] * (1 - tx) + row1[c1] * tx) * ty;
}

Rgb sample_level(const Environment::Level& level, Vec3 dir) {
  // Single precision is ample; atan2 needs no normalised input.
  const float x = float(dir.x), y = float(dir.y), z = float(dir.z);
  const float theta = fast_atan2(std::sqrt(x * x + y * y), z);
  float phi = fast_atan2(y, x);
  if (phi < 0) phi += float(kTwoPi);
  return bilinear(level, phi * float(level.width / kTwoPi), theta * float(level.height / kPi));
}

}  // namespace

// --- Environment ----------------------------------------------------------------------------------

Rgb Environment::radiance(Vec3 dir) const {
  if (is_uniform()) return uniform_radiance;
  return sample_level(levels[0], dir);
}

Rgb Environment::radiance_filtered(Vec3 dir, double cone) const {
  if (is_uniform()) return uniform_radiance;
  // Level m has texels pi / height_m tall; pick the level whose texel spans the cone's diameter and
  // blend the two nearest levels (trilinear).
  const double texel0 = kPi / levels[0].height;
  const double lod = std::log2(std::max(2 * cone, 1e-12) / texel0);
  const double top = double(levels.size() - 1);
  if (lod <= 0) return sample_level(levels[0], dir);
  if (lod >= top) return sample_level(levels.back(), dir);
  const int m = int(lod);
  const float t = float(lod - m);
  return sample_level(levels[m], dir) * (1 - t) + sample_level(levels[m + 1], dir) * t;
}

Vec3 Environment::texel_direction(int c, int r) const {
  const Level& l = levels.at(0);
  const double theta = kPi * (r + 0.5) / l.height, phi = kTwoPi * (c + 0.5) / l.width;
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

double Environment::texel_solid_angle(int r) const {
  const Level& l = levels.at(0);
  return latlong_texel_solid_angle(l.width, l.height, r);
}

double latlong_texel_solid_angle(int width, int height, int r) {
  const double t0 = kPi * r / height, t1 = kPi * (r + 1) / height;
  return (std::cos(t0) - std::cos(t1)) * kTwoPi / width;
}

// --- construction ---------------------------------------------------------------------------------

void build_mip_levels(Environment& env) {
  if (env.levels.empty()) return;
  env.levels.resize(1);
  for (;;) {
    const Environment::Level& fine = env.levels.back();
    if (fine.height <= 1 || fine.width <= 2 || fine.height % 2 || fine.width % 2) break;
    Environment::Level coarse;
    coarse.width = fine.width / 2;
    coarse.height = fine.height / 2;
    coarse.texels.resize(std::size_t(coarse.width) * coarse.height);
    for (int r = 0; r < coarse.height; ++r) {
      // Weights: the two child rows' solid angles (the same for every column of a row).
      const double w0 = latlong_texel_solid_angle(fine.width, fine.height, 2 * r);
      const double w1 = latlong_texel_solid_angle(fine.width, fine.height, 2 * r + 1);
      const double norm = 1.0 / (2 * (w0 + w1));
      for (int c = 0; c < coarse.width; ++c) {
        const auto at = [&](int cc, int rr) { return fine.texels[std::size_t(rr) * fine.width + cc]; };
        const Rgb a = at(2 * c, 2 * r) + at(2 * c + 1, 2 * r);
        const Rgb b = at(2 * c, 2 * r + 1) + at(2 * c + 1, 2 * r + 1);
        coarse.texels[std::size_t(r) * coarse.width + c] =
            Rgb{float((a.r * w0 + b.r * w1) * norm), float((a.g * w0 + b.g * w1) * norm),
                float((a.b * w0 + b.b * w1) * norm)};
      }
    }
    env.levels.push_back(std::move(coarse));
  }
}

Environment make_latlong_environment(int width, int height, std::vector<Rgb> texels) {
  if (width <= 0 || height <= 0 || width != 2 * height || texels.size() != std::size_t(width) * height)
    throw std::invalid_argument("make_latlong_environment: need width == 2 * height texels");
  Environment env;
  env.uniform = false;
  env.levels.resize(1);
  env.levels[0].width = width;
  env.levels[0].height = height;
  env.levels[0].texels = std::move(texels);
  build_mip_levels(env);
  // The mean radiance (what a uniform stand-in would be) is handy for diagnostics.
  const Rgb total = integrate_sphere(env, int(env.levels.size()) - 1);
  env.uniform_radiance = total * float(1 / (4 * kPi));
  return env;
}

Environment make_uniform_environment(Rgb radiance) {
  Environment env =
      make_latlong_environment(2 * kUniformHeight, kUniformHeight,
                               std::vector<Rgb>(std::size_t(2 * kUniformHeight * kUniformHeight), radiance));
  env.uniform = true;
  env.uniform_radiance = radiance;
  return env;
}

Rgb integrate_sphere(const Environment& env, int level) {
  if (env.levels.empty()) return env.uniform_radiance * float(4 * kPi);
  const Environment::Level& l = env.levels.at(std::size_t(level));
  double r = 0, g = 0, b = 0;
  for (int row = 0; row < l.height; ++row) {
    double rr = 0, gg = 0, bb = 0;
    for (int c = 0; c < l.width; ++c) {
      const Rgb& t = l.texels[std::size_t(row) * l.width + c];
      rr += t.r, gg += t.g, bb += t.b;
    }
    const double w = latlong_texel_solid_angle(l.width, l.height, row);
    r += rr * w, g += gg * w, b += bb * w;
  }
  return {float(r), float(g), float(b)};
}

std::vector<Rgb> azimuth_wedge_profile(const Environment& env, double phi0, double phi1) {
  if (env.levels.empty()) return {};
  const Environment::Level& l = env.levels[0];
  if (env.uniform) return std::vector<Rgb>(std::size_t(l.height), env.uniform_radiance);
  if (!(phi1 > phi0)) throw std::invalid_argument("azimuth_wedge_profile: need phi1 > phi0");
  // In column units; a wedge of a full turn or more is the whole row (weighted by whole turns + rest).
  const double scale = l.width / kTwoPi;
  const double a = phi0 * scale, b = phi1 * scale;
  // Weight of each column: its overlap with [a, b] summed over all wraps.
  std::vector<double> weight(std::size_t(l.width), 0.0);
  const double first = std::floor(a);
  for (double c = first; c < b; c += 1) {
    const double overlap = std::min(c + 1, b) - std::max(c, a);
    if (overlap <= 0) continue;
    long col = long(c) % l.width;
    if (col < 0) col += l.width;
    weight[std::size_t(col)] += overlap;
  }
  const double total = b - a;
  std::vector<Rgb> out(std::size_t(l.height));
  for (int r = 0; r < l.height; ++r) {
    double R = 0, G = 0, B = 0;
    const Rgb* row = &l.texels[std::size_t(r) * l.width];
    for (int c = 0; c < l.width; ++c) {
      if (weight[std::size_t(c)] == 0) continue;
      R += row[c].r * weight[std::size_t(c)], G += row[c].g * weight[std::size_t(c)],
          B += row[c].b * weight[std::size_t(c)];
    }
    out[std::size_t(r)] = Rgb{float(R / total), float(G / total), float(B / total)};
  }
  return out;
}

// --- sky ------------------------------------------------------------------------------------------

Vec3 direction_from_elevation_azimuth(double elevation_deg, double azimuth_deg) {
  const double e = elevation_deg * kPi / 180, a = azimuth_deg * kPi / 180;
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

EnvironmentLighting make_sky_environment(const SkySpec& spec) {
  const int h = std::max(2, spec.height + spec.height % 2), w = 2 * h;
  std::vector<Rgb> texels(std::size_t(w) * h);
  for (int r = 0; r < h; ++r) {
    // Mean over the texel: dOmega = dz dphi, and L is linear in z above the horizon, so the mean is L at
    // the mean z of the row. h is even, so no row straddles the horizon.
    const double z0 = std::cos(kPi * r / h), z1 = std::cos(kPi * (r + 1) / h);
    Rgb value = spec.ground;
    if (r < h / 2) {
      const float s = float(0.5 * (z0 + z1));
      value = spec.horizon * (1 - s) + spec.zenith * s;
    }
    value = value * spec.intensity;
    std::fill(texels.begin() + std::ptrdiff_t(r) * w, texels.begin() + std::ptrdiff_t(r + 1) * w, value);
  }
  EnvironmentLighting out;
  out.environment = make_latlong_environment(w, h, std::move(texels));
  const Rgb sun = spec.sun_irradiance * spec.intensity;
  if (spec.sun_elevation_deg > 0 && (sun.r > 0 || sun.g > 0 || sun.b > 0)) {
    DirectionalLight light;
    light.direction =
        direction_from_elevation_azimuth(spec.sun_elevation_deg, spec.sun_azimuth_deg + spec.rotation_deg);
    light.angular_diameter = spec.sun_angular_diameter_deg * kPi / 180;
    light.irradiance = sun;
    out.lights.push_back(light);
  }
  return out;
}

// --- cube view ------------------------------------------------------------------------------------

namespace {
// (axis, u, v) per face, u x v = axis.
constexpr double kFaceFrames[6][3][3] = {
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},  {{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}},
    {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}}, {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {1, 0, 0}, {0, -1, 0}},
};
Vec3 frame_vec(int face, int k) {
  const double* v = kFaceFrames[face][k];
  return {v[0], v[1], v[2]};
}
// Solid angle subtended by [0, a] x [0, b] on the plane at distance 1 (signed; a standard closed form).
double rect_solid_angle(double a, double b) {
  return std::atan2(a * b, std::sqrt(a * a + b * b + 1));
}
}  // namespace

Vec3 CubeView::face_axis(int face) {
  return frame_vec(face, 0);
}
Vec3 CubeView::face_u(int face) {
  return frame_vec(face, 1);
}
Vec3 CubeView::face_v(int face) {
  return frame_vec(face, 2);
}

Vec3 CubeView::texel_direction(int face, int i, int j) const {
  const double a = 2 * (i + 0.5) / size - 1, b = 2 * (j + 0.5) / size - 1;
  return normalize(face_axis(face) + a * face_u(face) + b * face_v(face));
}

double CubeView::texel_solid_angle(int i, int j) const {
  const double a0 = 2.0 * i / size - 1, a1 = 2.0 * (i + 1) / size - 1;
  const double b0 = 2.0 * j / size - 1, b1 = 2.0 * (j + 1) / size - 1;
  return rect_solid_angle(a1, b1) - rect_solid_angle(a0, b1) - rect_solid_angle(a1, b0) +
         rect_solid_angle(a0, b0);
}

CubeView make_cube_view(const Environment& env, int size) {
  if (size <= 0) throw std::invalid_argument("make_cube_view: size must be > 0");
  CubeView view;
  view.size = size;
  // Each texel is the solid-angle-weighted mean of s x s bilinear samples, s chosen so the samples are
  // no farther apart than the environment's texels (a cube texel near a face center spans 2 / size
  // radians; a lat-long texel pi / height).
  int s = 1;
  if (!env.uniform && !env.levels.empty())
    s = std::clamp(int(std::ceil((2.0 / size) / (kPi / env.levels[0].height))), 1, 8);
  for (int f = 0; f < 6; ++f) {
    std::vector<Rgb>& face = view.faces[f];
    face.resize(std::size_t(size) * size);
    const Vec3 axis = CubeView::face_axis(f), u = CubeView::face_u(f), v = CubeView::face_v(f);
    for (int j = 0; j < size; ++j) {
      for (int i = 0; i < size; ++i) {
        if (env.is_uniform()) {
          face[std::size_t(j) * size + i] = env.uniform_radiance;
          continue;
        }
        double r = 0, g = 0, b = 0, wsum = 0;
        for (int sj = 0; sj < s; ++sj) {
          for (int si = 0; si < s; ++si) {
            const double a = 2 * (i + (si + 0.5) / s) / size - 1, bb = 2 * (j + (sj + 0.5) / s) / size - 1;
            // dOmega = dA / (1 + a^2 + b^2)^(3/2) on the unit-distance plane.
            const double q = 1 + a * a + bb * bb, w = 1 / (q * std::sqrt(q));
            const Rgb L = env.radiance(axis + a * u + bb * v);
            r += L.r * w, g += L.g * w, b += L.b * w, wsum += w;
          }
        }
        face[std::size_t(j) * size + i] = Rgb{float(r / wsum), float(g / wsum), float(b / wsum)};
      }
    }
  }
  return view;
}

}  // namespace hfbake
