// relief: the relief-visualisation quantities GIS users know from RVT, SAGA and GRASS, from horizons
// limited to a search radius (radius_horizon.hpp): sky-view factor, positive and negative openness
// (Yokoyama et al. 2002), and horizon elevation angles in degrees, with azimuths in hfbake's convention or
// in compass terms. Definitions: docs/gis.md, "Relief quantities".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/height_field.hpp"
#include "field/scene.hpp"
#include "job/far_field.hpp"
#include "methods/method_table.hpp"
#include "methods/relief/radius_horizon.hpp"

namespace hfbake {

struct ReliefSettings {
  int directions = 16;
  double search_radius = 10;  // world units (default: 10 texels, RVT's 10 px)
  bool compass = false;       // direction k at compass azimuth 360 k / K (relief_direction)
  std::vector<std::string> layers;
  std::optional<FarFieldSpec> far_field;  // none: the exact march out to the search radius (FarField)
};

ReliefSettings read_relief_settings(Params& in, const FieldShape& field);

// The horizontal unit direction (world axes: x = columns, y = rows) of direction k of K: hfbake's phi_k =
// 2 pi k / K from +x towards +y; compass: azimuth A_k = 2 pi k / K clockwise from the map's north, which
// `axes` places on the grid (the raster's geotransform; without one north is the image top, -y, and east the
// image right, +x): (east_x sin A, north_y cos A).
void relief_direction(int k, int K, bool compass, GridAxes axes, double& dx, double& dy);
// The compass convention in words for the outputs' metadata.
std::string relief_azimuth_convention(bool compass, GridAxes axes);

LayerSet bake_relief(const Scene& scene, const MethodConfig& config, const RunControl& rc);
// The same from the heights alone (tests), with the Earth's curvature c per world unit (Scene::curvature).
// With a far field, `coarse` is the coarse copy of the field the window `field` is cut from, its texel
// (0, 0) at (x0, y0) there (a tile of a raster); null: the copy of `field` itself, made here. kept: the
// texels whose slack the recorded bound counts (FieldWindow::kept).
// axes: the raster's (grid_axes of its georeference; compass directions only).
LayerSet bake_relief(const HeightField& field, const ReliefSettings& s, const RunControl& rc,
                     double curvature = 0, const CoarseHeights* coarse = nullptr, int x0 = 0, int y0 = 0,
                     const KeptTexels& kept = {}, GridAxes axes = {});

MethodInfo relief_method();

}  // namespace hfbake
