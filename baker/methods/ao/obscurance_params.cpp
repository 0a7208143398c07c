#include "methods/ao/obscurance_params.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace hfbake {

Falloff parse_falloff(const nlohmann::json& params) {
  Falloff f;
  const bool has_radius = params.contains("radius");
  f.kind = has_radius ? FalloffKind::step : FalloffKind::none;
  if (params.contains("falloff")) {
    const auto& v = params.at("falloff");
    if (!v.is_string() || !parse_falloff_kind(v.get<std::string>(), f.kind))
      throw InputError(
          "", "falloff",
          "must be one of \"none\", \"step\", \"linear\", \"smooth\", \"exponential\", \"rational\"");
  }
  if (has_radius) {
    const auto& r = params.at("radius");
    if (!r.is_number() || !(r.get<double>() > 0) || !std::isfinite(r.get<double>()))
      throw InputError("", "radius", "must be a positive number (world units)");
    f.radius = r.get<double>();
  }
  if (f.kind == FalloffKind::none && has_radius)
    throw InputError("", "radius",
                     "has no effect with falloff \"none\" (use \"step\" for AO limited to a radius)");
  if (f.kind != FalloffKind::none && !has_radius)
    throw InputError("", "radius", "is required with a falloff other than \"none\" (world units)");
  return f;
}

Weighting parse_weighting(const nlohmann::json& params, bool allow_uniform) {
  if (!params.contains("weighting")) return Weighting::cosine;
  const auto& v = params.at("weighting");
  if (v == "cosine") return Weighting::cosine;
  if (v == "uniform") {
    if (!allow_uniform) throw InputError("", "weighting", "this method supports only \"cosine\"");
    return Weighting::uniform;
  }
  throw InputError("", "weighting", "must be \"cosine\" or \"uniform\"");
}

int int_param(const nlohmann::json& params, const char* key, int fallback, int lo, int hi) {
  if (!params.contains(key)) return fallback;
  const auto& v = params.at(key);
  if (!v.is_number_integer()) throw InputError("", key, "must be an integer");
  const long long x = v.get<long long>();
  if (x < lo || x > hi)
    throw InputError("", key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return int(x);
}

double number_param(const nlohmann::json& params, const char* key, double fallback, double lo, double hi) {
  if (!params.contains(key)) return fallback;
  const auto& v = params.at(key);
  if (!v.is_number()) throw InputError("", key, "must be a number");
  const double x = v.get<double>();
  if (!(x >= lo && x <= hi))
    throw InputError("", key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return x;
}

std::vector<std::string> select_layers(const nlohmann::json& params, const std::vector<std::string>& known,
                                       const std::vector<std::string>& defaults) {
  if (!params.contains("layers")) return defaults;
  std::vector<std::string> out;
  for (const auto& v : params.at("layers")) {
    const std::string name = v.is_string() ? v.get<std::string>() : v.dump();
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "\"" : ", \"") + k + "\"";
      throw InputError("", "layers",
                       "layer \"" + name + "\" is not written by this method (it writes " + list + ")");
    }
    out.push_back(name);
  }
  if (out.empty()) throw InputError("", "layers", "must name at least one layer");
  return out;
}

bool wants(const std::vector<std::string>& layers, const char* name) {
  return std::find(layers.begin(), layers.end(), name) != layers.end();
}

LayerSet obscurance_layers(int width, int height, const std::vector<std::string>& layers,
                           const std::vector<float>& light, const std::vector<Vec3f>& bent) {
  LayerSet out;
  out.width = width;
  out.height = height;
  for (const std::string& name : layers) {
    if (name == "bent_normal") {
      Layer& l = out.add(name, xyz_channels());
      for (std::size_t t = 0; t < bent.size(); ++t)
        l.data[3 * t] = bent[t].x, l.data[3 * t + 1] = bent[t].y, l.data[3 * t + 2] = bent[t].z;
    } else {
      out.add(name, mono_channels()).data = light;
    }
  }
  return out;
}

}  // namespace hfbake
