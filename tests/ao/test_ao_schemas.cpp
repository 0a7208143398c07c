// The obscurance methods' schemas (hbao, hsao, vo and the shared keys): valid entries pass, typos and
// out-of-range values are reported at their JSON pointer; and the entry points' own parameter checks.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "job/schema_validation.hpp"
#include "methods/ao/obscurance_params.hpp"

namespace hfbake {
namespace {

// The shared falloff rule (read_falloff) on a bare object.
Falloff parse_falloff(const nlohmann::json& params) {
  Params in(params);
  return read_falloff(in);
}

// An entry as the job loader checks it: against its method's schema, pointers as in a job's first entry.
std::vector<SchemaViolation> check(const nlohmann::json& entry) {
  std::vector<SchemaViolation> v =
      validate_against_schema(entry, "methods/" + entry["method"].get<std::string>() + ".schema.json");
  for (SchemaViolation& x : v) x.pointer = "/bake/0" + x.pointer;
  return v;
}

TEST(AoSchemas, ValidEntries) {
  for (
      const char* text : {
          R"({"method": "hbao"})",
          R"({"method": "hbao", "directions": 32, "radius": 8, "falloff": "rational", "weighting": "uniform"})",
          R"({"method": "hbao", "estimator": "largest_occluder", "tangent": -0.85, "occluders": "all", "radius": 4})",
          R"({"method": "hbao", "tangent": "normal", "steps": 64, "max_distance": 100, "layers": ["ao"]})",
          R"({"method": "hsao", "radius": 16, "falloff": "linear", "steps": 32, "normal_rays": 0})",
          R"({"method": "hsao", "radius": 16, "surface": "triangles"})",
          R"({"method": "hsao", "radius": 16, "surface": "bilinear", "steps": 8})",
          R"({"method": "vo", "radius": 8, "box_height": 4, "fade": 2, "depth_layers": 1})",
      }) {
    const auto v = check(nlohmann::json::parse(text));
    EXPECT_TRUE(v.empty()) << text << ": " << (v.empty() ? "" : v[0].pointer + " " + v[0].message);
  }
}

TEST(AoSchemas, InvalidEntries) {
  struct Case {
    const char* text;
    const char* pointer;
  };
  for (const Case& c : {
           Case{R"({"method": "hbao", "radius": 0})", "/bake/0/radius"},
           Case{R"({"method": "hbao", "falloff": "gauss"})", "/bake/0/falloff"},
           Case{R"({"method": "hbao", "weighting": "cos"})", "/bake/0/weighting"},
           Case{R"({"method": "hbao", "radiu": 3})", "/bake/0"},
           Case{R"({"method": "hbao", "layers": ["horizon"]})", "/bake/0/layers/0"},
           Case{R"({"method": "hsao"})", "/bake/0"},
           Case{R"({"method": "hsao", "radius": 4, "falloff": "rational"})", "/bake/0/falloff"},
           Case{R"({"method": "hsao", "radius": 4, "surface": "quads"})", "/bake/0/surface"},
           Case{R"({"method": "vo", "radius": 4, "depth_layers": 3})", "/bake/0/depth_layers"},
           Case{R"({"method": "vo", "radius": 4, "falloff": "step"})", "/bake/0"},
       }) {
    const auto v = check(nlohmann::json::parse(c.text));
    ASSERT_FALSE(v.empty()) << c.text;
    bool found = false;
    for (const auto& x : v) found |= x.pointer.rfind(c.pointer, 0) == 0;
    EXPECT_TRUE(found) << c.text << ": first violation " << v[0].pointer << " " << v[0].message;
  }
}

TEST(AoParams, FalloffAndRadiusRules) {
  EXPECT_EQ(parse_falloff(nlohmann::json::object()).kind, FalloffKind::none);
  EXPECT_EQ(parse_falloff({{"radius", 3}}).kind, FalloffKind::step);
  EXPECT_EQ(parse_falloff({{"radius", 3}}).radius, 3);
  EXPECT_THROW(parse_falloff({{"falloff", "smooth"}}), InputError);               // no radius
  EXPECT_THROW(parse_falloff({{"falloff", "none"}, {"radius", 2}}), InputError);  // radius ignored
  const nlohmann::json uniform = {{"weighting", "uniform"}};
  Params w(uniform);
  EXPECT_THROW(read_weighting(w, false), InputError);
  const nlohmann::json horizon = {{"layers", {"horizon"}}};
  Params l(horizon);
  EXPECT_THROW(l.layers({"obscurance"}, {"obscurance"}), InputError);
}

}  // namespace
}  // namespace hfbake
