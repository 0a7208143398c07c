// The method table against the schemas: the same methods, and every constraint a method's schema documents
// enforced by the method's own reader (so validate refuses it with file and pointer, and a direct call from
// code cannot get past it either).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "job/manifest.hpp"
#include "methods/method_table.hpp"

namespace hfbake {
namespace {

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::stringstream s;
  s << in.rdbuf();
  return nlohmann::json::parse(s.str());
}

const std::string kSchemas = std::string(HFBAKE_SOURCE_DIR) + "/schemas/";

TEST(MethodTable, ListsTheMethodsThatHaveASchema) {
  std::vector<std::string> table = method_names();
  std::sort(table.begin(), table.end());
  EXPECT_EQ(table, method_schema_names());
  for (const MethodInfo& m : method_table()) {
    const nlohmann::json schema = read_json(kSchemas + "methods/" + m.name + ".schema.json");
    EXPECT_EQ(schema["properties"]["method"]["const"], m.name);
    EXPECT_TRUE(m.read && m.bake && m.working_bytes) << m.name;
    EXPECT_NE(std::string(m.summary), "") << m.name;
    EXPECT_NE(std::string(m.division_note), "") << m.name;
  }
  EXPECT_EQ(find_method("nope"), nullptr);
}

MethodContext context() {
  MethodContext c;
  c.field.width = c.field.height = 64;
  c.bounces = 2;
  c.placed = true;  // a CRS places the field: sun's base entry needs no latitude
  return c;
}

// The record of what the entry's reader read (MethodConfig::resolved).
nlohmann::json resolved_params(const nlohmann::json& entry, const MethodContext& c, const std::string& file,
                               const std::string& pointer) {
  return resolve_method(entry, c, file, pointer).resolved;
}

// The smallest valid entry of each method (hsao and vo need a radius).
nlohmann::json base_entry(const std::string& method) {
  nlohmann::json e = {{"method", method}};
  if (method == "hsao" || method == "vo") e["radius"] = 2;
  if (method == "sun")
    e.update({{"start", "2026-06-21T00:00"}, {"end", "2026-06-22T00:00"}, {"utc_offset", 0}});
  return e;
}

// Follows "$ref": "obscurance_common.schema.json#/definitions/<key>", merging the local keys over it.
nlohmann::json property_schema(const nlohmann::json& p) {
  if (!p.contains("$ref")) return p;
  const std::string ref = p["$ref"];
  const auto hash = ref.find('#');
  nlohmann::json target = read_json(kSchemas + "methods/" + ref.substr(0, hash))
                              .at(nlohmann::json::json_pointer(ref.substr(hash + 1)));
  for (auto& [k, v] : p.items())
    if (k != "$ref") target[k] = v;
  return target;
}

// Values the schema refuses for one property, each with what it breaks.
std::vector<std::pair<nlohmann::json, std::string>> refused_values(const nlohmann::json& p) {
  std::vector<std::pair<nlohmann::json, std::string>> out;
  const std::string type = p.value("type", "");
  const bool integer = type == "integer";
  if (p.contains("minimum")) {
    const double m = p["minimum"];
    out.push_back({integer ? nlohmann::json(std::int64_t(m) - 1)
                           : nlohmann::json(m - 1e-3 * std::max(1.0, std::abs(m))),
                   "minimum"});
  }
  if (p.contains("exclusiveMinimum"))
    out.push_back({integer ? nlohmann::json(std::int64_t(p["exclusiveMinimum"])) : p["exclusiveMinimum"],
                   "exclusiveMinimum"});
  if (p.contains("maximum")) {
    const double m = p["maximum"];
    out.push_back({integer ? nlohmann::json(std::int64_t(m) + 1)
                           : nlohmann::json(m + 1e-3 * std::max(1.0, std::abs(m))),
                   "maximum"});
  }
  if (integer) out.push_back({1.5, "integer"});
  if (type == "number" || integer) out.push_back({"7", "type"});
  if (type == "boolean") out.push_back({"yes", "boolean"});
  if (p.contains("enum")) {
    const bool numeric = !p["enum"].empty() && p["enum"][0].is_number();
    out.push_back({numeric ? nlohmann::json(12345) : nlohmann::json("no-such-value"), "enum"});
  }
  if (type == "array") {
    out.push_back({nlohmann::json::array({"no-such-layer"}), "items"});
    out.push_back({"ao", "array"});
  }
  return out;
}

TEST(MethodTable, EveryDocumentedConstraintIsEnforcedByTheReader) {
  int checked = 0;
  for (const MethodInfo& m : method_table()) {
    const nlohmann::json schema = read_json(kSchemas + "methods/" + m.name + ".schema.json");
    const nlohmann::json base = base_entry(m.name);
    ASSERT_NO_THROW(resolved_params(base, context(), "job.json", "/bake/3")) << m.name;
    for (auto& [key, raw] : schema["properties"].items()) {
      if (key == "method") continue;
      const nlohmann::json p = property_schema(raw);
      if (p.value("type", "") == "object") {  // a nested object: each of its keys, and not an object
        for (auto& [inner, inner_raw] : p["properties"].items())
          for (const auto& [value, rule] : refused_values(property_schema(inner_raw))) {
            nlohmann::json e = base;
            e[key] = {{inner, value}};
            SCOPED_TRACE(std::string(m.name) + "." + key + "." + inner + " = " + value.dump() + " (" + rule +
                         ")");
            try {
              resolved_params(e, context(), "job.json", "/bake/3");
              ADD_FAILURE() << "accepted";
            } catch (const InputError& err) {
              EXPECT_EQ(err.where().rfind("/bake/3/" + key + "/" + inner, 0), 0u) << err.where();
            }
            ++checked;
          }
        nlohmann::json e = base;
        e[key] = 7;
        EXPECT_THROW(resolved_params(e, context(), "job.json", "/bake/3"), InputError)
            << m.name << "." << key;
        continue;
      }
      for (const auto& [value, rule] : refused_values(p)) {
        nlohmann::json e = base;
        e[key] = value;
        SCOPED_TRACE(std::string(m.name) + "." + key + " = " + value.dump() + " (" + rule + ")");
        try {
          resolved_params(e, context(), "job.json", "/bake/3");
          ADD_FAILURE() << "accepted";
        } catch (const InputError& err) {
          EXPECT_EQ(err.file(), "job.json");
          EXPECT_EQ(err.where().rfind("/bake/3/" + key, 0), 0u) << err.where();
          if (rule == "enum" && value.is_string()) {
            EXPECT_NE(std::string(err.what()).find('"'), std::string::npos) << err.what();
          }
        }
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(MethodTable, ResolvedParametersHoldTheDefaults) {
  const nlohmann::json p1 = resolved_params({{"method", "p1"}}, context(), "", "/bake/0");
  EXPECT_EQ(p1["directions"], 64);
  EXPECT_EQ(p1["normal_bins"], 0);
  EXPECT_EQ(p1["layers"], nlohmann::json({"ao", "vsky", "direct"}));
  const nlohmann::json p2 = resolved_params({{"method", "p2"}}, context(), "", "/bake/0");
  EXPECT_EQ(p2["near_radius"], 4.0);
  EXPECT_EQ(p2["bounces"], 2);  // the job's
  EXPECT_EQ(p2["senders"], "facets");
  const nlohmann::json hbao = resolved_params({{"method", "hbao"}, {"radius", 3}}, context(), "", "/bake/0");
  EXPECT_EQ(hbao["falloff"], "step");
  EXPECT_EQ(hbao["surface"], "triangles");  // the reference's surface
  EXPECT_EQ(hbao["estimator"], "segment");  // its exact slice integral
  const nlohmann::json stepped =
      resolved_params({{"method", "hbao"}, {"radius", 3}, {"step", 0.5}}, context(), "", "/bake/0");
  EXPECT_EQ(stepped["surface"], "bilinear");  // a step means the stepped march
  EXPECT_EQ(stepped["estimator"], "slab");
  const nlohmann::json farfield = resolved_params({{"method", "farfield"}}, context(), "", "/bake/0");
  EXPECT_EQ(farfield["surface"], "triangles");
  EXPECT_EQ(farfield["near_field"], 12.0);  // 1.5 intervals of 8, as the bake uses it
  EXPECT_EQ(
      resolved_params({{"method", "farfield"}, {"interval", 4}}, context(), "", "/bake/0")["near_field"],
      6.0);
  EXPECT_EQ(hbao["max_distance"], 3.0);  // the step falloff's support
  EXPECT_EQ(hbao["layers"], nlohmann::json({"obscurance", "bent_normal"}));
  const nlohmann::json plain = resolved_params({{"method", "hbao"}}, context(), "", "/bake/0");
  EXPECT_EQ(plain["layers"], nlohmann::json({"obscurance", "bent_normal", "ao"}));  // falloff none: ao too
}

TEST(MethodTable, RulesTheSchemaCannotExpress) {
  auto where = [](nlohmann::json e) {
    try {
      resolved_params(e, context(), "j.json", "/bake/1");
    } catch (const InputError& err) {
      return err.where();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(where({{"method", "p1"}, {"normal_bins", 4}}), "/bake/1/normal_bins");
  EXPECT_EQ(where({{"method", "p1"}, {"normal_bins", 7}}), "accepted");
  EXPECT_EQ(where({{"method", "p2"}, {"near_radius", 0.5}}), "/bake/1/near_radius");
  EXPECT_EQ(where({{"method", "p2"}, {"layers", {"indirect_b3"}}}), "/bake/1/layers/0");  // 2 bounces
  EXPECT_EQ(where({{"method", "p2"}, {"layers", {"indirect_b2"}}}), "accepted");
  EXPECT_EQ(where({{"method", "hbao"}, {"falloff", "none"}, {"radius", 2}}), "/bake/1/radius");
  EXPECT_EQ(where({{"method", "hbao"}, {"falloff", "smooth"}}), "/bake/1/radius");
  EXPECT_EQ(where({{"method", "lsao"}, {"radius", std::nan("")}}), "/bake/1/radius");
  EXPECT_EQ(where({{"method", "hbao"}, {"step", 1}, {"steps", 4}}), "/bake/1/steps");
  EXPECT_EQ(where({{"method", "hbao"}, {"tangent", -0.5}}), "/bake/1/tangent");  // not largest_occluder
  EXPECT_EQ(where({{"method", "hbao"}, {"radius", 2}, {"layers", {"ao"}}}), "/bake/1/layers");
  EXPECT_EQ(where({{"method", "vo"}, {"radius", 2}, {"depth_layers", 3}}), "/bake/1/depth_layers");
  EXPECT_EQ(where({{"method", "vo"}, {"radius", 500}}), "/bake/1/radius");  // footprint beyond the field
  EXPECT_EQ(where({{"method", "hsao"}}), "/bake/1/radius");
  EXPECT_EQ(where({{"method", "hsao"}, {"radius", 2}, {"falloff", "exponential"}}), "/bake/1/falloff");
  EXPECT_EQ(where({{"method", "farfield"}, {"weighting", "uniform"}}), "/bake/1/weighting");
  EXPECT_EQ(where({{"method", "p1"}, {"layers", {"ao", "ao"}}}), "/bake/1/layers/1");
  EXPECT_EQ(where({{"method", "warp"}}), "/bake/1/method");
}

// A method receives its typed config (MethodConfig) and reads the job's JSON only through its reader's
// Params getters: no file of a method's folder names the JSON library, reads a value raw or reads the
// reader's record back.
TEST(MethodTable, NoMethodFileReadsJson) {
  namespace fs = std::filesystem;
  int files = 0;
  for (const auto& f : fs::recursive_directory_iterator(std::string(HFBAKE_SOURCE_DIR) + "/baker/methods")) {
    if (!f.is_regular_file() || f.path().parent_path().filename() == "methods") continue;  // the table
    const std::string ext = f.path().extension().string();
    if (ext != ".cpp" && ext != ".hpp") continue;
    std::ifstream in(f.path());
    std::stringstream text;
    text << in.rdbuf();
    for (const char* forbidden : {"nlohmann", "json::", ".raw(", "resolved()"})
      EXPECT_EQ(text.str().find(forbidden), std::string::npos) << f.path() << " has " << forbidden;
    ++files;
  }
  EXPECT_GT(files, 40);
}

}  // namespace
}  // namespace hfbake
