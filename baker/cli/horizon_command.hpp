// hfbake horizon: the exact horizon profile at one point of a georeferenced DEM (terrain/point_horizon),
// as CSV or JSON. docs/gis.md "Horizon at a point".
#pragma once

#include <optional>
#include <string>

namespace hfbake {

struct HorizonOptions {
  std::string dem;
  std::string at;  // "X,Y" in the raster's CRS, or "LON,LAT" (WGS 84) with lonlat
  bool lonlat = false;
  double observer_height = 0;  // world units above the surface
  // Heights are stored x height_scale + height_offset, as a job's keys (docs/heights.md); unset: 1 and 0, and
  // a band that declares a scale, an offset or another unit than its pixels' is warned about.
  std::optional<double> height_scale, height_offset;
  int directions = 360;
  int band = 0;                // 0-based
  std::string format = "csv";  // "csv" or "json"
  std::string out;             // empty: stdout
  std::string plot;            // a polar plot PNG as well; empty: none
  int plot_size = 512;
  // Earth curvature: nullopt = the default (on for a geographic CRS, off for a projected one).
  std::optional<bool> curvature;
  std::optional<double> refraction;  // k; default kDefaultRefraction
};

// Exit 0, or 2 with one line "hfbake: error: <dem>: <argument>: <what>" for bad input.
int run_horizon(const HorizonOptions& options);

}  // namespace hfbake
