// p2's `subdivide` (docs/methods/p2.md, rough ground): the field baked subdivided on its triangulation and
// read at its original texels. Against the Embree reference on ground rough at the texel scale under a sun
// (closer than without), on a plane (the same values), determinism, the farm's stages (the same bits) and
// the parameter's checks.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "core/direction_blocks.hpp"
#include "core/error.hpp"
#include "env/environment.hpp"
#include "farm/merge_blocks.hpp"
#include "field/procedural.hpp"
#include "field/scene.hpp"
#include "methods/p2/bake_p2.hpp"
#include "p2_test_scenes.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake {
namespace {

// Uniform sky `sky`, albedo 0.5, two bounces, and a sun at `sun_deg` elevation (0: none).
Scene make_scene(HeightField f, float sky, double sun_deg) {
  Scene s;
  s.name = "test";
  s.field = std::move(f);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{0.5f, 0.5f, 0.5f});
  s.environment = make_uniform_environment({sky, sky, sky});
  s.bounces = 2;
  if (sun_deg > 0) {
    const double e = sun_deg * kPi / 180, a = 135 * kPi / 180;
    DirectionalLight sun;
    sun.direction = {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
    sun.angular_diameter = 0.0093;
    sun.irradiance = {3, 3, 3};
    s.lights.push_back(sun);
  }
  return s;
}

nlohmann::json entry(int subdivide, int K = 64) {
  return {{"method", "p2"},
          {"directions", K},
          {"subdivide", subdivide},
          {"layers", {"indirect_b1", "indirect_b2", "direct", "indirect"}}};
}

double layer_mean(const LayerSet& l, const std::string& name, int crop) {
  const Layer* x = l.find(name);
  EXPECT_NE(x, nullptr) << name;
  if (!x) return 0;
  double m = 0;
  int n = 0;
  for (int j = crop; j < l.height - crop; ++j)
    for (int i = crop; i < l.width - crop; ++i, ++n) m += x->data[3 * (std::size_t(j) * l.width + i) + 1];
  return m / n;
}

// White noise of 1.8 texels under a sun at 35 degrees and a dim sky: p2 takes each facet's light at its
// corners, which on such ground reads the bounces low (docs/methods/p2.md); subdivided twice, the facets'
// light is taken at four times as many points of the same surface, and the bias against the reference (the
// original field, its receivers at the original texels) shrinks.
// Measured (K = 64, 256 samples, the border ring cropped): indirect_b1 -8.8 % at subdivide 1, -2.5 % at 2;
// indirect_b2 -16.8 % and -4.6 %.
TEST(P2Subdivide, WhiteNoiseUnderASunIsCloserToTheReference) {
  const HeightField f = white_noise_field(36);
  const Scene s = make_scene(f, 0.2f, 35);
  ReferenceOptions o;
  o.samples = 256;
  o.layers = {"indirect_b1", "indirect_b2"};
  const LayerSet ref = bake_reference(s, o, RunControl{});
  const LayerSet one = bake_method("p2", s, entry(1), RunControl{});
  const LayerSet two = bake_method("p2", s, entry(2), RunControl{});
  ASSERT_EQ(two.width, f.width);
  ASSERT_EQ(two.height, f.height);
  for (const char* layer : {"indirect_b1", "indirect_b2"}) {
    const double mr = layer_mean(ref, layer, 4);  // the border ring reads dark in the reference
    const double b1 = layer_mean(one, layer, 4) / mr - 1, b2 = layer_mean(two, layer, 4) / mr - 1;
    std::printf("%s: reference mean %.4f, subdivide 1 %+.1f %%, subdivide 2 %+.1f %%\n", layer, mr, 100 * b1,
                100 * b2);
    EXPECT_LT(std::fabs(b2), std::fabs(b1)) << layer;
    EXPECT_LT(std::fabs(b2), std::string(layer) == "indirect_b1" ? 0.05 : 0.08) << layer;
  }
  // Direct light at the original texels: the same horizons (P1's are exact on the surface) at the same
  // normals (the original texels keep theirs), so the same values to rounding.
  const Layer *d1 = one.find("direct"), *d2 = two.find("direct");
  ASSERT_TRUE(d1 && d2);
  for (std::size_t t = 0; t < d1->data.size(); ++t)
    ASSERT_NEAR(d2->data[t], d1->data[t], 1e-4 * (1e-3 + d1->data[t])) << "value " << t;
}

// On a plane every texel's lobe meets the sky alone: p2 is exact there, and the subdivided bake gives the
// same direct light (the original texels keep their normals) and no indirect light, at the clamp border too.
TEST(P2Subdivide, APlaneGivesTheSameValues) {
  HeightField f;
  f.width = 20, f.height = 14, f.texel_size = 0.7;
  f.z.resize(f.texel_count());
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) f.z[f.index(i, j)] = float(0.4 * i * f.dx() - 0.25 * j * f.dy());
  const Scene s = make_scene(f, 0.5f, 35);
  const LayerSet one = bake_method("p2", s, entry(1, 16), RunControl{});
  for (int sub : {2, 4}) {
    const LayerSet fine = bake_method("p2", s, entry(sub, 16), RunControl{});
    const Layer *d1 = one.find("direct"), *d2 = fine.find("direct"), *i2 = fine.find("indirect");
    ASSERT_TRUE(d1 && d2 && i2);
    ASSERT_EQ(d1->data.size(), d2->data.size());
    for (std::size_t t = 0; t < d1->data.size(); ++t) {
      ASSERT_NEAR(d2->data[t], d1->data[t], 1e-5 * d1->data[t]) << "subdivide " << sub << ", value " << t;
      ASSERT_LT(std::fabs(i2->data[t]), 1e-6f);
    }
  }
}

// near_radius keeps its world length: a subdivided bake with near_radius r is the fine field baked with
// near_radius s r (its receivers reading P1's horizons at the scene's normals) and read at the original
// texels, bit for bit; with r fine texels instead, the near field is half as long and the result differs.
TEST(P2Subdivide, NearRadiusKeepsItsWorldLength) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = spec.height = 24;
  spec.seed = 4;
  spec.amplitude = 6;
  const Scene s = make_scene(make_procedural(spec, 1.0, Wrap::clamp), 1.0f, 35);
  nlohmann::json e = entry(2, 16);
  e["near_radius"] = 2;
  const LayerSet baked = bake_method("p2", s, e, RunControl{});
  const Scene fine = p2_subdivided_scene(s, 2);
  auto by_hand = [&](double fine_near_radius) {
    P2Params p;
    p.directions = 16;
    p.bounces = 2;
    p.near_radius = fine_near_radius;
    p.scene_normals = true;
    p.layers = {"indirect_b1", "indirect_b2", "direct", "indirect"};
    return p2_original_texels(p2_layers(p, 2, compute_p2(fine, p, RunControl{})), s.field, 2);
  };
  const LayerSet world = by_hand(4), texels = by_hand(2);
  const Layer *b = baked.find("indirect"), *w = world.find("indirect"), *t = texels.find("indirect");
  ASSERT_TRUE(b && w && t);
  EXPECT_EQ(b->data, w->data);
  EXPECT_NE(b->data, t->data);
}

// A smooth field, where p2 without subdividing is already close to exact: the bounces agree within 0.5 %.
TEST(P2Subdivide, ASmoothFieldGivesTheSameBounces) {
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    ProceduralSpec spec;
    spec.kind = ProceduralKind::sines;
    spec.width = spec.height = 48;
    spec.seed = 2;
    spec.feature_size = 24;
    const Scene s = make_scene(make_procedural(spec, 1.0, wrap), 1.0f, 0);
    const LayerSet one = bake_method("p2", s, entry(1, 32), RunControl{});
    const LayerSet two = bake_method("p2", s, entry(2, 32), RunControl{});
    for (const char* layer : {"indirect_b1", "indirect_b2", "direct"}) {
      const double m1 = layer_mean(one, layer, 0), m2 = layer_mean(two, layer, 0);
      std::printf("sines, %s, %s: subdivide 1 %.5f, 2 %.5f (%+.2f %%)\n",
                  wrap == Wrap::clamp ? "clamp" : "repeat", layer, m1, m2, 100 * (m2 / m1 - 1));
      EXPECT_NEAR(m2 / m1, 1.0, 0.005) << layer;
    }
  }
}

TEST(P2Subdivide, SameBitsForAnyThreadCount) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = spec.height = 24;
  const Scene s = make_scene(make_procedural(spec, 1.0, Wrap::clamp), 1.0f, 30);
  LayerSet one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = bake_method("p2", s, entry(2, 8), RunControl{});
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = bake_method("p2", s, entry(2, 8), RunControl{});
  }
  for (std::size_t l = 0; l < one.layers.size(); ++l)
    for (std::size_t i = 0; i < one.layers[l].data.size(); ++i)
      ASSERT_EQ(one.layers[l].data[i], two.layers[l].data[i]);
}

// The farm's stages and their direction blocks (MethodInfo::bake_stage, bake_stage_block), whose files are
// the job field's size, give bake's bits.
TEST(P2Subdivide, TheFarmsStagesGiveTheBakesBits) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = 20, spec.height = 15;
  const Scene s = make_scene(make_procedural(spec, 1.0, Wrap::clamp), 1.0f, 30);
  const MethodConfig config = read_method_config("p2", entry(2, 8), scene_method_context(s));
  const MethodInfo& m = *config.method;
  const LayerSet whole = m.bake(s, config, RunControl{});
  LayerSet staged, blocked;
  for (int stage = 0; stage < m.stages(config); ++stage) {
    staged = m.bake_stage(s, config, stage, std::move(staged), RunControl{});
    EXPECT_EQ(staged.width, s.field.width);
    LayerSet sums;
    for (int b = 0; b < m.stage_blocks(config, stage); ++b) {
      LayerSet before = blocked;
      add_direction_block(sums, m.bake_stage_block(s, config, stage, b, std::move(before), RunControl{}));
    }
    blocked = m.finish_stage_blocks(s, config, stage, std::move(blocked), std::move(sums), RunControl{});
  }
  for (const LayerSet* last : {&staged, &blocked}) {
    const LayerSet out = m.finish_stages(s, config, LayerSet(*last), RunControl{});
    ASSERT_EQ(out.layers.size(), whole.layers.size());
    for (std::size_t l = 0; l < out.layers.size(); ++l)
      for (std::size_t i = 0; i < out.layers[l].data.size(); ++i)
        ASSERT_EQ(out.layers[l].data[i], whole.layers[l].data[i]) << out.layers[l].name;
  }
}

TEST(P2Subdivide, OnlyOneTwoOrFour) {
  EXPECT_EQ(read_method_config("p2", {{"method", "p2"}}, {}).get<P2Params>().subdivide, 1);
  EXPECT_EQ(read_method_config("p2", {{"method", "p2"}, {"subdivide", 4}}, {}).get<P2Params>().subdivide, 4);
  for (int bad : {0, 3, 5, 8}) {
    try {
      read_method_config("p2", {{"method", "p2"}, {"subdivide", bad}}, {});
      ADD_FAILURE() << "subdivide " << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "/subdivide") << e.line();
    }
  }
}

}  // namespace
}  // namespace hfbake
