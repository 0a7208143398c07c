#include "job/parameter_sweep.hpp"

#include <map>
#include <set>

#include "job/embedded_schemas.hpp"

namespace hfbake {
namespace {

// The parsed method schemas, keyed by method name ("p1" for methods/p1.schema.json).
const std::map<std::string, nlohmann::json>& method_schemas() {
  static const std::map<std::string, nlohmann::json> schemas = [] {
    std::map<std::string, nlohmann::json> m;
    const std::string prefix = "methods/", suffix = ".schema.json";
    for (const EmbeddedSchema& s : embedded_schemas()) {
      const std::string path(s.path);
      if (path.rfind(prefix, 0) != 0 || path.size() <= prefix.size() + suffix.size() ||
          path.compare(path.size() - suffix.size(), suffix.size(), suffix) != 0)
        continue;
      const std::string method = path.substr(prefix.size(), path.size() - prefix.size() - suffix.size());
      m.emplace(method, nlohmann::json::parse(s.text.begin(), s.text.end(), nullptr, false));
    }
    return m;
  }();
  return schemas;
}

bool is_numeric_type(const nlohmann::json& type) {
  if (type.is_string()) return type == "integer" || type == "number";
  if (type.is_array()) {
    for (const auto& t : type)
      if (t == "array") return false;
    for (const auto& t : type)
      if (t == "integer" || t == "number") return true;
  }
  return false;
}

// True when `method`'s schema declares `property` a scalar number.
bool sweepable(const std::string& method, const std::string& property) {
  const auto& schemas = method_schemas();
  const auto it = schemas.find(method);
  if (it == schemas.end() || !it->second.is_object()) return false;
  const nlohmann::json::json_pointer p("/properties/" + property + "/type");
  return it->second.contains(p) && is_numeric_type(it->second.at(p));
}

bool all_numbers(const nlohmann::json& a) {
  if (!a.is_array() || a.empty()) return false;
  for (const auto& v : a)
    if (!v.is_number()) return false;
  return true;
}

}  // namespace

std::string sweep_stem_suffix(const std::string& parameter, const nlohmann::json& value) {
  return parameter + value.dump();  // integers print as integers, numbers in their shortest form
}

SweepExpansion expand_parameter_sweeps(const nlohmann::json& doc) {
  SweepExpansion r;
  r.doc = doc;
  if (!doc.is_object() || !doc.contains("bake") || !doc["bake"].is_array()) return r;
  const nlohmann::json& bake = doc["bake"];
  nlohmann::json expanded = nlohmann::json::array();
  for (std::size_t i = 0; i < bake.size(); ++i) {
    const nlohmann::json& e = bake[i];
    const std::string ptr = "/bake/" + std::to_string(i);
    std::vector<std::string> swept;
    if (e.is_object() && e.contains("method") && e["method"].is_string())
      for (const auto& [key, value] : e.items())
        if (key != "method" && all_numbers(value) && sweepable(e["method"].get<std::string>(), key))
          swept.push_back(key);
    if (swept.size() > 1) {
      std::string names;
      for (const std::string& s : swept) names += (names.empty() ? "" : ", ") + s;
      r.errors.push_back(ptr + ": sweep one parameter per bake entry (lists given for " + names + ")");
    }
    if (swept.size() != 1) {
      expanded.push_back(e);
      r.origins.push_back({i, "", 0, nullptr});
      continue;
    }
    const std::string& key = swept.front();
    std::set<std::string> seen;
    for (std::size_t k = 0; k < e[key].size(); ++k) {
      const nlohmann::json& v = e[key][k];
      if (!seen.insert(v.dump()).second)
        r.errors.push_back(ptr + "/" + key + "/" + std::to_string(k) + ": " + v.dump() +
                           " is listed twice in the sweep");
      nlohmann::json run = e;
      run[key] = v;
      expanded.push_back(std::move(run));
      r.origins.push_back({i, key, k, v});
    }
  }
  r.doc["bake"] = std::move(expanded);
  return r;
}

std::string original_pointer(const std::string& pointer, const std::vector<SweepOrigin>& origins) {
  const std::string prefix = "/bake/";
  if (pointer.rfind(prefix, 0) != 0) return pointer;
  const std::size_t end = pointer.find('/', prefix.size());
  const std::string index =
      pointer.substr(prefix.size(), end == std::string::npos ? end : end - prefix.size());
  if (index.empty() || index.find_first_not_of("0123456789") != std::string::npos) return pointer;
  const std::size_t k = std::stoul(index);
  if (k >= origins.size()) return pointer;
  const SweepOrigin& o = origins[k];
  std::string rest = end == std::string::npos ? "" : pointer.substr(end);
  const std::string swept = "/" + o.parameter;
  if (!o.parameter.empty() && (rest == swept || rest.rfind(swept + "/", 0) == 0))
    rest = swept + "/" + std::to_string(o.value_index) + rest.substr(swept.size());
  return prefix + std::to_string(o.entry) + rest;
}

}  // namespace hfbake
