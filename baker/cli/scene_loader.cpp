#include "cli/scene_loader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cli/scene_inputs.hpp"
#include "core/error.hpp"
#include "field/procedural.hpp"
#include "methods/method_table.hpp"

namespace hfbake {

namespace {

Rgb rgb_of(const nlohmann::json& v) {
  if (v.is_number()) {
    const float x = v.get<float>();
    return {x, x, x};
  }
  return {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
}

ProceduralSpec procedural_spec(const nlohmann::json& p) {
  ProceduralSpec s;
  parse_procedural_kind(p["kind"].get<std::string>(), s.kind);  // the schema guarantees a known kind
  if (p.contains("size")) {
    s.width = p["size"][0].get<int>();
    s.height = p["size"][1].get<int>();
  }
  s.seed = p.value("seed", std::uint64_t(1));
  s.amplitude = p.value("amplitude", 0.0);
  s.feature_size = p.value("feature_size", 0.0);
  s.angle_deg = p.value("angle_deg", 30.0);
  s.aspect_deg = p.value("aspect_deg", 0.0);
  s.radius = p.value("radius", 0.0);
  s.depth = p.value("depth", 0.0);
  return s;
}

}  // namespace

SceneNeeds scene_needs(const Job& job) {
  SceneNeeds needs;
  needs.normals = needs.albedo = job.has_reference;  // the reference shades with both
  for (const BakeEntry& e : job.bakes) {
    const MethodInfo* m = find_method(e.method);
    needs.normals = needs.normals || !m || m->reads_normals;
    needs.albedo = needs.albedo || !m || m->reads_albedo;
  }
  return needs;
}

FieldSize probe_field_size(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  if (h.contains("procedural")) {
    const ProceduralSpec s = procedural_spec(h["procedural"]);
    return {s.width, s.height};
  }
  return probe_image_field_size(job);
}

double job_texel_size(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  if (h.contains("image"))
    if (const std::optional<double> from_file = image_texel_size(job)) return *from_file;
  if (h.contains("texel_size") && h["texel_size"].is_string())
    throw InputError(job.file.string(), "/height/texel_size",
                     "is \"from_file\" but the field is procedural: give texel_size as a number");
  return h.value("texel_size", 1.0);
}

int job_bounces(const Job& job) {
  return job.doc.value("bounces", 1);
}

std::size_t estimate_peak_bytes(const Job& job, FieldSize size, std::vector<MemoryPart>* parts) {
  const double texels = double(size.width) * double(size.height);
  // Field (4), normals (12), albedo (12), emission (12), and the scene's copy during loading (8).
  double per_texel = 48;
  // Methods: results are kept until the report when there is a reference, else one at a time.
  double methods = 0, largest = 0;
  double scratch = 0;  // the largest method's working memory (methods run one at a time)
  MethodContext context;
  context.field.width = size.width;
  context.field.height = size.height;
  context.bounces = job_bounces(job);
  for (const BakeEntry& e : job.bakes) {
    // The method table's reader (resolve_job has usually run it already).
    const nlohmann::json r = e.resolved.is_object()
                                 ? e.resolved
                                 : resolve_method_params(e.params, context, job.file.string(), e.pointer);
    const MethodInfo* m = find_method(e.method);
    int channels = 0;
    for (const auto& l : r.value("layers", nlohmann::json::array()))
      channels += layer_channel_count(l.get<std::string>(), r);
    const double bytes = 4.0 * channels * 1.5;  // float layers + the half copy written to EXR
    const double working = m ? m->working_bytes_per_texel(r, context) : 0.0;
    methods += bytes;
    largest = std::max(largest, bytes);
    scratch = std::max(scratch, working);
    if (parts) parts->push_back({e.stem, std::size_t(texels * (bytes + working))});
  }
  const double reference = job.has_reference ? 2 * 4.0 * 24 * 1.5 : 0.0;
  if (parts) {
    parts->insert(parts->begin(), {"scene", std::size_t(texels * per_texel) + (std::size_t(64) << 20)});
    if (job.has_reference) parts->push_back({"reference", std::size_t(texels * reference)});
  }
  per_texel += (job.has_reference ? methods + reference : largest) + scratch;
  return std::size_t(texels * per_texel) + (std::size_t(64) << 20);  // + fixed overhead
}

Scene load_scene(const Job& job, const std::function<void(double)>& progress) {
  Scene scene;
  scene.name = job.name;
  const nlohmann::json& doc = job.doc;
  const nlohmann::json& h = doc["height"];
  const double texel = job_texel_size(job);
  const Wrap wrap = h.value("wrap", "clamp") == "repeat" ? Wrap::repeat : Wrap::clamp;
  scene.georeference.geotransform = local_geotransform(texel);
  if (h.contains("procedural")) {
    scene.field = make_procedural(procedural_spec(h["procedural"]), texel, wrap);
  } else {
    scene.field = load_image_field(job, texel, wrap, scene.georeference, progress);
  }
  const double scale = h.value("height_scale", 1.0), offset = h.value("height_offset", 0.0);
  if (scale != 1.0 || offset != 0.0)
    for (float& z : scene.field.z) z = float(z * scale + offset);
  if (scene.field.width < 2 || scene.field.height < 2)
    throw InputError(job.file.string(), "/height",
                     "the field is " + std::to_string(scene.field.width) + "x" +
                         std::to_string(scene.field.height) + "; at least 2x2 texels are needed");
  // Heights whose squares of differences overflow float would turn normals and slopes into inf and NaN
  // downstream: refuse them here (validate loads the scene too). 1e12 world units is far beyond any terrain.
  constexpr float kMaxHeight = 1e12f;
  for (std::size_t t = 0; t < scene.field.z.size(); ++t)
    if (!(std::fabs(scene.field.z[t]) <= kMaxHeight)) {
      const int i = int(t % std::size_t(scene.field.width)), j = int(t / std::size_t(scene.field.width));
      char value[32];
      std::snprintf(value, sizeof value, "%g", double(scene.field.z[t]));
      throw InputError(job.file.string(), "/height",
                       "texel (" + std::to_string(i) + ", " + std::to_string(j) + ") is " + value +
                           " world units high; heights (after height_scale and height_offset) must be within "
                           "+-1e12");
    }
  const SceneNeeds needs = scene_needs(job);
  if (needs.normals) scene.normals = compute_normals(scene.field);

  const std::size_t n = scene.field.texel_count();
  const nlohmann::json surface = doc.value("surface", nlohmann::json::object());
  if (needs.albedo || surface.contains("albedo")) {
    scene.surface.albedo.assign(n, Rgb{0.5f, 0.5f, 0.5f});
    if (surface.contains("albedo"))
      load_surface_map(job, "/surface/albedo", scene.field, scene.surface.albedo);
  }
  if (surface.contains("emission")) {
    scene.surface.emission.assign(n, Rgb{});
    load_surface_map(job, "/surface/emission", scene.field, scene.surface.emission);
  }

  load_lighting(job, scene);
  if (doc.contains("lights")) {
    for (const auto& l : doc["lights"]) {
      const auto& d = l["directional"];
      DirectionalLight light;
      light.direction = normalize({d["direction"][0].get<double>(), d["direction"][1].get<double>(),
                                   d["direction"][2].get<double>()});
      light.angular_diameter = d.value("angular_diameter_deg", 0.0) * kPi / 180.0;
      light.irradiance = rgb_of(d["irradiance"]);
      scene.lights.push_back(light);
    }
  }
  scene.bounces = job_bounces(job);
  return scene;
}

}  // namespace hfbake
