// Height rasters of the GIS world through GDAL: GeoTIFF/COG, VRT, SRTM HGT, Arc/Info ASCII grids, ERDAS
// IMG, ... with their georeferencing (CRS, geotransform) and their NoData value. Images of the asset world
// (EXR, PNG, JPEG, a TIFF without georeferencing) stay with OpenImageIO (io/image_input.hpp).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "io/image_input.hpp"

namespace hfbake {

// What GDAL says about a raster, from its header (no pixels are read).
struct GeoRasterInfo {
  std::string driver;  // GDAL's short driver name: "GTiff", "VRT", "SRTMHGT", "AAIGrid", "HFA", ...
  int width = 0, height = 0, bands = 0;
  std::vector<std::string> band_names;  // each band's description ("" when it has none)
  // Each band's colour as OpenImageIO names a channel of it ("R", "G", "B", "A"; "" for any other).
  std::vector<std::string> band_colours;
  bool palette = false;  // one band of palette indices, read as its palette's red
  bool has_geotransform = false;
  std::array<double, 6> geotransform{0, 1, 0, 0, 0, 1};
  // What places the raster instead of a geotransform, when it has none: "ground control points", "RPCs"
  // or "geolocation arrays" (GDAL's warper reads each); "" when nothing does.
  std::string placed_by;
  std::string crs_wkt, crs_name;              // empty: no CRS
  bool geographic = false;                    // the CRS is geographic (coordinates in degrees)
  std::string angular_unit;                   // a geographic CRS's unit ("degree", "grad", ...)
  double angular_unit_radians = 0;            // radians in that unit
  std::string linear_unit;                    // a projected CRS's unit ("metre", "US survey foot", ...)
  double linear_unit_metres = 1;              // metres in that unit
  std::vector<std::optional<double>> nodata;  // per band: the NoData value, if the file declares one
  // Per band: GDAL's scale and offset (unscaled = stored x scale + offset) when the file declares them
  // other than 1 and 0. hfbake reads the stored values (docs/heights.md); the heights line names these.
  std::vector<double> scale, offset;
  // Per band: the unit its values are in as the file declares it (GDAL's unit type: "m", "ft", ...; "" when
  // none).
  std::vector<std::string> unit_types;
  // Per band: the percentage of the raster that none of the file's data covers, where GDAL reads 0 or the
  // band's NoData value: a GeoTIFF's missing blocks (a sparse file's), from its block table; a mosaic's
  // gaps between its sources, from GDAL's data coverage status; 0 when all is covered or the driver cannot
  // tell.
  std::vector<double> uncovered_percent;
};

// What is wrong with reading band `band` of the raster as heights where no data covers it ("" when nothing
// is): GDAL reads 0 there unless the band has a NoData value, and a mosaic's gap would bake as a canyon down
// to height 0. With a NoData value a gap is a hole like any other (docs/gis.md).
std::string uncovered_problem(const GeoRasterInfo& info, int band);
// "" for a geographic CRS in degrees (or a CRS that is not geographic), else what is wrong: hfbake reads a
// geographic raster's geotransform in degrees, so one in grads or radians is refused, with the warp that
// makes it one in degrees.
std::string geographic_unit_problem(const GeoRasterInfo& info);

// Whether a geotransform is north-up (neither rotated nor sheared): its rotation terms within 1e-9 of its
// pixel sizes, the tolerance square pixels are held to (a term of 1e-15, a conversion's rounding, is none).
inline bool north_up(const std::array<double, 6>& g) {
  return std::abs(g[2]) <= 1e-9 * std::abs(g[1]) && std::abs(g[4]) <= 1e-9 * std::abs(g[5]);
}

// Whether a raster's heights are read through OpenImageIO, GDAL only placing it: a PNG (placed by a world
// file), whose values and channels are then those it has without one (docs/heights.md; GDAL 3.6 reads an
// interlaced 16-bit PNG byte-swapped, and a tRNS colour as NoData).
inline bool values_through_image_reader(const GeoRasterInfo& info) {
  return info.driver == "PNG";
}

// The raster's header when it is one for GDAL (a format OpenImageIO does not read, or a raster with a
// geotransform, a CRS, or ground control points, RPCs or geolocation arrays in place of a geotransform);
// nullopt when GDAL cannot open it or it is an image without georeferencing in a format OpenImageIO reads
// (EXR, PNG, JPEG, plain TIFF, ...), which then stays with OpenImageIO; but a TIFF that declares a NoData
// value or holds MinIsWhite samples is GDAL's (its holes seen, its values as stored).
std::optional<GeoRasterInfo> probe_georaster(const std::filesystem::path& file);

// Every file GDAL reads when it opens `file` as a raster (GDALGetFileList: the file, a VRT's sources, side
// files such as .aux.xml, .msk, .ovr and world files), `file` first and each once; {file} alone when GDAL
// cannot open it. What a bake reads through an input: what its identity hashes and its outputs never replace.
std::vector<std::filesystem::path> raster_files(const std::filesystem::path& file);

// Band `band` (0-based) as float32, row 0 = the first stored row (north for a north-up raster); values as
// stored (no normalisation, NoData values left as they are). Read a band of whole block rows at a time
// straight into the plane, GDAL's block cache emptied after each band, so the plane is the only full-size
// buffer (one RasterIO of the whole band held a second copy in the cache: 2.1 GB peak for a 16384^2 float32
// BigTIFF, 1.1 GB now). `progress` gets the fraction of rows read after each band. Unreadable, corrupt or
// truncated -> InputError at `site` naming the file.
Plane read_georaster_band(const std::filesystem::path& file, int band, const InputSite& site,
                          const ReadProgress& progress = {});

// The dataset metadata item `key` (GDAL's default domain) of a raster; "" when it has none or GDAL cannot
// open it.
std::string georaster_metadata_item(const std::filesystem::path& file, const std::string& key);

// GDAL's block cache held to `bytes` while the object lives (the previous size restored after): what a tiled
// bake budgets for it.
class GdalCacheLimit {
 public:
  explicit GdalCacheLimit(std::size_t bytes);
  ~GdalCacheLimit();
  GdalCacheLimit(const GdalCacheLimit&) = delete;
  GdalCacheLimit& operator=(const GdalCacheLimit&) = delete;

 private:
  long long previous_ = 0;
};

// Columns [x0, x0 + width) and rows [y0, y0 + height) of band `band` as float32, as read_georaster_band reads
// the whole band (values as stored), in one RasterIO of the window: a tiled bake's reads (the window alone
// is decoded: the blocks it touches), GDAL's block cache emptied after it. InputError at `site` naming the
// file and the window for a window outside the raster or a failed decode.
Plane read_georaster_window(const std::filesystem::path& file, int band, int x0, int y0, int width,
                            int height, const InputSite& site);

}  // namespace hfbake
