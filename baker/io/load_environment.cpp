#include "io/load_environment.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "env/env_mapping.hpp"
#include "io/image_input.hpp"

namespace hfbake {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::size_t kMaxInputPixels = std::size_t(1) << 27;

Rgb rgb_of(const json& v) {
  if (v.is_number()) {
    const float x = v.get<float>();
    return {x, x, x};
  }
  return {v.at(0).get<float>(), v.at(1).get<float>(), v.at(2).get<float>()};
}

int pow2_at_least(int n) {
  int p = 1;
  while (p < n && p < (1 << 20)) p *= 2;
  return p;
}

struct Source {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;
  Rgb at(int x, int y) const { return pixels[std::size_t(y) * width + x]; }
};

// Bilinear at continuous pixel coordinates (pixel (x, y) covers [x, x+1) x [y, y+1)); columns wrap
// when `wrap_x`, everything else clamps.
Rgb bilinear(const Source& s, double u, double v, bool wrap_x) {
  const double x = u - 0.5, y = v - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const float tx = float(x - fx), ty = float(y - fy);
  int x0 = int(fx), x1 = x0 + 1;
  if (wrap_x) {
    x0 = ((x0 % s.width) + s.width) % s.width;
    x1 = (x0 + 1) % s.width;
  } else {
    x0 = std::clamp(x0, 0, s.width - 1);
    x1 = std::clamp(x1, 0, s.width - 1);
  }
  const int y0 = std::clamp(int(fy), 0, s.height - 1), y1 = std::clamp(int(fy) + 1, 0, s.height - 1);
  return (s.at(x0, y0) * (1 - tx) + s.at(x1, y0) * tx) * (1 - ty) +
         (s.at(x0, y1) * (1 - tx) + s.at(x1, y1) * tx) * ty;
}

// Resamples a radiance function of world direction into a world lat-long of the given height.
Environment resample(int height, int supersample, const std::function<Rgb(Vec3)>& radiance) {
  const int h = height, w = 2 * height, s = supersample;
  std::vector<Rgb> texels(std::size_t(w) * h);
  tbb::parallel_for(0, h, [&](int r) {
    for (int c = 0; c < w; ++c) {
      double R = 0, G = 0, B = 0, W = 0;
      for (int j = 0; j < s; ++j) {
        const double theta = kPi * (r + (j + 0.5) / s) / h, st = std::sin(theta), ct = std::cos(theta);
        for (int i = 0; i < s; ++i) {
          const double phi = 2 * kPi * (c + (i + 0.5) / s) / w;
          const Rgb L = radiance({st * std::cos(phi), st * std::sin(phi), ct});
          R += L.r * st, G += L.g * st, B += L.b * st, W += st;
        }
      }
      texels[std::size_t(r) * w + c] = Rgb{float(R / W), float(G / W), float(B / W)};
    }
  });
  return make_latlong_environment(w, h, std::move(texels));
}

class Loader {
 public:
  Loader(const json& env, const fs::path& base, const EnvironmentLoadOptions& o)
      : env_(env), base_(base), o_(o) {
    intensity_ = env.value("intensity", 1.0f);
    rotation_ = env.value("rotation_deg", 0.0) * kPi / 180;
    if (env.contains("colorspace")) colorspace_ = env["colorspace"].get<std::string>();
  }

  EnvironmentLighting load() {
    std::string given;
    int count = 0;
    for (const char* key : {"uniform", "cubemap", "cross", "latlong", "sky"})
      if (env_.contains(key)) given += (count++ ? ", " : "") + std::string(key);
    if (count > 1)
      throw InputError(o_.job_file, o_.pointer,
                       "give one of uniform, cubemap, cross, latlong, sky (this gives " + given + ")");
    if (env_.contains("uniform")) return {make_uniform_environment(rgb_of(env_["uniform"]) * intensity_), {}};
    if (env_.contains("sky")) return make_sky_environment(sky_spec(env_["sky"]));
    if (env_.contains("latlong")) return {latlong(), {}};
    if (env_.contains("cubemap")) return {cubemap(), {}};
    if (env_.contains("cross")) return {cross(), {}};
    return {make_uniform_environment(Rgb{1, 1, 1} * intensity_), {}};
  }

 private:
  InputSite site(const std::string& key) const { return {o_.job_file, o_.pointer + "/" + key}; }

  [[noreturn]] void fail(const std::string& key, const fs::path& file, const std::string& what) const {
    throw InputError(o_.job_file, o_.pointer + "/" + key, file.string() + ": " + what);
  }

  SkySpec sky_spec(const json& sky) const {
    SkySpec s;
    if (sky.contains("zenith")) s.zenith = rgb_of(sky["zenith"]);
    if (sky.contains("horizon")) s.horizon = rgb_of(sky["horizon"]);
    if (sky.contains("ground")) s.ground = rgb_of(sky["ground"]);
    if (sky.contains("sun")) {
      const json& sun = sky["sun"];
      s.sun_elevation_deg = sun.value("elevation_deg", s.sun_elevation_deg);
      s.sun_azimuth_deg = sun.value("azimuth_deg", s.sun_azimuth_deg);
      s.sun_angular_diameter_deg = sun.value("angular_diameter_deg", s.sun_angular_diameter_deg);
      if (sun.contains("irradiance")) s.sun_irradiance = rgb_of(sun["irradiance"]);
    }
    s.intensity = intensity_;
    s.rotation_deg = rotation_ * 180 / kPi;
    return s;
  }

  // Reads one image (header checked first) as linear RGB.
  Source read(const std::string& key, const fs::path& file) const {
    const ImageInfo info = probe_image(file, site(key));
    if (std::size_t(info.width) * std::size_t(info.height) > kMaxInputPixels)
      fail(key, file,
           "the image is " + std::to_string(info.width) + "x" + std::to_string(info.height) +
               "; environments are limited to 2^27 pixels");
    RgbImage img = read_rgb_image(file, colorspace_, site(key), site("colorspace"));
    // Radiance is finite and non-negative: a negative pixel would subtract light and break the reference's
    // importance sampling (a luminance CDF with negative weights). Checked after the conversion to linear.
    for (std::size_t i = 0; i < img.pixels.size(); ++i) {
      Rgb& p = img.pixels[i];
      p = p * intensity_;
      const bool finite = std::isfinite(p.r) && std::isfinite(p.g) && std::isfinite(p.b);
      const bool bounded = p.r <= kMaxRadiance && p.g <= kMaxRadiance && p.b <= kMaxRadiance;
      if (finite && bounded && p.r >= 0 && p.g >= 0 && p.b >= 0) continue;
      const std::string where = "pixel (" + std::to_string(i % std::size_t(img.width)) + ", " +
                                std::to_string(i / std::size_t(img.width)) + ")";
      if (finite && !bounded) {
        char value[96];
        std::snprintf(value, sizeof value, " is (%g, %g, %g) in linear RGB", double(p.r), double(p.g),
                      double(p.b));
        fail(key, file,
             where + value + (intensity_ != 1 ? " times the intensity" : "") +
                 "; an environment's radiance lies in [0, 1e9], as a uniform one does");
      }
      if (!finite)
        fail(key, file,
             where + " is not finite (NaN or Inf" +
                 (intensity_ != 1 ? " times the intensity " + std::to_string(intensity_) : "") +
                 "); an environment must be finite everywhere");
      char value[96];
      std::snprintf(value, sizeof value, " is negative (%g, %g, %g in linear RGB)", double(p.r), double(p.g),
                    double(p.b));
      fail(key, file,
           where + value +
               "; radiance must be >= 0 (a colour space conversion of out-of-gamut colours "
               "can make negatives: convert the image to linear Rec.709 and clamp at 0 first)");
    }
    return {img.width, img.height, std::move(img.pixels)};
  }

  Vec3 unrotate(Vec3 d) const { return rotation_ == 0 ? d : rotate_about_z(d, -rotation_); }

  Environment latlong() {
    const fs::path file = base_ / env_["latlong"].get<std::string>();
    const Source src = read("latlong", file);
    if (src.width != 2 * src.height)
      fail("latlong", file,
           "a lat-long needs a 2:1 image, this one is " + std::to_string(src.width) + "x" +
               std::to_string(src.height));
    const int h = std::clamp(pow2_at_least(src.height), 8, o_.max_height);
    const int ss = std::clamp(int(std::ceil(double(src.height) / h)), 1, 4);
    return resample(h, ss, [&](Vec3 d) {
      double u, v;
      latlong_pixel_of(unrotate(d), src.width, src.height, u, v);
      return bilinear(src, u, v, true);
    });
  }

  struct Face {
    FaceFrame frame;
    Source image;  // n x n
    int x0 = 0, y0 = 0;
  };

  Environment from_faces(const std::vector<Face>& faces, int n) {
    const int h = std::clamp(pow2_at_least(2 * n), 8, o_.max_height);
    const int ss = std::clamp(int(std::ceil(2.0 * n / h)), 1, 4);
    return resample(h, ss, [&](Vec3 d) {
      d = unrotate(d);
      int best = 0;
      double best_dot = -2;
      for (int f = 0; f < 6; ++f) {
        const double c = dot(d, faces[f].frame.center);
        if (c > best_dot) best_dot = c, best = f;
      }
      const Face& f = faces[best];
      double x, y;
      face_pixel_of(f.frame, d, n, x, y);
      return bilinear(f.image, x, y, false);
    });
  }

  Environment cubemap() {
    const json& files = env_["cubemap"];
    std::vector<Face> faces(6);
    int n = 0;
    for (int f = 0; f < 6; ++f) {
      const std::string key = "cubemap/" + std::to_string(f);
      const fs::path file = base_ / files.at(std::size_t(f)).get<std::string>();
      faces[f].frame = openexr_cube_face(f);
      faces[f].image = read(key, file);
      const Source& img = faces[f].image;
      if (img.width != img.height)
        fail(key, file,
             "a cube face must be square, this one is " + std::to_string(img.width) + "x" +
                 std::to_string(img.height));
      if (f == 0) n = img.width;
      if (img.width != n)
        fail(key, file,
             "all cube faces must be the same size: this one is " + std::to_string(img.width) +
                 ", the first is " + std::to_string(n));
    }
    return from_faces(faces, n);
  }

  Environment cross() {
    const fs::path file = base_ / env_["cross"].get<std::string>();
    const Source src = read("cross", file);
    CrossLayout layout;
    int n;
    if (src.width * 3 == src.height * 4) {
      layout = CrossLayout::horizontal, n = src.width / 4;
    } else if (src.width * 4 == src.height * 3) {
      layout = CrossLayout::vertical, n = src.width / 3;
    } else {
      fail("cross", file,
           "a cube cross must be 4:3 (horizontal) or 3:4 (vertical), this one is " +
               std::to_string(src.width) + "x" + std::to_string(src.height));
    }
    std::vector<Face> faces(6);
    const auto cells = cross_faces(layout);
    for (int f = 0; f < 6; ++f) {
      faces[f].frame = cells[f].frame;
      Source& img = faces[f].image;
      img.width = img.height = n;
      img.pixels.resize(std::size_t(n) * n);
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          img.pixels[std::size_t(y) * n + x] = src.at(cells[f].col * n + x, cells[f].row * n + y);
    }
    return from_faces(faces, n);
  }

  const json& env_;
  fs::path base_;
  EnvironmentLoadOptions o_;
  float intensity_ = 1;
  double rotation_ = 0;
  std::string colorspace_;
};

}  // namespace

EnvironmentLighting load_environment(const json& environment, const fs::path& base_dir,
                                     const EnvironmentLoadOptions& options) {
  return Loader(environment, base_dir, options).load();
}

EnvironmentBytes environment_bytes(const json& environment, const fs::path& base_dir,
                                   const EnvironmentLoadOptions& options) {
  EnvironmentBytes b;
  if (!environment.is_object()) return b;
  // The world lat-long of `rows` rows (2 rows x rows texels): 16 bytes a texel with its mip levels, and 16
  // for the reference's sampling tables.
  auto set_world = [&b](int rows) {
    b.world = 16.0 * 2.0 * double(rows) * double(rows);
    b.tables = 16.0 * 2.0 * double(rows) * double(rows);
  };
  if (environment.contains("sky")) {
    set_world(SkySpec{}.height);
    return b;
  }
  std::vector<std::pair<std::string, std::string>> files;  // key, file
  if (environment.contains("latlong") && environment["latlong"].is_string())
    files.emplace_back("latlong", environment["latlong"].get<std::string>());
  else if (environment.contains("cross") && environment["cross"].is_string())
    files.emplace_back("cross", environment["cross"].get<std::string>());
  else if (environment.contains("cubemap") && environment["cubemap"].is_array())
    for (std::size_t f = 0; f < environment["cubemap"].size(); ++f)
      if (environment["cubemap"][f].is_string())
        files.emplace_back("cubemap/" + std::to_string(f), environment["cubemap"][f].get<std::string>());
  if (files.empty()) return b;
  double sum = 0, largest = 0;
  int rows = 0;
  for (const auto& [key, name] : files) {
    const ImageInfo info = probe_image(base_dir / name, {options.job_file, options.pointer + "/" + key});
    const double px = double(info.width) * double(info.height);
    if (px > double(kMaxInputPixels)) return {};  // refused by the loader, with its own message
    sum += px, largest = std::max(largest, px);
    // Rows of the world lat-long (Loader::latlong, from_faces): the lat-long's height, twice a face's side.
    const int face = key != "cross"                      ? info.width
                     : info.width * 3 == info.height * 4 ? info.width / 4
                                                         : info.width / 3;
    const int latitude = key == "latlong" ? info.height : 2 * face;
    rows = std::max(rows, std::clamp(pow2_at_least(latitude), 8, options.max_height));
  }
  // Every image held as linear RGB (12 bytes a pixel) until the resampling, and while the last one is read
  // its decoded channels beside it (read_rgb_image: up to 12 bytes a pixel more); then the world lat-long
  // built beside them.
  set_world(rows);
  b.loading = std::max(12 * sum + 12 * largest, 12 * sum + b.world);
  return b;
}

}  // namespace hfbake
