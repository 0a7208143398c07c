// Reference for relief's GIS quantities (methods/relief): per texel and direction k the highest and the
// lowest elevation angle under which the texel centre sees the triangulated surface within the horizontal
// search radius, found by bisection on the elevation with Embree rays that end at that radius
// (bisect_horizon's max_horizontal), independently of relief's exact march:
//   beta_up(k)   = the horizon within the radius of the field (0 where only the receiver's own border lies
//                  within it, as relief: rays just above the horizontal escape);
//   beta_down(k) = minus the same of the field turned upside down (z -> -z).
// Then svf = 1 - mean_k sin(max(beta_up, 0)), openness_positive = mean_k (90 - beta_up) degrees,
// openness_negative = mean_k (90 + beta_down) degrees, horizon_deg = beta_up in degrees per direction
// (relief's definitions; directions from relief_direction, so the compass convention is relief's).
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/height_field.hpp"
#include "methods/relief/relief.hpp"

namespace hfbake {

struct ReliefReferenceSettings {
  int directions = 16;
  double search_radius = 10;  // world units
  bool compass = false;
  GridAxes axes;  // where a compass direction lies on the grid (relief_direction)
};

// beta_up and beta_down (radians) of every texel, [texel * K + k] each; down left empty unless asked for.
struct ReliefHorizons {
  std::vector<double> up, down;
};
// curvature: Scene::curvature (0: flat), traced as horizon_reference.hpp's curved rays.
ReliefHorizons trace_relief_horizons(const HeightField& field, const ReliefReferenceSettings& s, bool down,
                                     const RunControl& rc, int iterations = 30, double curvature = 0);

// The reference's record of the settings it used (attribute "hfbake:relief_reference"): the report compares a
// relief entry's layers only when its resolved parameters are these.
inline constexpr const char* kReliefReferenceAttribute = "hfbake:relief_reference";
nlohmann::json relief_reference_record(const ReliefReferenceSettings& s);

// Adds svf, openness_positive, openness_negative and horizon_deg (those the first relief entry bakes:
// `relief`, its layers `relief_layers`) to a reference's layers, with relief's directions, search radius
// and azimuth convention, and the record. Nothing when the reference has them already.
void add_reference_relief(const HeightField& field, const ReliefSettings& relief,
                          const LayerSet& relief_layers, LayerSet& reference, const RunControl& rc,
                          double curvature = 0, GridAxes axes = {});

}  // namespace hfbake
