#include "job/parameter_sweep.hpp"

#include <algorithm>
#include <map>
#include <set>

#include "job/embedded_schemas.hpp"

namespace hfbake {
namespace {

// Every embedded schema, parsed, by its path relative to schemas/ ("methods/p1.schema.json").
const std::map<std::string, nlohmann::json>& schema_documents() {
  static const std::map<std::string, nlohmann::json> docs = [] {
    std::map<std::string, nlohmann::json> m;
    for (const EmbeddedSchema& s : embedded_schemas())
      m.emplace(std::string(s.path), nlohmann::json::parse(s.text.begin(), s.text.end(), nullptr, false));
    return m;
  }();
  return docs;
}

// Follows "$ref" ("file#/pointer" relative to `file`'s folder, or "#/pointer" in `file`) to the schema it
// names; null when it cannot be resolved.
const nlohmann::json* resolve(const nlohmann::json* schema, std::string file, int depth = 0) {
  while (schema && schema->is_object() && schema->contains("$ref") && (*schema)["$ref"].is_string()) {
    if (++depth > 8) return nullptr;
    const std::string ref = (*schema)["$ref"].get<std::string>();
    const auto hash = ref.find('#');
    const std::string target = ref.substr(0, hash),
                      pointer = hash == std::string::npos ? "" : ref.substr(hash + 1);
    if (!target.empty()) {
      const auto slash = file.rfind('/');
      file = (slash == std::string::npos ? "" : file.substr(0, slash + 1)) + target;
    }
    const auto& docs = schema_documents();
    const auto it = docs.find(file);
    if (it == docs.end()) return nullptr;
    try {
      schema = &it->second.at(nlohmann::json::json_pointer(pointer));
    } catch (const std::exception&) {
      return nullptr;
    }
  }
  return schema;
}

// 1: the schema accepts numbers only; 0: not a number; -1: it also accepts arrays (never a sweep).
int numeric_kind(const nlohmann::json* schema, const std::string& file, int depth = 0) {
  schema = resolve(schema, file);
  if (!schema || !schema->is_object() || depth > 8) return 0;
  int kind = 0;
  if (schema->contains("type")) {
    const nlohmann::json& type = (*schema)["type"];
    const nlohmann::json types = type.is_array() ? type : nlohmann::json::array({type});
    for (const auto& t : types) {
      if (t == "array") return -1;
      if (t == "integer" || t == "number") kind = 1;
    }
  }
  for (const char* combinator : {"oneOf", "anyOf"})
    if (schema->contains(combinator) && (*schema)[combinator].is_array())
      for (const auto& alternative : (*schema)[combinator]) {
        const int k = numeric_kind(&alternative, file, depth + 1);
        if (k < 0) return -1;
        kind = std::max(kind, k);
      }
  return kind;
}

// True when `method`'s schema declares `property` a number (and never an array).
bool sweepable(const std::string& method, const std::string& property) {
  const std::string file = "methods/" + method + ".schema.json";
  if (property.find_first_of("/~") != std::string::npos) return false;
  const auto& docs = schema_documents();
  const auto it = docs.find(file);
  if (it == docs.end() || !it->second.is_object()) return false;
  const nlohmann::json::json_pointer p("/properties/" + property);
  return it->second.contains(p) && numeric_kind(&it->second.at(p), file) == 1;
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
  auto swept_keys = [](const nlohmann::json& e) {
    std::vector<std::string> swept;
    if (e.is_object() && e.contains("method") && e["method"].is_string())
      for (const auto& [key, value] : e.items())
        if (key != "method" && all_numbers(value) && sweepable(e["method"].get<std::string>(), key))
          swept.push_back(key);
    return swept;
  };
  // The count first: entries, each sweep as many runs as it lists values.
  std::size_t runs = 0;
  for (std::size_t i = 0; i < bake.size(); ++i) {
    const std::vector<std::string> swept = swept_keys(bake[i]);
    const std::size_t n = swept.size() == 1 ? bake[i][swept.front()].size() : 1;
    if (runs + n > kMaxBakeEntries) {
      const std::string where = "/bake/" + std::to_string(i) + (swept.size() == 1 ? "/" + swept.front() : "");
      r.errors.push_back(where + ": the job would bake " + std::to_string(runs + n) + "+ entries" +
                         (swept.size() == 1 ? " with this sweep" : "") + "; a job bakes at most " +
                         std::to_string(kMaxBakeEntries) + " (sweeps expanded)");
      r.too_many = true;
      return r;
    }
    runs += n;
  }
  nlohmann::json expanded = nlohmann::json::array();
  for (std::size_t i = 0; i < bake.size(); ++i) {
    const nlohmann::json& e = bake[i];
    const std::string ptr = "/bake/" + std::to_string(i);
    const std::vector<std::string> swept = swept_keys(e);
    if (swept.size() > 1) {
      std::string names;
      for (const std::string& s : swept) names += (names.empty() ? "" : ", ") + s;
      r.errors.push_back(ptr + ": sweep one parameter per bake entry (lists given for " + names + ")");
      r.refused.push_back(expanded.size());
    }
    if (swept.size() != 1) {
      expanded.push_back(e);
      r.origins.push_back({i, "", 0, nullptr});
      continue;
    }
    const std::string& key = swept.front();
    // Values compared as what they are: 3 and 3.0 are one number (two runs of the same bake).
    std::map<std::string, std::size_t> seen;  // the value -> where it first stands
    for (std::size_t k = 0; k < e[key].size(); ++k) {
      const nlohmann::json& v = e[key][k];
      const std::string same = v.is_number() ? nlohmann::json(v.get<double>()).dump() : v.dump();
      if (const auto [at, fresh] = seen.emplace(same, k); !fresh)
        r.errors.push_back(ptr + "/" + key + "/" + std::to_string(k) + ": " + v.dump() +
                           " is listed twice in the sweep (first at " + ptr + "/" + key + "/" +
                           std::to_string(at->second) + ")");
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
