// Where a height field lies on the Earth (when its file says so) and which of its texels had no height:
// what the GeoTIFF outputs need to be georeferenced like the input and to mark its holes as NoData.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hfbake {

struct Georeference {
  // True when the height raster's geotransform was read from the file (through GDAL); false for a
  // procedural field or an image without georeferencing, whose geotransform is made from texel_size.
  bool from_file = false;
  std::string crs_wkt;   // the input's CRS as WKT; empty: none
  std::string crs_name;  // e.g. "Slovenia 1996 / Slovene National Grid"; empty: none
  // GDAL's affine geotransform: X = g[0] + (i + 0.5) g[1] + (j + 0.5) g[2] at texel (i, j)'s centre, Y =
  // g[3] + (i + 0.5) g[4] + (j + 0.5) g[5]. hfbake accepts only g[2] = g[4] = 0 and |g[1]| = |g[5]|.
  std::array<double, 6> geotransform{0, 1, 0, 0, 0, -1};
  // The field's centre on the Earth, when PROJ can place it (filled by the loader from the CRS): longitude
  // and latitude in degrees on the CRS's datum, and the grid's azimuth of true north there (radians,
  // clockwise from the grid's north: the meridian convergence). What the sun method takes its place and
  // its north from.
  bool has_site = false;
  double site_longitude = 0, site_latitude = 0, site_convergence = 0;
  // A projected CRS's point scale factor there (io/crs_geodesy grid_scale_factor; 1: none known): the map's
  // metres per ground metre, which hfbake takes as 1.
  double site_scale = 1;
  // One byte per texel (row-major like the field), 1 where the input had no valid height (NaN, Inf, the
  // file's NoData value or the job's nodata_value) and the hole was filled; empty when there was none.
  std::vector<std::uint8_t> holes;
};

// Where the map's east and north lie on the grid: +x points east (east_x = 1) or west (-1), +y points north
// (north_y = 1: a south-up raster) or south (-1: north-up, the image top is north). From the signs of the
// geotransform read from the file; a field without one is north-up with east to the right.
struct GridAxes {
  int east_x = 1, north_y = -1;
};
inline GridAxes grid_axes(const Georeference& g) {
  if (!g.from_file) return {};
  return {g.geotransform[1] < 0 ? -1 : 1, g.geotransform[5] > 0 ? 1 : -1};
}

// The geotransform of a field without georeferencing: no CRS, north-up, texel (0, 0)'s centre at (0, 0),
// pixel size texel_size (map Y = -hfbake y, so the raster shows the way it is stored).
inline std::array<double, 6> local_geotransform(double texel_size) {
  return {-0.5 * texel_size, texel_size, 0.0, 0.5 * texel_size, 0.0, -texel_size};
}

}  // namespace hfbake
