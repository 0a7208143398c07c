// A CRS's Earth through GDAL/PROJ: its ellipsoid and unit, and points moved between it and
// longitude/latitude.
#pragma once

#include <array>
#include <optional>
#include <string>

namespace hfbake {

struct CrsEarth {
  double semi_major = 0, semi_minor = 0;  // the ellipsoid's semi-axes, metres
  double metres_per_unit = 1;             // a projected CRS's linear unit (1 for a geographic CRS)
  bool geographic = false;
};

// The ellipsoid and unit of the CRS given as WKT; nullopt when GDAL cannot read it or it has no ellipsoid.
std::optional<CrsEarth> crs_earth(const std::string& wkt);

// WGS 84 longitude/latitude (degrees) to the CRS's (x, y) (a geographic CRS: longitude, latitude); nullopt
// when PROJ cannot transform it.
std::optional<std::array<double, 2>> lonlat_to_crs(const std::string& wkt, double lon, double lat);

// The CRS's (x, y) to longitude/latitude (degrees) on the CRS's own datum; nullopt when PROJ cannot.
std::optional<std::array<double, 2>> crs_to_lonlat(const std::string& wkt, double x, double y);

// The meridian convergence at the CRS point (x, y): the azimuth of true north in the grid, radians clockwise
// from the grid's +y (0 for a geographic CRS); nullopt when PROJ cannot transform the point.
std::optional<double> grid_convergence(const std::string& wkt, double x, double y);

// A projected CRS's point scale factor along the meridian at (x, y): metres of the grid (its linear unit in
// metres) per metre on the ellipsoid; 1.4514 for Web Mercator at 46.45 degrees, 0.9996 to 1.001 in a UTM
// zone. 1 for a geographic CRS; nullopt when PROJ cannot transform the point.
std::optional<double> grid_scale_factor(const std::string& wkt, double x, double y);

}  // namespace hfbake
