// p1's far field (methods/p1/far_floor.hpp): the floor against the exact steepest crossing beyond its
// distance (an independent march over every crossing of the triangulated surface, p1_truth.hpp) on a family
// of fields, windows of them included; the bake against the exact bake within the certified bound it
// records; a window of the field with the raster's coarse copy gives the whole bake's bits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "core/error.hpp"
#include "field/coarse_heights.hpp"
#include "field/scene.hpp"
#include "methods/method_table.hpp"
#include "methods/p1/far_floor.hpp"
#include "methods/p1/p1.hpp"
#include "p1_truth.hpp"

namespace hfbake {
namespace {

// Rough (white noise), stepped, smooth and fractal fields.
std::vector<std::pair<std::string, HeightField>> family(int w, int h, double texel) {
  std::vector<std::pair<std::string, HeightField>> out;
  HeightField noise = truth::random_field(w, h, 6.0, 3, Wrap::clamp);
  noise.texel_size = texel;
  out.emplace_back("noise", std::move(noise));
  out.emplace_back("blocks", truth::procedural(ProceduralKind::blocks, w, h, Wrap::clamp, texel));
  out.emplace_back("sines", truth::procedural(ProceduralKind::sines, w, h, Wrap::clamp, texel));
  out.emplace_back("fractal", truth::procedural(ProceduralKind::fractal, w, h, Wrap::clamp, texel));
  return out;
}

// The window [x0, x0 + w) x [y0, y0 + h) of f as a field of its own.
HeightField window_of(const HeightField& f, int x0, int y0, int w, int h) {
  HeightField g;
  static_cast<FieldShape&>(g) = f;
  g.width = w, g.height = h;
  g.z.resize(g.texel_count());
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) g.z[g.index(i, j)] = f.z[f.index(x0 + i, y0 + j)];
  return g;
}

TEST(P1FarFloor, BoundsEveryCasterBeyondItsDistance) {
  const int x0 = 13, y0 = 9, ww = 50, wh = 40;
  std::vector<double> azimuths = {0, kPi / 2, kPi, 1.5 * kPi, kPi / 4, 3 * kPi / 4};
  for (int a = 0; a < 7; ++a) azimuths.push_back(0.3 + 0.87 * a);
  for (const double texel : {1.0, 2.5})
    for (auto& [name, f] : family(90, 71, texel))
      for (const int cell : {4, 7})
        for (const double beyond_texels : {6.5, 15.0})
          for (const double c : {0.0, 2e-3 / texel}) {
            SCOPED_TRACE(name + " texel " + std::to_string(texel) + " cell " + std::to_string(cell) +
                         " beyond " + std::to_string(beyond_texels) + " c " + std::to_string(c));
            const CoarseHeights g = coarse_heights(f, cell);
            const HeightField win = window_of(f, x0, y0, ww, wh);
            const double beyond = beyond_texels * texel;
            const p1::FloorGrid grid = p1::floor_grid(g, x0, y0, win, beyond, c);
            double worst_excess = 0;
            int checked = 0;
            for (const double phi : azimuths) {
              p1::DirectionFloor df;
              p1::direction_floor(grid, ww, wh, phi, df);
              for (int j = 0; j < wh; j += 3)
                for (int i = (j / 3) % 2; i < ww; i += 2) {
                  double dz = 0, run = 0;
                  const bool any = truth::march_from(f, x0 + i, y0 + j, std::cos(phi), std::sin(phi), 7,
                                                     beyond_texels, &dz, &run, 1e300, c);
                  const p1::FloorPick pick = p1::floor_at(grid, df, i, j, win.z[win.index(i, j)]);
                  if (!any) {
                    ASSERT_FALSE(pick.least > -1e30f) << "a certified lower end with nothing beyond";
                    continue;
                  }
                  const double exact = dz / run;
                  ASSERT_GE(double(pick.slope), exact) << "texel (" << i << ", " << j << ") phi " << phi;
                  ASSERT_LE(double(pick.least), exact + 1e-9)
                      << "texel (" << i << ", " << j << ") phi " << phi;
                  worst_excess = std::max(worst_excess, double(pick.slope) - exact);
                  ++checked;
                }
            }
            EXPECT_GT(checked, 1000);
            // Not a contract, a sanity check that the floor is a bound worth having: its excess stays below
            // the field's whole relief over the distance.
            const auto [lo, hi] = std::minmax_element(f.z.begin(), f.z.end());
            EXPECT_LT(worst_excess, 2 * double(*hi - *lo) / beyond);
          }
}

// Farther, larger, and along the axes, where the centre of a cell's rays lies on the walk's cell borders
// and a direction's cosine rounds to about 1e-16: white noise with sparse spikes of 100 (any one of them
// can be a horizon), 1400 x 520 texels of 0.125, cells of 16, 200 texels exact, the window far from the
// origin (where a texel coordinate's rounding swallows a step of 1e-14).
TEST(P1FarFloor, BoundsEveryCasterOnALargerFieldAlongTheAxes) {
  HeightField f = truth::random_field(1400, 520, 1.0, 9, Wrap::clamp);
  f.texel_size = 0.125;
  const HeightField spikes = truth::random_field(1400, 520, 1.0, 10, Wrap::clamp);
  for (std::size_t t = 0; t < f.z.size(); ++t)
    if (spikes.z[t] < 0.02f) f.z[t] += 100 * spikes.z[t] / 0.02f;
  const int x0 = 1050, y0 = 170, ww = 300, wh = 250, cell = 16;
  const double beyond_texels = 200;
  const CoarseHeights g = coarse_heights(f, cell);
  const HeightField win = window_of(f, x0, y0, ww, wh);
  const p1::FloorGrid grid = p1::floor_grid(g, x0, y0, win, beyond_texels * f.texel_size, 0.0);
  int checked = 0;
  for (int a = 0; a < 16; ++a) {
    const double phi = 2 * kPi * a / 16;
    p1::DirectionFloor df;
    p1::direction_floor(grid, ww, wh, phi, df);
    for (int j = 0; j < wh; j += 3)
      for (int i = (j / 3) % 2; i < ww; i += 2) {
        double dz = 0, run = 0;
        if (!truth::march_from(f, x0 + i, y0 + j, std::cos(phi), std::sin(phi), 7, beyond_texels, &dz, &run))
          continue;
        const p1::FloorPick pick = p1::floor_at(grid, df, i, j, win.z[win.index(i, j)]);
        ASSERT_GE(double(pick.slope), dz / run) << "texel (" << i << ", " << j << ") phi " << phi;
        ASSERT_LE(double(pick.least), dz / run + 1e-9) << "texel (" << i << ", " << j << ") phi " << phi;
        ++checked;
      }
  }
  EXPECT_GT(checked, 50000);
}

Scene scene_of(HeightField f) {
  Scene s;
  s.name = "far";
  s.field = std::move(f);
  s.environment = make_uniform_environment({1, 1, 1});
  return s;
}

double bound_of(const LayerSet& out) {
  for (const auto& [key, value] : out.attributes)
    if (key == "hfbake:p1:far_field_bound") return std::stod(value);
  ADD_FAILURE() << "no hfbake:p1:far_field_bound";
  return 0;
}

// Every horizon at least the exact bake's and at most the recorded bound above it (in sine, which moves
// less than the tangent); vsky never above the exact bake's.
TEST(P1FarField, BakeStaysWithinTheRecordedBoundOfTheExactBake) {
  constexpr int K = 8;
  for (auto& [name, f] : family(96, 80, 1.5))
    for (const double c : {0.0, 1e-3}) {
      SCOPED_TRACE(name + " c " + std::to_string(c));
      Scene s = scene_of(f);
      s.curvature = c;
      const nlohmann::json exact_entry = {{"directions", K}, {"layers", {"vsky", "horizon"}}};
      nlohmann::json far_entry = exact_entry;
      far_entry["far_field"] = {{"beyond", 12}, {"cell", 4}};
      const LayerSet exact = bake_method("p1", s, exact_entry, RunControl{});
      const LayerSet far = bake_method("p1", s, far_entry, RunControl{});
      const double bound = bound_of(far);
      EXPECT_GT(bound, 0);
      const auto [lo, hi] = std::minmax_element(f.z.begin(), f.z.end());
      EXPECT_LT(bound, 2 * double(*hi - *lo) / 12);  // a bound worth having (not a contract)
      const std::vector<float>&he = exact.find("horizon")->data, &hf = far.find("horizon")->data;
      std::size_t raised = 0;
      for (std::size_t t = 0; t < he.size(); ++t) {
        ASSERT_GE(hf[t], he[t] - 2e-6f) << t;
        ASSERT_LE(hf[t], he[t] + bound + 2e-6) << t;
        raised += hf[t] > he[t] + 1e-6f;
      }
      EXPECT_GT(raised, 0u) << "the floor never raised a horizon: the test checks nothing";
      const std::vector<float>&ve = exact.find("vsky")->data, &vf = far.find("vsky")->data;
      for (std::size_t t = 0; t < ve.size(); ++t) ASSERT_LE(vf[t], ve[t] + 2e-6f) << t;
    }
}

// A window of the field whose halo holds every point within `beyond` of its interior, baked with the
// field's coarse copy (a tile of a tiled bake), gives the whole bake's interior bit for bit.
TEST(P1FarField, WindowWithTheFieldsCoarseCopyGivesTheWholeBakesBits) {
  constexpr int K = 12;
  const double beyond = 7;
  for (auto& [name, f] : family(90, 71, 1.0)) {
    SCOPED_TRACE(name);
    nlohmann::json entry = {{"directions", K},
                            {"layers", {"ao", "vsky", "horizon", "horizon_distance", "bent_normal"}},
                            {"far_field", {{"beyond", beyond}, {"cell", 5}}}};
    const Scene whole = scene_of(f);
    const LayerSet all = bake_method("p1", whole, entry, RunControl{});
    const int halo = 9, ix = 30, iy = 25, iw = 33, ih = 29;  // interior
    Scene tile = scene_of(window_of(f, ix - halo, iy - halo, iw + 2 * halo, ih + 2 * halo));
    tile.window.x0 = ix - halo, tile.window.y0 = iy - halo;
    tile.window.coarse.push_back(std::make_shared<const CoarseHeights>(coarse_heights(f, 5)));
    const LayerSet part = bake_method("p1", tile, entry, RunControl{});
    for (const char* layer : {"ao", "vsky", "horizon", "horizon_distance", "bent_normal"}) {
      const Layer &a = *all.find(layer), &b = *part.find(layer);
      const std::size_t n = a.channel_count();
      for (int j = 0; j < ih; ++j)
        for (int i = 0; i < iw; ++i)
          for (std::size_t ch = 0; ch < n; ++ch) {
            const float va = a.data[f.index(ix + i, iy + j) * n + ch];
            const float vb = b.data[tile.field.index(halo + i, halo + j) * n + ch];
            ASSERT_EQ(std::memcmp(&va, &vb, sizeof va), 0)
                << layer << " texel (" << ix + i << ", " << iy + j << ") channel " << ch << ": " << va
                << " whole, " << vb << " window";
          }
    }
  }
}

// With a horizon_tolerance the search prunes from its neighbours' casters, which differ at a window's
// edge: the window's horizons are then within the tolerance of the whole bake's, not its bits.
TEST(P1FarField, WindowWithAToleranceStaysWithinIt) {
  constexpr int K = 12;
  constexpr float tau = 0.02f;
  for (auto& [name, f] : family(90, 71, 1.0)) {
    SCOPED_TRACE(name);
    const nlohmann::json entry = {{"directions", K},
                                  {"horizon_tolerance", tau},
                                  {"layers", {"horizon"}},
                                  {"far_field", {{"beyond", 7}, {"cell", 5}}}};
    const LayerSet all = bake_method("p1", scene_of(f), entry, RunControl{});
    const int halo = 9, ix = 30, iy = 25, iw = 33, ih = 29;
    Scene tile = scene_of(window_of(f, ix - halo, iy - halo, iw + 2 * halo, ih + 2 * halo));
    tile.window.x0 = ix - halo, tile.window.y0 = iy - halo;
    tile.window.coarse.push_back(std::make_shared<const CoarseHeights>(coarse_heights(f, 5)));
    const LayerSet part = bake_method("p1", tile, entry, RunControl{});
    const Layer &a = *all.find("horizon"), &b = *part.find("horizon");
    for (int j = 0; j < ih; ++j)
      for (int i = 0; i < iw; ++i)
        for (int k = 0; k < K; ++k)
          ASSERT_NEAR(a.data[f.index(ix + i, iy + j) * K + std::size_t(k)],
                      b.data[tile.field.index(halo + i, halo + j) * K + std::size_t(k)], tau + 1e-6f);
  }
}

TEST(P1FarField, ReaderRefusesARepeatField) {
  FieldShape shape;
  shape.width = shape.height = 64;
  shape.wrap = Wrap::repeat;
  const nlohmann::json entry = {{"far_field", {{"beyond", 10}, {"cell", 8}}}};
  Params p(entry, "job.json", "/bake/0");
  try {
    read_p1_params(p, shape);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "/bake/0/far_field");
  }
}

}  // namespace
}  // namespace hfbake
