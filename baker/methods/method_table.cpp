#include "methods/method_table.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "core/error.hpp"
#include "methods/ao/bake_ao.hpp"
#include "methods/nlp/bake_nlp.hpp"
#include "methods/p1/bake_p1.hpp"
#include "methods/p2/bake_p2.hpp"
#include "methods/relief/relief.hpp"
#include "methods/sun/sun.hpp"

namespace hfbake {

std::span<const MethodInfo> method_table() {
  // One line per method.
  static const std::vector<MethodInfo> table = {
      p1_method(),       p2_method(),   nlp_method(), hbao_method(),   lsao_method(),
      farfield_method(), hsao_method(), vo_method(),  relief_method(), sun_method(),
  };
  return table;
}

const MethodInfo* find_method(std::string_view name) {
  for (const MethodInfo& m : method_table())
    if (name == m.name) return &m;
  return nullptr;
}

std::vector<std::string> method_names() {
  std::vector<std::string> names;
  for (const MethodInfo& m : method_table()) names.emplace_back(m.name);
  return names;
}

namespace {

// The methods that bake rectangular texels, and those that apply the Earth's curvature, for messages.
std::vector<std::string> rectangular_methods() {
  std::vector<std::string> names;
  for (const MethodInfo& m : method_table())
    if (m.rectangular_texels) names.emplace_back(m.name);
  return names;
}
std::vector<std::string> curved_methods() {
  std::vector<std::string> names;
  for (const MethodInfo& m : method_table())
    if (m.applies_curvature) names.emplace_back(m.name);
  return names;
}

}  // namespace

MethodConfig resolve_method(const nlohmann::json& entry, const MethodContext& context,
                            const std::string& file, const std::string& pointer) {
  const std::string name = entry.is_object() ? entry.value("method", "") : "";
  const MethodInfo* m = find_method(name);
  if (!m)
    throw InputError(file, pointer + "/method",
                     "unknown method \"" + name + "\" (one of " + quoted_list(method_names()) + ")");
  if (!context.field.square_texels() && !m->rectangular_texels) {
    // As many digits as show the two sides differ (a geographic raster's can agree to 6 and more).
    char sides[96];
    for (int digits = 6; digits <= 17; ++digits) {
      char a[40], b[40];
      std::snprintf(a, sizeof a, "%.*g", digits, context.field.dx());
      std::snprintf(b, sizeof b, "%.*g", digits, context.field.dy());
      std::snprintf(sides, sizeof sides, "%s x %s", a, b);
      if (std::strcmp(a, b) != 0) break;
    }
    throw InputError(
        file, pointer + "/method",
        name + " needs square texels and this field's are " + sides +
            " world units (a geographic raster in its local frame): bake " +
            quoted_list(rectangular_methods()) +
            ", or reproject the raster to square texels (gdalwarp -t_srs EPSG:<UTM zone> -tr S S)");
  }
  if (context.curvature && !m->applies_curvature)
    throw InputError(file, pointer + "/method",
                     name +
                         " bakes a flat Earth and the job's Earth curvature is on (height.curvature, on by "
                         "default for a geographic raster): bake " +
                         quoted_list(curved_methods()) + ", or set \"curvature\": false in height");
  Params in(entry, file, pointer);
  MethodConfig config = m->read(in, context);
  config.method = m;
  config.layers = in.resolved_layers();
  config.resolved = in.resolved();
  config.resolved["method"] = name;
  return config;
}

MethodConfig read_method_config(std::string_view name, const nlohmann::json& params,
                                const MethodContext& context) {
  nlohmann::json entry = params.is_object() ? params : nlohmann::json::object();
  entry["method"] = std::string(name);
  return resolve_method(entry, context, "", "");
}

MethodContext scene_method_context(const Scene& scene) {
  MethodContext c;
  c.field = scene.field;
  c.curvature = scene.curvature > 0;
  c.bounces = scene.bounces;
  c.uniform_environment = scene.environment.is_uniform();
  c.placed = scene.georeference.has_site;
  return c;
}

LayerSet bake_method(std::string_view name, const Scene& scene, const nlohmann::json& params,
                     const RunControl& rc) {
  const MethodConfig config = read_method_config(name, params, scene_method_context(scene));
  return config.method->bake(scene, config, rc);
}

}  // namespace hfbake
