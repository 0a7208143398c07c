#include "methods/method_table.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "methods/ao/bake_ao.hpp"
#include "methods/nlp/bake_nlp.hpp"
#include "methods/p1/bake_p1.hpp"
#include "methods/p2/bake_p2.hpp"
#include "methods/relief/relief.hpp"

namespace hfbake {

std::span<const MethodInfo> method_table() {
  // One line per method.
  static const std::vector<MethodInfo> table = {
      p1_method(),       p2_method(),   nlp_method(), hbao_method(),   lsao_method(),
      farfield_method(), hsao_method(), vo_method(),  relief_method(),
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

nlohmann::json resolve_method_params(const nlohmann::json& entry, const MethodContext& context,
                                     const std::string& file, const std::string& pointer) {
  const std::string name = entry.is_object() ? entry.value("method", "") : "";
  const MethodInfo* m = find_method(name);
  if (!m)
    throw InputError(file, pointer + "/method",
                     "unknown method \"" + name + "\" (one of " + quoted_list(method_names()) + ")");
  Params in(entry, file, pointer);
  m->read(in, context);
  nlohmann::json resolved = in.resolved();
  resolved["method"] = name;
  return resolved;
}

int layer_channel_count(const std::string& layer, const nlohmann::json& resolved) {
  if (layer == "horizon" || layer == "horizon_distance" || layer == "horizon_deg")
    return resolved.value("directions", 64);
  if (layer == "sh_visibility") return 16;
  if (layer == "sh_irradiance") return 48;
  if (layer == "bent_normal" || layer == "direct" || layer == "indirect" || layer == "total" ||
      layer.rfind("indirect_b", 0) == 0)
    return 3;
  return 1;
}

}  // namespace hfbake
