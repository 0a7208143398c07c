#include "io/crs_geodesy.hpp"

#include <ogr_spatialref.h>

#include <cmath>
#include <memory>

#include "io/gdal_quiet.hpp"

namespace hfbake {

namespace {

struct TransformDeleter {
  void operator()(OGRCoordinateTransformation* t) const { OGRCoordinateTransformation::DestroyCT(t); }
};

std::optional<std::array<double, 2>> transform(const OGRSpatialReference& from, const OGRSpatialReference& to,
                                               double x, double y) {
  std::unique_ptr<OGRCoordinateTransformation, TransformDeleter> ct(
      OGRCreateCoordinateTransformation(&from, &to));
  if (!ct || !ct->Transform(1, &x, &y)) return std::nullopt;
  return std::array<double, 2>{x, y};
}

// The CRS in traditional GIS axis order (x = easting or longitude), as hfbake's geotransforms are.
bool read_crs(const std::string& wkt, OGRSpatialReference& srs) {
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return !wkt.empty() && srs.importFromWkt(wkt.c_str()) == OGRERR_NONE;
}

}  // namespace

std::optional<CrsEarth> crs_earth(const std::string& wkt) {
  GdalQuiet gdal;
  OGRSpatialReference srs;
  if (!read_crs(wkt, srs)) return std::nullopt;
  OGRErr e1 = OGRERR_NONE, e2 = OGRERR_NONE;
  CrsEarth earth;
  earth.semi_major = srs.GetSemiMajor(&e1);
  earth.semi_minor = srs.GetSemiMinor(&e2);
  if (e1 != OGRERR_NONE || e2 != OGRERR_NONE || !(earth.semi_major > 0) || !(earth.semi_minor > 0))
    return std::nullopt;
  earth.geographic = srs.IsGeographic() != 0;
  if (srs.IsProjected()) earth.metres_per_unit = srs.GetLinearUnits();
  return earth;
}

std::optional<std::array<double, 2>> lonlat_to_crs(const std::string& wkt, double lon, double lat) {
  GdalQuiet gdal;
  OGRSpatialReference to, wgs84;
  if (!read_crs(wkt, to)) return std::nullopt;
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  if (wgs84.importFromEPSG(4326) != OGRERR_NONE) return std::nullopt;
  return transform(wgs84, to, lon, lat);
}

std::optional<std::array<double, 2>> crs_to_lonlat(const std::string& wkt, double x, double y) {
  GdalQuiet gdal;
  OGRSpatialReference from;
  if (!read_crs(wkt, from)) return std::nullopt;
  std::unique_ptr<OGRSpatialReference> geog(from.CloneGeogCS());
  if (!geog) return std::nullopt;
  geog->SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return transform(from, *geog, x, y);
}

std::optional<double> grid_convergence(const std::string& wkt, double x, double y) {
  GdalQuiet gdal;
  OGRSpatialReference crs;
  if (!read_crs(wkt, crs)) return std::nullopt;
  if (crs.IsGeographic()) return 0.0;
  std::unique_ptr<OGRSpatialReference> geog(crs.CloneGeogCS());
  if (!geog) return std::nullopt;
  geog->SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  const auto lonlat = transform(crs, *geog, x, y);
  if (!lonlat) return std::nullopt;
  // A step of 1e-4° (11 m) north along the meridian, back in the grid.
  const auto north = transform(*geog, crs, (*lonlat)[0], (*lonlat)[1] + 1e-4);
  if (!north) return std::nullopt;
  return std::atan2((*north)[0] - x, (*north)[1] - y);
}

std::optional<double> grid_scale_factor(const std::string& wkt, double x, double y) {
  GdalQuiet gdal;
  OGRSpatialReference crs;
  if (!read_crs(wkt, crs)) return std::nullopt;
  if (!crs.IsProjected()) return 1.0;
  std::unique_ptr<OGRSpatialReference> geog(crs.CloneGeogCS());
  if (!geog) return std::nullopt;
  geog->SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  const auto lonlat = transform(crs, *geog, x, y);
  if (!lonlat) return std::nullopt;
  // 1e-4 degrees along the meridian: its length on the ellipsoid (the meridional radius of curvature M
  // times the angle) against the grid's, in metres.
  const double dlat = 1e-4;
  const auto north = transform(*geog, crs, (*lonlat)[0], (*lonlat)[1] + dlat);
  if (!north) return std::nullopt;
  OGRErr err = OGRERR_NONE;
  const double a = crs.GetSemiMajor(&err), inv_f = crs.GetInvFlattening(&err);
  const double f = inv_f > 0 ? 1 / inv_f : 0, e2 = f * (2 - f);
  const double phi = ((*lonlat)[1] + 0.5 * dlat) * std::acos(-1.0) / 180;
  const double s = std::sin(phi);
  const double M = a * (1 - e2) / std::pow(1 - e2 * s * s, 1.5);
  const double ground = M * dlat * std::acos(-1.0) / 180;
  const double grid = std::hypot((*north)[0] - x, (*north)[1] - y) * crs.GetLinearUnits();
  return ground > 0 ? grid / ground : std::optional<double>();
}

}  // namespace hfbake
