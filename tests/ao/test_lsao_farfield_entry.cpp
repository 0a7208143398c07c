// The lsao and farfield entry points: schemas (valid entries pass, typos and bad values are reported at
// their pointer), layers, parameter errors, determinism and cancellation.
#include <gtest/gtest.h>

#include <atomic>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "field/procedural.hpp"
#include "job/schema_validation.hpp"
#include "methods/ao/bake_ao.hpp"

namespace hfbake {
namespace {

std::vector<SchemaViolation> check(const char* text) {
  // As the job loader checks an entry: against its method's schema, pointers as in a job's first entry.
  const nlohmann::json entry = nlohmann::json::parse(text);
  std::vector<SchemaViolation> v =
      validate_against_schema(entry, "methods/" + entry["method"].get<std::string>() + ".schema.json");
  for (SchemaViolation& x : v) x.pointer = "/bake/0" + x.pointer;
  return v;
}

TEST(LsaoFarfieldSchemas, ValidEntries) {
  for (
      const char* text : {
          R"({"method": "lsao"})",
          R"({"method": "lsao", "directions": 32, "radius": 8, "falloff": "rational", "weighting": "uniform"})",
          R"({"method": "lsao", "radius": 8, "tangent": -1, "layers": ["obscurance"]})",
          R"({"method": "lsao", "radius": 8, "falloff": "smooth", "tangent": "normal"})",
          R"({"method": "lsao", "radius": 8, "surface": "bilinear", "near_radius": 0})",
          R"({"method": "lsao", "radius": 8, "surface": "triangles", "near_radius": 2.5})",
          R"({"method": "farfield"})",
          R"({"method": "farfield", "radius": 30, "falloff": "smooth", "interval": 4, "near_field": 10})",
          R"({"method": "farfield", "sector_average": false, "split": false, "growth": 0.5, "weighting": "cosine"})",
      }) {
    const auto v = check(text);
    EXPECT_TRUE(v.empty()) << text << ": " << (v.empty() ? "" : v[0].pointer + " " + v[0].message);
  }
}

TEST(LsaoFarfieldSchemas, InvalidEntries) {
  struct Case {
    const char* text;
    const char* pointer;
  };
  for (const Case& c : {
           Case{R"({"method": "lsao", "tangent": 0.5})", "/bake/0/tangent"},
           Case{R"({"method": "lsao", "tangent": "up"})", "/bake/0/tangent"},
           Case{R"({"method": "lsao", "layers": ["ao"]})", "/bake/0/layers/0"},
           Case{R"({"method": "lsao", "near_radius": -1})", "/bake/0/near_radius"},
           Case{R"({"method": "lsao", "surface": "quads"})", "/bake/0/surface"},
           Case{R"({"method": "farfield", "layers": ["bent"]})", "/bake/0/layers/0"},
           Case{R"({"method": "lsao", "radus": 3})", "/bake/0"},
           Case{R"({"method": "farfield", "weighting": "uniform"})", "/bake/0/weighting"},
           Case{R"({"method": "farfield", "interval": 0})", "/bake/0/interval"},
           Case{R"({"method": "farfield", "growth": 100})", "/bake/0/growth"},
           Case{R"({"method": "farfield", "split": 1})", "/bake/0/split"},
       }) {
    const auto v = check(c.text);
    ASSERT_FALSE(v.empty()) << c.text;
    bool found = false;
    for (const auto& x : v) found |= x.pointer.rfind(c.pointer, 0) == 0;
    EXPECT_TRUE(found) << c.text << ": first violation " << v[0].pointer << " " << v[0].message;
  }
}

Scene small_scene() {
  ProceduralSpec s;
  s.kind = ProceduralKind::fractal;
  s.width = 48;
  s.height = 40;
  Scene sc;
  sc.field = make_procedural(s, 0.5, Wrap::clamp);
  sc.normals = compute_normals(sc.field);
  return sc;
}

TEST(LsaoFarfieldEntry, LayersSizesAndErrors) {
  const Scene sc = small_scene();
  for (const char* method : {"lsao", "farfield"}) {
    auto bake = [&](const Scene& scene, const nlohmann::json& p, const RunControl& rc) {
      return bake_method(method, scene, p, rc);
    };
    const nlohmann::json params = {{"directions", 8}, {"radius", 4.0}, {"falloff", "rational"}};
    const LayerSet a = bake(sc, params, RunControl{});
    EXPECT_EQ(a.width, 48);
    EXPECT_EQ(a.height, 40);
    const Layer* o = a.find("obscurance");
    ASSERT_NE(o, nullptr);
    ASSERT_EQ(o->data.size(), 48u * 40u);
    for (float v : o->data) {
      EXPECT_GE(v, 0.0f);
      EXPECT_LE(v, 1.0f);
    }
    const Layer* b = a.find("bent_normal");  // a default layer: unit vectors in the upper hemisphere
    ASSERT_NE(b, nullptr);
    ASSERT_EQ(b->data.size(), 3u * 48u * 40u);
    for (std::size_t t = 0; t < 48u * 40u; ++t) {
      const double x = b->data[3 * t], y = b->data[3 * t + 1], z = b->data[3 * t + 2];
      EXPECT_NEAR(x * x + y * y + z * z, 1.0, 1e-5);
      EXPECT_GT(z, 0.0);
    }
    const LayerSet again = bake(sc, params, RunControl{});  // deterministic
    EXPECT_EQ(again.find("obscurance")->data, o->data);
    EXPECT_EQ(again.find("bent_normal")->data, b->data);
    nlohmann::json only = params;
    only["layers"] = {"obscurance"};
    const LayerSet c = bake(sc, only, RunControl{});
    EXPECT_EQ(c.layers.size(), 1u);
    EXPECT_EQ(c.find("obscurance")->data, o->data);
    try {
      bake(sc, {{"layers", {"ao"}}}, RunControl{});
      ADD_FAILURE() << "unknown layer accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "/layers/0");
    }
    try {
      bake(sc, {{"falloff", "smooth"}}, RunControl{});  // a falloff needs a radius
      ADD_FAILURE() << "falloff without radius accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "/radius");
    }
    std::atomic<bool> cancel{true};
    RunControl rc;
    rc.cancel = &cancel;
    EXPECT_THROW(bake(sc, params, rc), Cancelled);
  }
  EXPECT_THROW(bake_method("farfield", sc, {{"weighting", "uniform"}}, RunControl{}), InputError);
}

}  // namespace
}  // namespace hfbake
