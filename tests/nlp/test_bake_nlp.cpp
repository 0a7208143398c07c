// The nlp method end to end on analytic fields: flat, trench, slope; against closed forms.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "core/error.hpp"
#include "field/procedural.hpp"
#include "methods/nlp/bake_nlp.hpp"
#include "methods/nlp/horizon_march.hpp"
#include "methods/nlp/pyramid.hpp"
#include "methods/nlp/sh.hpp"

namespace hfbake {
namespace {

Scene make_scene(ProceduralSpec spec, Wrap wrap, Rgb sky, float albedo = 0.5f) {
  Scene s;
  s.field = make_procedural(spec, 1.0, wrap);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{albedo, albedo, albedo});
  s.environment = make_uniform_environment(sky);
  s.bounces = 1;
  return s;
}

const float* texel(const LayerSet& ls, const char* layer, int i, int j) {
  const Layer* l = ls.find(layer);
  EXPECT_NE(l, nullptr);
  return l->data.data() + (std::size_t(j) * ls.width + i) * l->channel_count();
}

TEST(NlpBake, FlatFieldSeesTheUpperHemisphere) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::flat;
  spec.width = spec.height = 33;
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    const Scene s = make_scene(spec, wrap, Rgb{0.7f, 1.0f, 1.3f});
    const LayerSet ls = bake_nlp(s, NlpOptions{}, RunControl{});
    for (auto [i, j] : {std::pair{16, 16}, std::pair{0, 0}, std::pair{32, 5}}) {
      const float* d = texel(ls, "direct", i, j);
      EXPECT_NEAR(d[0], 0.7f, 1e-4);
      EXPECT_NEAR(d[1], 1.0f, 1e-4);
      EXPECT_NEAR(d[2], 1.3f, 1e-4);
      const float* ind = texel(ls, "indirect", i, j);
      EXPECT_EQ(ind[0], 0.0f);
      // Upper hemisphere: 2 pi Y00, pi Y10, 0, 2 pi Y30 (5/4 - 3/2); nothing else.
      const float* v = texel(ls, "sh_visibility", i, j);
      for (int r = 0; r < 16; ++r) {
        const double want = r == 0    ? 2 * kPi * 0.28209479
                            : r == 2  ? kPi * 0.48860251
                            : r == 12 ? -0.25 * 2 * kPi * 0.37317633
                                      : 0.0;
        EXPECT_NEAR(v[r], want, 2e-5) << r;
      }
      // sh_irradiance evaluated at the normal (+z) is the total.
      const float* e = texel(ls, "sh_irradiance", i, j);
      const float y00 = 0.28209479f, y10 = 0.48860251f, y20 = 0.31539157f * 2;
      EXPECT_NEAR(e[0 * 3 + 1] * y00 + e[2 * 3 + 1] * y10 + e[6 * 3 + 1] * y20, 1.0f, 1e-4);
    }
  }
}

// V-trench floor (odd width, center column): the horizon across the trench is the wall plane,
// tan(omega(phi)) = |cos phi| tan A, so the sky through the V gives E / pi = L cos A (the cosine-weighted
// view factor of the opening). NLP/SH approximates it; the error bound here is the measured one plus margin.
TEST(NlpBake, TrenchFloorMatchesViewFactor) {
  for (double angle : {20.0, 45.0}) {
    ProceduralSpec spec;
    spec.kind = ProceduralKind::trench;
    spec.width = spec.height = 65;
    spec.angle_deg = angle;
    const Scene s = make_scene(spec, Wrap::clamp, Rgb{1, 1, 1});
    NlpOptions o;
    o.directions = 64;
    o.layers = {"direct"};
    const LayerSet ls = bake_nlp(s, o, RunControl{});
    const float* d = texel(ls, "direct", 32, 32);
    EXPECT_NEAR(d[0], std::cos(angle * kPi / 180), 0.03) << angle;
    std::printf("trench %.0f: direct %.5f, view factor %.5f\n", angle, d[0], std::cos(angle * kPi / 180));
  }
}

// direct_cosine exact: the environment integrated per azimuth with the exact cosine. A flat field under the
// built-in sky (L = horizon + (zenith - horizon) sin e above the horizon) gets E / pi = horizon + (zenith -
// horizon) 2 / 3; a V-trench floor under a uniform sky its opening's cosine-weighted view factor cos A. The
// SH form (NS09) misses both by its order-4 truncation.
TEST(NlpBake, DirectCosineExactMatchesClosedForms) {
  ProceduralSpec flat;
  flat.kind = ProceduralKind::flat;
  flat.width = flat.height = 33;
  Scene s = make_scene(flat, Wrap::clamp, Rgb{1, 1, 1});
  SkySpec sky;
  sky.sun_irradiance = Rgb{0, 0, 0};
  s.environment = make_sky_environment(sky).environment;
  NlpOptions o;
  o.layers = {"direct"};
  o.exact_direct_cosine = true;
  const LayerSet baked = bake_nlp(s, o, RunControl{});  // d points into it
  const float* d = texel(baked, "direct", 16, 16);
  const float want[3] = {sky.horizon.r + (sky.zenith.r - sky.horizon.r) * 2 / 3.0f,
                         sky.horizon.g + (sky.zenith.g - sky.horizon.g) * 2 / 3.0f,
                         sky.horizon.b + (sky.zenith.b - sky.horizon.b) * 2 / 3.0f};
  // Bound: the environment is constant across each of its 64 lat-long rows (3.4e-4 measured).
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(d[c], want[c], 1e-3 * want[c]) << c;
  for (double angle : {20.0, 45.0}) {
    ProceduralSpec spec;
    spec.kind = ProceduralKind::trench;
    spec.width = spec.height = 65;
    spec.angle_deg = angle;
    const Scene t = make_scene(spec, Wrap::clamp, Rgb{1, 1, 1});
    NlpOptions e;
    e.directions = 64;
    e.layers = {"direct"};
    e.exact_direct_cosine = true;
    const float got = texel(bake_nlp(t, e, RunControl{}), "direct", 32, 32)[0];
    EXPECT_NEAR(got, std::cos(angle * kPi / 180), 2e-3) << angle;
    std::printf("trench %.0f, direct_cosine exact: %.5f, view factor %.5f\n", angle, got,
                std::cos(angle * kPi / 180));
  }
}

// Emitting V-trench walls (radiance 1, albedo 0, black sky): the floor's first bounce is the cosine-weighted
// view factor of the walls, 1 - cos A. With indirect_cosine exact the casting-set segments carry the exact
// cosine and the result is close; the order-3 SH lobe (NS09 section 7) over-weights grazing light.
TEST(NlpBake, EmittingTrenchWallsExactCosine) {
  for (double angle : {20.0, 45.0}) {
    ProceduralSpec spec;
    spec.kind = ProceduralKind::trench;
    spec.width = spec.height = 65;
    spec.angle_deg = angle;
    Scene s = make_scene(spec, Wrap::clamp, Rgb{0, 0, 0}, 0.0f);
    s.surface.emission.assign(s.field.texel_count(), Rgb{1, 1, 1});
    NlpOptions o;
    o.directions = 64;
    o.layers = {"indirect"};
    o.exact_indirect_cosine = true;
    const float exact = texel(bake_nlp(s, o, RunControl{}), "indirect", 32, 32)[0];
    o.exact_indirect_cosine = false;
    const float lobe = texel(bake_nlp(s, o, RunControl{}), "indirect", 32, 32)[0];
    const double want = 1 - std::cos(angle * kPi / 180);
    EXPECT_NEAR(exact, want, 2e-3) << angle;
    EXPECT_LT(std::abs(exact - want), std::abs(lobe - want)) << angle;
    std::printf("emitting trench %.0f: exact cosine %.5f, SH lobe %.5f, view factor %.5f\n", angle, exact,
                lobe, want);
  }
}

// A single straight cliff: flat ground at height 0, a step of height h between columns c and c + 1
// (the triangulated surface makes the face one plane, tilted t = atan h), flat again at h beyond; uniform sky
// L = 1, albedo rho, one bounce. A receiver on the low ground D texels from the foot sees only the sky and
// the face. The face sees the sky above the horizon in front of it (the low ground blocks the rest, the high
// ground lies behind its plane): exit radiance rho (1 + cos t) / 2. Its cosine-weighted view factor from the
// receiver, per azimuth phi up to the face's top edge at elevation e(phi) = atan(h cos phi / (D + 1)), is
// sin^2 e / 2: indirect E/pi = rho (1 + cos t) / 2 * (1 / 2 pi) * integral of sin^2 e(phi) dphi over the
// azimuths that reach the face inside the field. Texel senders (NS09) give the face the light of the flat
// treads at its ends, far too bright; facet senders light the face with its own normal.
TEST(NlpBake, CliffFaceRadiatesItsOwnLight) {
  const int W = 48, H = 161, c = 30, row = 80;
  const double h = 6, rho = 0.6;
  Scene s;
  s.field.width = W, s.field.height = H, s.field.texel_size = 1, s.field.wrap = Wrap::clamp;
  s.field.z.assign(std::size_t(W) * H, 0.0f);
  for (int j = 0; j < H; ++j)
    for (int i = c + 1; i < W; ++i) s.field.z[s.field.index(i, j)] = float(h);
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{float(rho), float(rho), float(rho)});
  s.environment = make_uniform_environment(Rgb{1, 1, 1});
  s.bounces = 1;
  const double face = rho * (1 + 1 / std::sqrt(1 + h * h)) / 2;
  double want = 0, got_facets = 0, got_texels = 0;
  for (bool facets : {true, false}) {
    NlpOptions o;
    o.directions = 64;
    o.levels_per_octave = 8;
    o.exact_indirect_cosine = true;
    o.facet_senders = facets;
    o.near_spacing = 0;  // the senders alone (with the default 0.5: facet senders +7.1 %, texels +13.5 %)
    o.layers = {"indirect"};
    const LayerSet ls = bake_nlp(s, o, RunControl{});
    for (int D = 3; D <= 16; ++D) {
      const float v = texel(ls, "indirect", c - D, row)[0];
      (facets ? got_facets : got_texels) += v;
      if (!facets) continue;
      double F = 0;
      const int n = 20000;
      for (int q = 0; q < n; ++q) {
        const double phi = -kPi / 2 + kPi * (q + 0.5) / n;
        if (std::abs((D + 1) * std::tan(phi)) > row) continue;  // leaves the field before the face
        const double e = std::atan(h * std::cos(phi) / (D + 1));
        F += std::sin(e) * std::sin(e) * (kPi / n);
      }
      want += face * F / (2 * kPi);
    }
  }
  std::printf(
      "cliff, receivers 3..16 texels from the foot, mean indirect: closed form %.5f, facet senders "
      "%.5f (%+.1f %%), texel senders %.5f (%+.1f %%)\n",
      want / 14, got_facets / 14, 100 * (got_facets / want - 1), got_texels / 14,
      100 * (got_texels / want - 1));
  // Measured: facet senders +3.2 %, texel senders +9.8 % (h = 3: -4.1 % and +6.0 %).
  EXPECT_NEAR(got_facets / want, 1.0, 0.06);
  EXPECT_GT(std::abs(got_texels / want - 1), 0.06);  // the bound fails on NS09's senders
}

// A thin wall (one column of height h on flat ground) 12 texels from the receiver, between two knots of the
// march (d = 11.3 and 13.5 texels: they read the wall's bilinear flank at 0.31 h and the ground). Its top is
// at elevation atan(h / 12) = 18.4 degrees, so a sun at 15 degrees towards it is blocked and one at 21
// degrees is not. NS09's one sample a knot misses the wall and lights the receiver; near_spacing 0.5 samples
// between the knots and finds it.
TEST(NlpBake, NearSpacingFindsAWallBetweenKnots) {
  const int W = 64, H = 33, wall = 40, ri = 28, rj = 16;
  Scene s;
  s.field.width = W, s.field.height = H, s.field.texel_size = 1, s.field.wrap = Wrap::clamp;
  s.field.z.assign(std::size_t(W) * H, 0.0f);
  for (int j = 0; j < H; ++j) s.field.z[s.field.index(wall, j)] = 4.0f;
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{0, 0, 0});
  s.environment = make_uniform_environment(Rgb{0, 0, 0});
  s.bounces = 0;
  for (double spacing : {0.0, 0.5})
    for (double elev : {15.0, 21.0}) {
      DirectionalLight L;
      L.direction = Vec3{std::cos(elev * kPi / 180), 0, std::sin(elev * kPi / 180)};
      L.angular_diameter = 0;
      L.irradiance = Rgb{1, 1, 1};
      s.lights = {L};
      NlpOptions o;
      o.layers = {"direct"};
      o.near_spacing = spacing;
      const float got = texel(bake_nlp(s, o, RunControl{}), "direct", ri, rj)[0];
      const double lit = std::sin(elev * kPi / 180) / kPi;
      const bool blocked = elev < std::atan(4.0 / (wall - ri)) * 180 / kPi;
      if (spacing > 0 || !blocked)
        EXPECT_NEAR(got, blocked ? 0.0 : lit, 1e-5) << spacing << " " << elev;
      else
        EXPECT_NEAR(got, lit, 1e-5) << "NS09's knots were expected to miss the wall";
    }
}

// A raised texel (i - 1, j) beside a receiver (i, j) on flat ground, a sun at azimuth 135 degrees and 30
// degrees up: its ray runs along the triangulation's facet edge from (i, j) to (i - 1, j + 1), where the
// triangulated surface (the reference's) is flat, so the receiver is lit. The bilinear surface bulges there
// (0.21 h one texel out), which NS09's knots read as an occluder; near_spacing reads the triangulated
// surface near the receiver.
TEST(NlpBake, NearSpacingReadsTheTriangulatedSurface) {
  const int W = 33, H = 33, ri = 16, rj = 16;
  Scene s;
  s.field.width = W, s.field.height = H, s.field.texel_size = 1, s.field.wrap = Wrap::clamp;
  s.field.z.assign(std::size_t(W) * H, 0.0f);
  s.field.z[s.field.index(ri - 1, rj)] = 4.0f;
  s.field.z[s.field.index(ri + 1, rj)] = 4.0f;  // behind the receiver: its normal stays +z
  s.normals = compute_normals(s.field);
  s.surface.albedo.assign(s.field.texel_count(), Rgb{0, 0, 0});
  s.environment = make_uniform_environment(Rgb{0, 0, 0});
  s.bounces = 0;
  const double elev = 30 * kPi / 180, az = 135 * kPi / 180;
  DirectionalLight L;
  L.direction = Vec3{std::cos(elev) * std::cos(az), std::cos(elev) * std::sin(az), std::sin(elev)};
  L.angular_diameter = 0;
  L.irradiance = Rgb{1, 1, 1};
  s.lights = {L};
  NlpOptions o;
  o.layers = {"direct"};
  const Vec3f n = normal_at(s.field, ri, rj);
  const double lit = (n.x * L.direction.x + n.y * L.direction.y + n.z * L.direction.z) / kPi;
  o.near_spacing = 0;
  const float ns09 = texel(bake_nlp(s, o, RunControl{}), "direct", ri, rj)[0];
  o.near_spacing = 0.5;
  const float got = texel(bake_nlp(s, o, RunControl{}), "direct", ri, rj)[0];
  std::printf("sun along a facet edge: lit %.5f, near_spacing %.5f, NS09 %.5f\n", lit, got, ns09);
  EXPECT_NEAR(got, lit, 1e-5);
  EXPECT_EQ(ns09, 0.0f);  // the bilinear bulge this test is about
}

// A tilted plane under a uniform environment (whole sphere): the plane never occludes its own hemisphere,
// E/pi = L.
TEST(NlpBake, SlopeUnderUniformEnvironment) {
  for (double angle : {15.0, 35.0}) {
    ProceduralSpec spec;
    spec.kind = ProceduralKind::slope;
    spec.width = spec.height = 65;
    spec.angle_deg = angle;
    spec.aspect_deg = 30;
    const Scene s = make_scene(spec, Wrap::clamp, Rgb{1, 1, 1});
    NlpOptions o;
    o.layers = {"direct", "indirect"};
    const LayerSet ls = bake_nlp(s, o, RunControl{});
    // The plane sees none of itself; the pyramid's renormalised border filtering bends far levels a little.
    EXPECT_NEAR(texel(ls, "direct", 32, 32)[0], 1.0, 0.03) << angle;
    EXPECT_NEAR(texel(ls, "indirect", 32, 32)[0], 0.0, 5e-3) << angle;
    std::printf("slope %.0f: direct %.5f indirect %.5f\n", angle, texel(ls, "direct", 32, 32)[0],
                texel(ls, "indirect", 32, 32)[0]);
  }
}

// A directional light: exact cosine on a flat field; across a trench, blocked below the wall angle.
TEST(NlpBake, DirectionalLightRestrictedExtent) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::trench;
  spec.width = spec.height = 65;
  spec.angle_deg = 30;
  Scene s = make_scene(spec, Wrap::clamp, Rgb{0, 0, 0});
  NlpOptions o;
  o.layers = {"direct"};
  for (double elev : {20.0, 40.0}) {
    DirectionalLight L;
    L.direction = Vec3{std::cos(elev * kPi / 180), 0, std::sin(elev * kPi / 180)};
    L.angular_diameter = 0.53 * kPi / 180;
    L.irradiance = Rgb{2, 2, 2};
    s.lights = {L};
    const LayerSet ls = bake_nlp(s, o, RunControl{});
    const double want = elev > 30 ? 2 * std::sin(elev * kPi / 180) / kPi : 0.0;
    EXPECT_NEAR(texel(ls, "direct", 32, 32)[0], want, 1e-4) << elev;
  }
}

// Subsampling (NS09 §7) on a smooth field: V and U on every other texel, shading with full-resolution
// normals. Exact on the flat field; close to full resolution on sines; identical at the coarse receivers'
// texels for V.
TEST(NlpBake, SubsampleTwo) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::sines;
  spec.width = 64;
  spec.height = 49;
  spec.feature_size = 24;  // period 24 texels (the default 8 is too sharp for 2x2 subsampling)
  const Scene s = make_scene(spec, Wrap::clamp, Rgb{1, 1, 1});
  NlpOptions o;
  o.directions = 16;
  const LayerSet full = bake_nlp(s, o, RunControl{});
  o.subsample = 2;
  const LayerSet half = bake_nlp(s, o, RunControl{});
  for (const char* layer : {"direct", "indirect"}) {
    const auto& a = full.find(layer)->data;
    const auto& b = half.find(layer)->data;
    double se = 0, mean = 0;
    for (std::size_t t = 0; t < a.size(); ++t) se += (a[t] - b[t]) * (a[t] - b[t]), mean += a[t];
    const double rmse = std::sqrt(se / a.size());
    std::printf("subsample 2 vs 1, sines, %s: rmse %.5f (mean %.4f)\n", layer, rmse, mean / a.size());
    // Measured: direct 1.0 %, indirect 4.6 % of the mean (the neighbours' casting sets differ most).
    EXPECT_LT(rmse, (layer[0] == 'd' ? 0.02 : 0.06) * mean / a.size()) << layer;
  }
  // Even texels are receivers: sh_visibility identical there.
  for (auto [i, j] : {std::pair{10, 20}, std::pair{62, 48}, std::pair{63, 48}})
    for (int r = 0; r < 16; ++r)
      EXPECT_FLOAT_EQ(texel(full, "sh_visibility", i, j)[r], texel(half, "sh_visibility", i, j)[r])
          << i << " " << r;
}

// Light is never negative (docs/contract.md: every layer is light-like): a subsampled receiver's
// interpolated light, or a truncated SH lobe, may ring below 0 on terrain rough at the texel scale, and the
// light layers are clamped there.
TEST(NlpBake, LightLayersAreNeverNegative) {
  for (const ProceduralKind kind :
       {ProceduralKind::rough, ProceduralKind::craters, ProceduralKind::terraces}) {
    ProceduralSpec spec;
    spec.kind = kind;
    spec.width = 97, spec.height = 83, spec.seed = 11;
    Scene s = make_scene(spec, Wrap::clamp, Rgb{1, 1, 1}, 0.6f);
    s.environment = make_sky_environment(SkySpec{}).environment;  // the built-in sky and its sun
    s.bounces = 2;
    for (const int subsample : {1, 2})
      for (const bool exact : {true, false}) {
        NlpOptions o;
        o.directions = 8;
        o.subsample = subsample;
        o.exact_direct_cosine = o.exact_indirect_cosine = exact;
        const LayerSet ls = bake_nlp(s, o, RunControl{});
        for (const char* layer : {"direct", "indirect", "total"}) {
          const auto& v = ls.find(layer)->data;
          EXPECT_GE(*std::min_element(v.begin(), v.end()), 0.0f)
              << layer << ", kind " << int(kind) << ", subsample " << subsample << ", exact " << exact;
        }
      }
  }
}

// sh_irradiance is the SH of E(n)/pi over normals: evaluated at each texel's normal it gives total (no
// lights) when total takes the SH form too (direct_cosine and indirect_cosine sh; with the exact cosines,
// the defaults, total differs from it by the SH truncation, 3 % at these texels).
TEST(NlpBake, ShIrradianceAtTheNormalIsTotal) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::fractal;
  spec.width = spec.height = 40;
  Scene s = make_scene(spec, Wrap::repeat, Rgb{1, 1, 1});
  SkySpec sky;
  sky.sun_irradiance = Rgb{0, 0, 0};
  s.environment = make_sky_environment(sky).environment;
  NlpOptions o;
  o.directions = 12;
  o.exact_direct_cosine = o.exact_indirect_cosine = false;
  const LayerSet ls = bake_nlp(s, o, RunControl{});
  for (auto [i, j] : {std::pair{3, 4}, std::pair{20, 31}, std::pair{39, 0}}) {
    const Vec3f n = s.normals[s.field.index(i, j)];
    double y[16];
    sh::eval<double>(n.x, n.y, n.z, y);
    const float* c = texel(ls, "sh_irradiance", i, j);
    const float* t = texel(ls, "total", i, j);
    for (int ch = 0; ch < 3; ++ch) {
      double e = 0;
      for (int k = 0; k < 16; ++k) e += c[k * 3 + ch] * y[k];
      EXPECT_NEAR(e, t[ch], 1e-4 * (1 + t[ch])) << i << " " << j << " " << ch;
    }
    for (int k = 9; k < 16; ++k) EXPECT_EQ(c[k * 3], 0.0f);
  }
}

TEST(NlpBake, UnknownLayerIsAnInputError) {
  nlohmann::json p = {{"method", "nlp"}, {"layers", {"direct", "ao"}}};
  EXPECT_THROW(read_method_config("nlp", p, {}), InputError);
}

TEST(NlpPyramid, LevelZeroIsTheFieldAndLevelsKeepTheMean) {
  const int W = 40, H = 24;
  std::vector<float> z(W * H);
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) z[j * W + i] = float(std::sin(0.7 * i) + 0.3 * j);
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
    const nlp::Pyramid p = nlp::build_pyramid(z.data(), 1, W, H, wrap, 4, 12);
    ASSERT_EQ(p.levels.size(), 12u);
    for (int j = 0; j < H; ++j)
      for (int i = 0; i < W; ++i)
        EXPECT_EQ(nlp::sample_level1(p, p.levels[0], float(i), float(j)), z[j * W + i]);
  }
  // A linear ramp survives any clamp-free (repeat) filtering in its periodic part; a plane in clamp mode is
  // reproduced away from the border by the symmetric kernel.
  std::vector<float> ramp(W * H);
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) ramp[j * W + i] = 0.5f * i - 0.25f * j;
  const nlp::Pyramid p = nlp::build_pyramid(ramp.data(), 1, W, H, Wrap::clamp, 4, 6);
  for (int l = 0; l < 6; ++l)
    EXPECT_NEAR(nlp::sample_level1(p, p.levels[l], 20.0f, 12.0f), 10.0f - 3.0f, 1e-3) << l;
}

// binary16 against its definition: known encodings, round to nearest even at the halfway points, every
// finite half value back and forth exactly, saturation instead of infinity.
TEST(NlpPyramid, HalfConversions) {
  EXPECT_EQ(nlp::float_to_half(1.0f), 0x3C00);
  EXPECT_EQ(nlp::float_to_half(-2.0f), 0xC000);
  EXPECT_EQ(nlp::float_to_half(65504.0f), 0x7BFF);
  EXPECT_EQ(nlp::float_to_half(1e9f), 0x7BFF);
  EXPECT_EQ(nlp::float_to_half(std::ldexp(1.0f, -24)), 0x0001);
  EXPECT_EQ(nlp::float_to_half(1.0f + std::ldexp(1.0f, -11)), 0x3C00);      // tie: to even
  EXPECT_EQ(nlp::float_to_half(1.0f + 3 * std::ldexp(1.0f, -11)), 0x3C02);  // tie: to even (up)
  EXPECT_EQ(nlp::half_to_float(0x3555), 0x1.554p-2f);
  EXPECT_EQ(nlp::half_to_float(0x0200), std::ldexp(1.0f, -15));  // subnormal
  for (std::uint32_t h = 0; h < 65536; ++h) {
    if (((h >> 10) & 0x1f) == 0x1f) continue;  // inf and NaN
    const float f = nlp::half_to_float(std::uint16_t(h));
    const int e = ((h >> 10) & 0x1f) == 0 ? -14 : int((h >> 10) & 0x1f) - 15;
    const float m = ((h >> 10) & 0x1f) == 0 ? float(h & 0x3ff) / 1024 : 1 + float(h & 0x3ff) / 1024;
    ASSERT_EQ(f, ((h & 0x8000) ? -1 : 1) * std::ldexp(m, e)) << h;
    if (h != 0x8000) {
      ASSERT_EQ(nlp::float_to_half(f), h) << h;
    }
  }
  // Every float between two neighbouring finite halves (their midpoint, just either side of it, and a
  // spread in between) goes to the nearer, a tie to the even one: against the table of half values.
  for (std::uint32_t h = 0; h < 0x7bff; ++h) {
    const double a = nlp::half_to_float(std::uint16_t(h)), b = nlp::half_to_float(std::uint16_t(h + 1));
    const double mid = 0.5 * (a + b);
    const std::uint16_t even = (h & 1) ? std::uint16_t(h + 1) : std::uint16_t(h);
    ASSERT_EQ(nlp::float_to_half(float(mid)), even) << h;
    ASSERT_EQ(nlp::float_to_half(-float(mid)), even | 0x8000) << h;
    ASSERT_EQ(nlp::float_to_half(std::nextafter(float(mid), 0.0f)), h) << h;
    ASSERT_EQ(nlp::float_to_half(std::nextafter(float(mid), 1e30f)), h + 1) << h;
    for (double t : {0.1, 0.37, 0.63, 0.9})
      ASSERT_EQ(nlp::float_to_half(float(a + t * (b - a))), t < 0.5 ? h : h + 1) << h << " " << t;
  }
}

// A half pyramid reads what the float one does to within half's relative rounding (2^-11 of the largest
// value, the scale it is stored against), also for values far above half's range.
TEST(NlpPyramid, HalfLevelsMatchFloatLevels) {
  const int W = 37, H = 29;
  for (float amplitude : {1.0f, 3e6f}) {
    std::vector<float> rad(std::size_t(W) * H * 3);
    for (std::size_t t = 0; t < rad.size(); ++t) rad[t] = amplitude * float(1.5 + std::sin(0.37 * double(t)));
    for (Wrap wrap : {Wrap::clamp, Wrap::repeat}) {
      const nlp::Pyramid a = nlp::build_pyramid(rad.data(), 3, W, H, wrap, 4, 10);
      const nlp::Pyramid b = nlp::build_pyramid(rad.data(), 3, W, H, wrap, 4, 10, true);
      ASSERT_GT(b.half_scale, 0.0f);
      EXPECT_EQ(b.bytes() * 2, a.bytes());
      EXPECT_EQ(nlp::pyramid_bytes(3, W, H, wrap, 4, 10, true), b.bytes());
      EXPECT_EQ(nlp::pyramid_bytes(3, W, H, wrap, 4, 10), a.bytes());
      for (int l = 0; l < 10; ++l)
        for (float y = 0; y < H; y += 0.7f)
          for (float x = 0; x < W; x += 0.9f) {
            float va[3], vb[3];
            nlp::sample_level(a, a.levels[l], x, y, va);
            nlp::sample_level(b, b.levels[l], x, y, vb);
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(vb[c], va[c], 2.5f * amplitude * 0x1p-11f) << l;
          }
    }
  }
}

TEST(NlpMarch, BsplineCurveOfAConstantIsConstant) {
  const float w[5] = {0.3f, 0.3f, 0.3f, 0.3f, 0.3f};
  float c[9];
  EXPECT_EQ(nlp::bspline_curve(w, 5, c), 9);
  for (float v : c) EXPECT_NEAR(v, 0.3f, 1e-6);
  EXPECT_NEAR(nlp::fast_atan(1.0f), kPi / 4, 2e-5);
  for (float x = -20; x < 20; x += 0.37f) EXPECT_NEAR(nlp::fast_atan(x), std::atan(x), 2e-5);
}

// The curve against the uniform cubic B-spline evaluated from its definition (end control points repeated),
// and bspline_max against the maximum of the whole curve, bit for bit, on random knot angles (plateaus,
// spikes, ties and short arrays included).
TEST(NlpMarch, BsplineCurveAndItsMaximum) {
  std::uint32_t state = 12345;
  auto rnd = [&] {
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1 << 24);
  };
  for (int trial = 0; trial < 4000; ++trial) {
    const int n = 1 + trial % 45;
    std::vector<float> w(n), c(2 * n);
    for (float& v : w) {
      const float r = rnd();
      v = trial % 3 == 0 ? std::round(r * 4) * 0.25f : (r - 0.4f) * 3.0f;  // ties, or a spread of angles
    }
    ASSERT_EQ(nlp::bspline_curve(w.data(), n, c.data()), 2 * n - 1);
    auto at = [&](int k) { return double(w[std::clamp(k, 0, n - 1)]); };
    for (int k = 0; k < n; ++k) {
      EXPECT_NEAR(c[2 * k], (at(k - 1) + 4 * at(k) + at(k + 1)) / 6, 1e-5);
      if (k + 1 < n) {
        EXPECT_NEAR(c[2 * k + 1], (at(k - 1) + 23 * at(k) + 23 * at(k + 1) + at(k + 2)) / 48, 1e-5);
      }
    }
    EXPECT_EQ(nlp::bspline_max(w.data(), n), *std::max_element(c.begin(), c.begin() + 2 * n - 1)) << trial;
  }
}

}  // namespace
}  // namespace hfbake

namespace hfbake {
namespace {

// The row march (the kernels') against march, receiver by receiver: knot counts, distances and angles, on a
// rough field, clamp and repeat, with and without near_spacing, at azimuths along and off the axes.
TEST(NlpMarch, RowMarchEqualsMarch) {
  ProceduralSpec spec;
  spec.kind = ProceduralKind::rough;
  spec.width = 45;
  spec.height = 38;
  spec.seed = 3;
  for (Wrap wrap : {Wrap::clamp, Wrap::repeat})
    for (float spacing : {0.0f, 0.5f}) {
      const HeightField f = make_procedural(spec, 1.0, wrap);
      nlp::MarchSetup ms = nlp::make_march_setup(f.width, f.height, 1.0, wrap, 4, 4, 4);
      ms.near_spacing = spacing;
      const nlp::Pyramid hp =
          nlp::build_pyramid(f.z.data(), 1, f.width, f.height, wrap, 4, nlp::height_levels(ms));
      const int lv = int(hp.levels.size()), W = f.width;
      std::vector<int> xs(static_cast<std::size_t>(W)), odd;
      for (int i = 0; i < W; ++i) xs[std::size_t(i)] = i;
      for (int i = 0; i < W; i += 3) odd.push_back(i);
      nlp::RowMarch rm(ms.steps, W);
      std::vector<float> recv(std::size_t(lv) * W), rt(static_cast<std::size_t>(lv)), om(ms.steps + 1),
          dist(ms.steps + 1);
      std::vector<int> lev(ms.steps + 1);
      for (int j : {0, 5, 37})
        for (double phi : {0.0, 0.3, 1.5707963, 2.2, 4.0}) {
          const float cx = float(std::cos(phi)), cy = float(std::sin(phi));
          for (bool contiguous : {true, false}) {
            const std::vector<int>& row = contiguous ? xs : odd;
            const int cnt = int(row.size());
            for (int l = 0; l < lv; ++l)
              for (int t = 0; t < cnt; ++t)
                recv[std::size_t(l) * W + t] = nlp::sample_level1(hp, hp.levels[l], float(row[t]), float(j));
            nlp::march_row(ms, hp, row.data(), cnt, contiguous, j, cx, cy, recv.data(), W, rm);
            nlp::row_angles(rm, cnt);
            for (int t = 0; t < cnt; ++t) {
              for (int l = 0; l < lv; ++l) rt[l] = recv[std::size_t(l) * W + t];
              const int n =
                  nlp::march(ms, hp, row[t], j, cx, cy, rt.data(), om.data(), dist.data(), lev.data());
              ASSERT_EQ(rm.n[t], n) << row[t] << " " << j << " " << phi;
              for (int k = 0; k < n; ++k) {
                EXPECT_NEAR(rm.dist(ms, k, t), dist[k], 1e-5f * dist[k]);
                EXPECT_NEAR(rm.omega[std::size_t(k) * rm.stride + t], om[k], 2e-5f)
                    << "receiver " << row[t] << ", " << j << " knot " << k << " phi " << phi;
              }
            }
          }
        }
    }
}

// nlp_working_bytes with subsample 2 against the bytes counted here: a bounce's gather holds the receivers'
// U, 3 x 16 floats for each of 513 x 385 receivers of a 1024 x 768 field (every other texel and the last),
// beside the radiance pyramid and indirect (12 bytes a texel); with every texel a receiver the pyramid's
// build (36 bytes a texel beside the pyramid) holds the most instead.
TEST(NlpBake, SubsampleTwoCountsTheReceiversValues) {
  FieldShape f;
  f.width = 1024, f.height = 768;
  NlpOptions full;
  full.directions = 8;
  NlpOptions half = full;
  half.subsample = 2;
  const double N = 1024.0 * 768.0, receivers = 513.0 * 385.0;
  EXPECT_DOUBLE_EQ(nlp_working_bytes(f, half, 1) - nlp_working_bytes(f, full, 1),
                   4.0 * 3 * 16 * receivers + 12 * N - 36 * N);
}

}  // namespace
}  // namespace hfbake
