#include "methods/relief/relief.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/azimuth.hpp"
#include "methods/relief/radius_horizon.hpp"

namespace hfbake {

namespace {
constexpr double kDegPerRad = 180 / kPi;
}

ReliefSettings read_relief_settings(Params& in, const FieldShape& field) {
  ReliefSettings s;
  s.directions = in.integer("directions", 16, 1, 4096);
  s.search_radius = in.number("search_radius", 10 * field.texel_size, 1e-12, 1e12);
  const double shorter = std::min(field.dx(), field.dy());
  if (s.search_radius < shorter)
    in.fail("search_radius", "is shorter than one texel (" + std::to_string(shorter) +
                                 " world units): no surface point lies within it");
  if (s.search_radius > 1e5 * shorter)
    in.fail("search_radius", "is more than 100000 texels: the march's cost grows with it");
  s.compass = in.choice("azimuth_convention", "hfbake", {"hfbake", "compass"}) == "compass";
  s.layers = in.layers({"svf", "openness_positive", "openness_negative", "horizon_deg"},
                       {"svf", "openness_positive", "openness_negative"});
  s.far_field = read_far_field(in, field, s.search_radius, "search_radius");
  return s;
}

void relief_direction(int k, int K, bool compass, GridAxes axes, double& dx, double& dy) {
  const double a = azimuth(k, K);
  if (compass) {
    dx = axes.east_x * std::sin(a);
    dy = axes.north_y * std::cos(a);
  } else {
    dx = std::cos(a);
    dy = std::sin(a);
  }
}

std::string relief_azimuth_convention(bool compass, GridAxes axes) {
  if (!compass) return "hfbake: direction k at phi = 360 k / K from +x (image right) towards +y (image down)";
  return std::string("compass: direction k at azimuth 360 k / K clockwise from north; north = ") +
         (axes.north_y < 0 ? "image top (-y)" : "image bottom (+y)") +
         ", east = " + (axes.east_x > 0 ? "image right (+x)" : "image left (-x)");
}

LayerSet bake_relief(const HeightField& field, const ReliefSettings& s, const RunControl& rc,
                     double curvature, const CoarseHeights* coarse, int x0, int y0, const KeptTexels& kept,
                     GridAxes axes) {
  const int w = field.width, h = field.height, K = s.directions;
  CoarseHeights own;
  FarField far;
  if (s.far_field) {
    if (!coarse) {
      own = coarse_heights(field, s.far_field->cell);
      coarse = &own;
    }
    far = {coarse, s.far_field->beyond, x0, y0};
  }
  // The largest slack of a row's horizons (radius_horizon.hpp), one slot a row: the same bits for any
  // thread count.
  std::vector<double> row_slack(std::size_t(h), 0.0);
  std::vector<double> dx(K), dy(K);
  for (int k = 0; k < K; ++k) relief_direction(k, K, s.compass, axes, dx[k], dy[k]);
  LayerSet out;
  out.width = w;
  out.height = h;
  auto wants = [&](const char* name) {
    return std::find(s.layers.begin(), s.layers.end(), name) != s.layers.end();
  };
  float* svf = wants("svf") ? out.add("svf", mono_channels()).data.data() : nullptr;
  float* pos =
      wants("openness_positive") ? out.add("openness_positive", mono_channels()).data.data() : nullptr;
  float* neg =
      wants("openness_negative") ? out.add("openness_negative", mono_channels()).data.data() : nullptr;
  float* hor = wants("horizon_deg") ? out.add("horizon_deg", indexed_channels(K)).data.data() : nullptr;
  std::atomic<int> rows_done{0};
  tbb::parallel_for(0, h, [&](int j) {
    rc.check();
    for (int i = 0; i < w; ++i) {
      double sum_sin = 0, sum_up = 0, sum_down = 0;
      const std::size_t t = field.index(i, j);
      for (int k = 0; k < K; ++k) {
        // No surface within the radius (beyond a clamp border): level in both senses, open sky.
        const HorizonPair hp = radius_horizon(field, i, j, dx[k], dy[k], s.search_radius, curvature, far);
        if (kept.contains(i, j))
          row_slack[std::size_t(j)] = std::max({row_slack[std::size_t(j)], hp.up_slack, hp.down_slack});
        const double up = std::atan(hp.up), down = std::atan(hp.down);
        sum_sin += std::sin(std::max(up, 0.0));
        sum_up += up;
        sum_down += down;
        if (hor) hor[t * K + k] = float(up * kDegPerRad);
      }
      if (svf) svf[t] = float(1 - sum_sin / K);
      if (pos) pos[t] = float(90 - sum_up / K * kDegPerRad);
      if (neg) neg[t] = float(90 + sum_down / K * kDegPerRad);
    }
    rc.report(double(++rows_done) / h);
  });
  std::ostringstream az;
  az.precision(10);
  for (int k = 0; k < K; ++k) az << (k ? " " : "") << 360.0 * k / K;
  out.attributes.emplace_back("hfbake:relief:azimuths_deg", az.str());
  out.attributes.emplace_back("hfbake:relief:azimuth_convention", relief_azimuth_convention(s.compass, axes));
  char c[32];
  std::snprintf(c, sizeof c, "%.9g", curvature);
  out.attributes.emplace_back("hfbake:curvature", c);
  out.attributes.emplace_back(
      "hfbake:relief:definitions",
      "beta_up/down(k): highest/lowest elevation angle of the triangulated surface within search_radius "
      "along direction k (0 where no surface lies within it), each point lowered by hfbake:curvature times "
      "its horizontal distance squared; svf = 1 - mean_k sin(max(beta_up, 0)); "
      "openness_positive = mean_k (90 - beta_up) deg; openness_negative = mean_k (90 + beta_down) deg; "
      "horizon_deg = beta_up per direction");
  if (s.far_field) {
    char b[160];
    std::snprintf(b, sizeof b, "beyond %.9g world units: coarse cells of %d texels (docs/gis.md, Far field)",
                  s.far_field->beyond, s.far_field->cell);
    out.attributes.emplace_back("hfbake:relief:far_field", b);
    // Certified per bake: beta_up's tangent exceeds, and beta_down's falls below, the exact march's by at
    // most this; svf by at most this, openness by at most atan of it.
    std::snprintf(b, sizeof b, "%.6g", *std::max_element(row_slack.begin(), row_slack.end()));
    out.attributes.emplace_back("hfbake:relief:far_field_bound", b);
  }
  return out;
}

LayerSet bake_relief(const Scene& scene, const MethodConfig& config, const RunControl& rc) {
  const ReliefSettings& s = config.get<ReliefSettings>();
  const CoarseHeights* coarse = s.far_field ? scene.window.coarse_of(s.far_field->cell) : nullptr;
  return bake_relief(scene.field, s, rc, scene.curvature, coarse, scene.window.x0, scene.window.y0,
                     scene.window.kept, grid_axes(scene.georeference));
}

MethodInfo relief_method() {
  MethodInfo m;
  m.name = "relief";
  m.summary =
      "GIS relief quantities from radius-limited horizons: sky-view factor, openness, horizons in degrees";
  m.read = [](Params& in, const MethodContext& c) {
    const ReliefSettings s = read_relief_settings(in, c.field);
    return method_config(s, s.directions);
  };
  m.bake = bake_relief;
  m.memory_knob = "its layers (horizon_deg: 4 bytes a texel per direction)";
  // The far field's coarse copy of the field (nothing per texel otherwise).
  m.working_bytes = [](const MethodConfig& c, const MethodContext& context) {
    const ReliefSettings& s = c.get<ReliefSettings>();
    return s.far_field ? coarse_bytes(context.field.width, context.field.height, s.far_field->cell) : 0.0;
  };
  m.division = WorkDivision::texel_tiles;
  m.reach = [](const MethodConfig& c) {
    const ReliefSettings& s = c.get<ReliefSettings>();
    return far_field_reach(s.far_field, s.search_radius);
  };
  m.far_cell = [](const MethodConfig& c) { return far_field_cell(c.get<ReliefSettings>().far_field); };
  m.division_note =
      "texel tiles with a halo of search_radius, or of far_field.beyond with the whole field's coarse copy "
      "(each texel's horizons are its own)";
  m.reads_normals = false;
  m.reads_albedo = false;
  m.rectangular_texels = true;
  m.applies_curvature = true;
  return m;
}

}  // namespace hfbake
