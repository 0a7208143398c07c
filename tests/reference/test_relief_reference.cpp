// The reference for relief's layers (reference/relief_reference.hpp) against closed forms: a plane (every
// point of it at the plane's own elevation angle, up and down alike), a cone's apex, and a wall that counts
// only inside the search radius; and the layers added for the first relief entry with its settings.
#include <gtest/gtest.h>

#include <cmath>

#include "core/azimuth.hpp"
#include "field/procedural.hpp"
#include "reference/relief_reference.hpp"

namespace hfbake {
namespace {

constexpr double kDeg = kPi / 180.0;

TEST(ReliefReference, PlaneSeesItsOwnSlopeUpAndDown) {
  ProceduralSpec p;
  p.kind = ProceduralKind::slope;
  p.width = p.height = 31;
  p.angle_deg = 30;
  p.aspect_deg = 0;  // faces +x: falls towards +x
  const HeightField f = make_procedural(p, 1.0, Wrap::clamp);
  ReliefReferenceSettings s;
  s.directions = 8;
  s.search_radius = 6;
  const ReliefHorizons h = trace_relief_horizons(f, s, true, {});
  const std::size_t t = f.index(15, 15);
  for (int k = 0; k < 8; ++k) {
    // The plane's elevation along phi_k: tan e = -tan(30) cos(phi_k) (falls towards +x).
    const double truth = std::atan(-std::tan(30 * kDeg) * std::cos(2 * kPi * k / 8));
    EXPECT_NEAR(h.up[t * 8 + k], truth, 1e-5) << k;
    EXPECT_NEAR(h.down[t * 8 + k], truth, 1e-5) << k;
  }
}

TEST(ReliefReference, ConeApexAndAWallInsideAndOutsideTheRadius) {
  ProceduralSpec p;
  p.kind = ProceduralKind::cone;
  p.width = p.height = 21;
  p.angle_deg = 30;
  const HeightField cone = make_procedural(p, 1.0, Wrap::clamp);
  ReliefReferenceSettings s;
  s.directions = 4;  // the axes: the cone's triangulated flanks are exact lines there
  s.search_radius = 5;
  const ReliefHorizons c = trace_relief_horizons(cone, s, true, {});
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(c.up[cone.index(10, 10) * 4 + k], -30 * kDeg, 2e-3) << k;
    EXPECT_NEAR(c.down[cone.index(10, 10) * 4 + k], -30 * kDeg, 2e-3) << k;
  }

  // Flat ground with a 5-high block from column 30 on: along +x from (20, 20) the ramp between columns 29
  // and 30 rises from d = 9 to d = 10.
  HeightField f;
  f.width = f.height = 41;
  f.texel_size = 1;
  f.z.assign(41 * 41, 0.0f);
  for (int j = 0; j < 41; ++j)
    for (int i = 30; i < 41; ++i) f.z[f.index(i, j)] = 5;
  const std::size_t t = f.index(20, 20);
  for (auto [radius, truth] :
       {std::pair{8.0, 0.0}, std::pair{9.5, std::atan(2.5 / 9.5)}, std::pair{12.0, std::atan(5.0 / 10.0)}}) {
    s.search_radius = radius;
    const ReliefHorizons h = trace_relief_horizons(f, s, true, {});
    EXPECT_NEAR(h.up[t * 4 + 0], truth, 1e-5) << "radius " << radius;  // towards the block
    EXPECT_NEAR(h.up[t * 4 + 2], 0.0, 1e-5) << "radius " << radius;    // flat the other way
    EXPECT_NEAR(h.down[t * 4 + 0], 0.0, 1e-5) << "radius " << radius;  // the flat part is the lowest
  }
}

// On a clamp field's border looking along it, the ray runs in the plane of the mesh's outer edges; the
// horizon is the border's own polyline, cut at the search radius. A 50-high ridge on row 0 only (row 1 is
// flat ground), seen from (20, 0) along +x: the ramp between columns 29 and 30, exactly (to the receiver's
// lift), up and down; and from the ridge's far end (40, 0) back along it.
TEST(ReliefReference, AlongTheBorderTheBorderRowCutAtTheRadius) {
  HeightField f;
  f.width = f.height = 41;
  f.texel_size = 1;
  f.z.assign(41 * 41, 0.0f);
  for (int i = 30; i < 41; ++i) f.z[f.index(i, 0)] = 50;
  ReliefReferenceSettings s;
  s.directions = 4;  // +x, +y, -x, -y
  const std::size_t t = f.index(20, 0), e = f.index(40, 0);
  for (auto [radius, truth] :
       {std::pair{8.0, 0.0}, std::pair{9.5, std::atan(25 / 9.5)}, std::pair{9.75, std::atan(37.5 / 9.75)},
        std::pair{12.0, std::atan(50 / 10.0)}}) {
    s.search_radius = radius;
    const ReliefHorizons h = trace_relief_horizons(f, s, true, {});
    EXPECT_NEAR(h.up[t * 4 + 0], truth, 2e-5) << "radius " << radius;
    EXPECT_NEAR(h.up[t * 4 + 2], 0.0, 2e-5) << "radius " << radius;
    EXPECT_NEAR(h.down[t * 4 + 0], 0.0, 2e-5) << "radius " << radius;
    EXPECT_NEAR(h.down[e * 4 + 2], radius < 11 ? 0.0 : -std::atan(50 / 11.0), 2e-5) << "radius " << radius;
    EXPECT_EQ(h.up[t * 4 + 3], 0.0) << "out of the field";
  }
}

TEST(ReliefReference, AddedForTheFirstReliefEntryWithItsSettings) {
  ProceduralSpec p;
  p.kind = ProceduralKind::flat;
  p.width = p.height = 9;
  const HeightField f = make_procedural(p, 1.0, Wrap::clamp);
  LayerSet relief;
  relief.width = relief.height = 9;
  ReliefSettings settings;
  settings.directions = 4;
  settings.search_radius = 3.0;
  settings.compass = true;
  relief.add("svf", {"Y"});
  relief.add("openness_negative", {"Y"});
  relief.add("horizon_deg", indexed_channels(4));
  LayerSet reference;
  reference.width = reference.height = 9;
  add_reference_relief(f, settings, relief, reference, {});
  ASSERT_TRUE(reference.find("svf") && reference.find("openness_negative") && reference.find("horizon_deg"));
  EXPECT_FALSE(reference.find("openness_positive"));  // not baked
  for (std::size_t t = 0; t < 81; ++t) {  // flat ground: svf 1, openness 90, horizons 0 (borders included)
    EXPECT_NEAR(reference.find("svf")->data[t], 1.0, 1e-6) << t;
    EXPECT_NEAR(reference.find("openness_negative")->data[t], 90.0, 1e-3) << t;
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(reference.find("horizon_deg")->data[t * 4 + k], 0.0, 1e-3);
  }
  std::string record;
  for (const auto& [k, v] : reference.attributes)
    if (k == kReliefReferenceAttribute) record = v;
  EXPECT_EQ(
      nlohmann::json::parse(record),
      nlohmann::json::parse(R"({"directions": 4, "search_radius": 3.0, "azimuth_convention": "compass"})"));
}

}  // namespace
}  // namespace hfbake
