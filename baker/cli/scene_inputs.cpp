#include "cli/scene_inputs.hpp"

#include <cmath>
#include <optional>
#include <string>

#include "core/error.hpp"
#include "field/nodata.hpp"
#include "io/image_input.hpp"
#include "io/load_environment.hpp"

namespace hfbake {

namespace {

InputSite site(const Job& job, const std::string& pointer) {
  return {job.file.string(), pointer};
}

std::optional<float> nodata_value(const nlohmann::json& h) {
  if (!h.contains("nodata_value")) return std::nullopt;
  return h["nodata_value"].get<float>();
}

}  // namespace

FieldSize probe_image_field_size(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  const ImageInfo info = probe_image(job.resolve(h["image"].get<std::string>()), site(job, "/height/image"));
  return {info.width, info.height};
}

HeightField load_image_field(const Job& job, double texel_size, Wrap wrap) {
  const nlohmann::json& h = job.doc["height"];
  const std::string image = h["image"].get<std::string>();
  const ChannelSelector channel = channel_selector(h.contains("channel") ? h["channel"] : nlohmann::json());
  Plane plane = read_image_channel(job.resolve(image), channel, site(job, "/height/image"),
                                   site(job, "/height/channel"));
  HeightField field;
  field.width = plane.width;
  field.height = plane.height;
  field.texel_size = texel_size;
  field.wrap = wrap;
  field.z = std::move(plane.values);

  const std::optional<float> nodata = nodata_value(h);
  const NodataScan scan = scan_nodata(field, nodata);
  if (scan.count == 0) return field;
  if (h.value("nodata", "error") != "fill") {
    const float first = field.z[field.index(scan.first_i, scan.first_j)];
    const std::string what = std::isnan(first) ? "NaN" : std::isinf(first) ? "infinite" : "nodata_value";
    throw InputError(job.file.string(), "/height/image",
                     image + ": texel (" + std::to_string(scan.first_i) + ", " +
                         std::to_string(scan.first_j) + ") is " + what + " (" + std::to_string(scan.count) +
                         " of " + std::to_string(field.texel_count()) +
                         " texels have no valid height); set \"nodata\": \"fill\" to fill the holes");
  }
  if (!fill_nodata(field, nodata))
    throw InputError(job.file.string(), "/height/image", image + ": no texel has a valid height");
  return field;
}

void load_surface_map(const Job& job, const std::string& pointer, const HeightField& field,
                      std::vector<Rgb>& texels) {
  const nlohmann::json& v = job.doc.at(nlohmann::json::json_pointer(pointer));
  if (v.is_number()) {
    const float x = v.get<float>();
    std::fill(texels.begin(), texels.end(), Rgb{x, x, x});
    return;
  }
  if (v.is_array()) {
    std::fill(texels.begin(), texels.end(), Rgb{v[0].get<float>(), v[1].get<float>(), v[2].get<float>()});
    return;
  }
  const std::string image = v["image"].get<std::string>();
  const RgbImage rgb = read_rgb_image(job.resolve(image), v.value("colorspace", std::string()),
                                      site(job, pointer + "/image"), site(job, pointer + "/colorspace"));
  if (rgb.width != field.width || rgb.height != field.height)
    throw InputError(job.file.string(), pointer + "/image",
                     image + ": is " + std::to_string(rgb.width) + "x" + std::to_string(rgb.height) +
                         ", the height field is " + std::to_string(field.width) + "x" +
                         std::to_string(field.height));
  const float scale = v.value("scale", 1.0f);
  for (std::size_t t = 0; t < texels.size(); ++t) {
    const Rgb p = rgb.pixels[t];
    if (!std::isfinite(p.r) || !std::isfinite(p.g) || !std::isfinite(p.b) || p.r < 0 || p.g < 0 || p.b < 0)
      throw InputError(job.file.string(), pointer + "/image",
                       image + ": pixel (" + std::to_string(t % std::size_t(field.width)) + ", " +
                           std::to_string(t / std::size_t(field.width)) + ") is negative or not finite");
    texels[t] = p * scale;
  }
}

void load_lighting(const Job& job, Scene& scene) {
  const nlohmann::json env = job.doc.value("environment", nlohmann::json::object());
  EnvironmentLoadOptions options;
  options.job_file = job.file.string();
  EnvironmentLighting lighting = load_environment(env, job.base_dir, options);
  scene.environment = std::move(lighting.environment);
  scene.lights = std::move(lighting.lights);
}

}  // namespace hfbake
