#include "io/georaster_input.hpp"

#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "io/gdal_quiet.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

// Drivers for image formats OpenImageIO reads as well: without georeferencing they stay with it (its channel
// names). Both readers give an integer band's stored integers (io/image_input.hpp read_image_channel).
bool asset_driver(const std::string& driver) {
  static const char* const names[] = {"GTiff", "PNG", "JPEG", "BMP", "GIF", "PNM", "EXR", "WEBP", "TGA"};
  return std::find(std::begin(names), std::end(names), driver) != std::end(names);
}

// The raster, read-only, or an error naming the file and what GDAL said.
std::unique_ptr<GDALDataset> open_raster(const fs::path& file, const InputSite& site, GdalQuiet& gdal) {
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds)
    throw InputError(site.job_file, site.pointer,
                     file.string() + ": cannot read the raster: " + gdal.error(file.string()));
  return ds;
}

bool is_png(const GDALDataset& ds) {
  const GDALDriver* d = const_cast<GDALDataset&>(ds).GetDriver();
  return d && std::string_view(d->GetDescription()) == "PNG";
}

// Whether `file` is a PNG of 16-bit samples stored interlaced (Adam7), from its header (IHDR: bit depth at
// byte 24, interlace method at byte 28): GDAL 3.6's PNG driver reads those samples byte-swapped.
bool interlaced_16bit_png(const fs::path& file) {
  unsigned char h[29] = {};
  std::FILE* f = std::fopen(file.c_str(), "rb");
  if (!f) return false;
  const std::size_t n = std::fread(h, 1, sizeof h, f);
  std::fclose(f);
  return n == sizeof h && h[1] == 'P' && h[2] == 'N' && h[3] == 'G' && h[24] == 16 && h[28] == 1;
}

// Band `band` (0-based) of ds, or an error naming the file; a PNG GDAL would misread is refused.
GDALRasterBand* band_of(GDALDataset& ds, const fs::path& file, int band, const InputSite& site) {
  GDALRasterBand* b = ds.GetRasterBand(band + 1);
  if (!b)
    throw InputError(site.job_file, site.pointer, file.string() + ": has no band " + std::to_string(band));
  if (is_png(ds) && interlaced_16bit_png(file))
    throw InputError(site.job_file, site.pointer,
                     file.string() +
                         ": is an interlaced 16-bit PNG, which GDAL reads byte-swapped here (this command "
                         "reads it through GDAL): save it without interlacing, or as a GeoTIFF "
                         "(gdal_translate)");
  return b;
}

// The band's NoData value as hfbake takes it: none for a PNG, whose tRNS colour (which GDAL reports as
// NoData) is a height like any other (docs/heights.md).
std::optional<double> band_nodata(GDALDataset& ds, GDALRasterBand* b) {
  int has = 0;
  const double v = b->GetNoDataValue(&has);
  if (!has || is_png(ds)) return std::nullopt;
  return v;
}

// Rows [y0, y0 + n) of columns [x0, x0 + w) of band b as floats into dst. A double band is read as double
// first: a finite value beyond float's range (other than the band's NoData value) would become an infinity
// and pass for a hole; it is refused instead, naming the texel.
bool read_rows_as_stored(GDALRasterBand* b, int x0, int y0, int w, int n, float* dst, const fs::path& file,
                         const InputSite& site) {
  if (b->GetRasterDataType() != GDT_Float64)
    return b->RasterIO(GF_Read, x0, y0, w, n, dst, w, n, GDT_Float32, 0, 0, nullptr) == CE_None;
  std::vector<double> row(static_cast<std::size_t>(w));
  int has_nodata = 0;
  const double nodata = b->GetNoDataValue(&has_nodata);  // a PNG has no double samples
  constexpr double kFloatMax = double(std::numeric_limits<float>::max());
  for (int y = 0; y < n; ++y) {
    if (b->RasterIO(GF_Read, x0, y0 + y, w, 1, row.data(), w, 1, GDT_Float64, 0, 0, nullptr) != CE_None)
      return false;
    for (int x = 0; x < w; ++x) {
      const double v = row[std::size_t(x)];
      if (std::isfinite(v) && std::fabs(v) > kFloatMax && !(has_nodata && v == nodata)) {
        char value[32];
        std::snprintf(value, sizeof value, "%g", v);
        throw InputError(
            site.job_file, site.pointer,
            file.string() + ": texel (" + std::to_string(x0 + x) + ", " + std::to_string(y0 + y) + ") is " +
                value +
                ", beyond a float's range: heights are baked as floats (if it marks missing data, "
                "declare it the band's NoData value)");
      }
      dst[std::size_t(y) * std::size_t(w) + std::size_t(x)] = float(v);
    }
  }
  return true;
}

// As read_rows_as_stored, and a texel its mask marks invalid (GDAL's mask band: a .msk side file or an
// internal mask) is NaN: a hole, as a NoData texel is. A mask that only restates the NoData value adds
// nothing; an alpha band is not a mask of the heights (OpenImageIO, reading the same image without a world
// file, ignores it too).
bool read_rows(GDALRasterBand* b, int x0, int y0, int w, int n, float* dst, const fs::path& file,
               const InputSite& site) {
  if (!read_rows_as_stored(b, x0, y0, w, n, dst, file, site)) return false;
  const int flags = b->GetMaskFlags();
  if (flags & (GMF_ALL_VALID | GMF_NODATA | GMF_ALPHA) || is_png(*b->GetDataset())) return true;
  GDALRasterBand* mask = b->GetMaskBand();
  if (!mask) return true;
  std::vector<std::uint8_t> valid(std::size_t(w) * std::size_t(n));
  if (mask->RasterIO(GF_Read, x0, y0, w, n, valid.data(), w, n, GDT_Byte, 0, 0, nullptr) != CE_None)
    return false;
  for (std::size_t i = 0; i < valid.size(); ++i)
    if (valid[i] == 0) dst[i] = std::numeric_limits<float>::quiet_NaN();
  return true;
}

// The band's colour table when its values are palette indices, else nullptr.
const GDALColorTable* palette_of(GDALRasterBand* b) {
  return b->GetColorInterpretation() == GCI_PaletteIndex ? b->GetColorTable() : nullptr;
}

// A palette band's indices as their colours' red values, as OpenImageIO reads a palette image (it expands
// the palette, and a height is read from the first channel): the same file gives the same heights through
// either reader (docs/heights.md). The band's NoData index is a hole (NaN), never compared with the reds;
// an index outside the palette is left as it is. Built once per read; a band without a palette leaves its
// values alone.
struct PaletteReds {
  std::vector<float> red;
  std::optional<double> nodata;

  explicit PaletteReds(GDALRasterBand* b) {
    const GDALColorTable* table = palette_of(b);
    if (!table) return;
    red.resize(std::size_t(std::max(0, table->GetColorEntryCount())));
    for (std::size_t i = 0; i < red.size(); ++i) red[i] = float(table->GetColorEntry(int(i))->c1);
    nodata = band_nodata(*b->GetDataset(), b);
  }
  void apply(float* values, std::size_t count) const {
    if (red.empty()) return;
    for (std::size_t i = 0; i < count; ++i) {
      const float v = values[i];
      if (nodata && double(v) == *nodata)
        values[i] = std::numeric_limits<float>::quiet_NaN();
      else if (v >= 0 && v < float(red.size()))
        values[i] = red[std::size_t(v)];
    }
  }
};

// The sample type the heights line names: GDAL's, and that a palette's colours are read.
std::string sample_type_of(GDALRasterBand* b) {
  std::string t = GDALGetDataTypeName(b->GetRasterDataType());
  if (palette_of(b)) t = "red of its palette, " + t;
  return t;
}

}  // namespace

namespace {

// The local file behind a name GDAL lists: the name itself, or for a file inside an archive
// ("/vsizip//data/a.zip/dem.tif", "/vsitar/{/data/a.tar}/dem.tif", "/vsigzip//data/dem.tif.gz") the archive;
// empty for what no local file holds (a network /vsi path).
fs::path local_file_of(const std::string& name) {
  for (const char* prefix : {"/vsizip/", "/vsitar/", "/vsigzip/", "/vsi7z/", "/vsirar/"}) {
    const std::string_view p(prefix);
    if (name.compare(0, p.size(), p) != 0) continue;
    std::string rest = name.substr(p.size());
    if (!rest.empty() && rest.front() == '{') {
      const std::size_t close = rest.find('}');
      return close == std::string::npos ? fs::path() : local_file_of(rest.substr(1, close - 1));
    }
    // The longest leading part that is a file: the archive (an archive inside an archive: the outer one).
    std::error_code ec;
    for (fs::path candidate(rest); !candidate.empty() && candidate != candidate.parent_path();
         candidate = candidate.parent_path())
      if (fs::is_regular_file(candidate, ec)) return local_file_of(candidate.string());
    return {};
  }
  if (name.compare(0, 4, "/vsi") == 0) return {};
  return fs::path(name);
}

}  // namespace

std::vector<fs::path> raster_files(const fs::path& file) {
  std::vector<fs::path> files = {file};
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return files;
  GdalQuiet gdal;
  std::set<fs::path> seen = {fs::weakly_canonical(fs::absolute(file), ec)};  // each file once, however named
  const auto known = [&](const fs::path& p) {
    std::error_code canonical;
    return !seen.insert(fs::weakly_canonical(fs::absolute(p), canonical)).second;
  };
  // Breadth first through what each dataset lists: a VRT's source may be a VRT of its own (a loop of them
  // ends where a file is listed again; at most kMostFiles files are followed).
  constexpr std::size_t kMostFiles = 100000;
  std::vector<std::string> open = {file.string()};
  for (std::size_t next = 0; next < open.size() && files.size() < kMostFiles; ++next) {
    std::unique_ptr<GDALDataset> ds(
        GDALDataset::Open(open[next].c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
    if (!ds) continue;
    char** list = ds->GetFileList();
    for (char** f = list; f && *f; ++f) {
      const fs::path local = local_file_of(*f);
      if (local.empty() || known(local) || !fs::is_regular_file(local, ec)) continue;
      files.push_back(local);
      open.emplace_back(*f);  // opened in turn: a nested VRT lists its own sources
    }
    CSLDestroy(list);
  }
  return files;
}

namespace {

// The percentage of the band GDAL reports as covered by none of its sources' data (a mosaic's gaps).
double uncovered_percent(GDALRasterBand& band) {
  double covered = 100;
  const int status = band.GetDataCoverageStatus(0, 0, band.GetXSize(), band.GetYSize(), 0, &covered);
  return status & GDAL_DATA_COVERAGE_STATUS_EMPTY ? std::clamp(100 - covered, 0.0, 100.0) : 0.0;
}

// A GeoTIFF's: the percentage of its area in blocks the file does not hold (offset or size 0: a sparse
// file's missing blocks). Not GDAL's coverage status, which also counts a written block of zeros that the
// file system keeps as a hole (GDAL writes an uncompressed file's zeros so) as not covered.
double missing_tiff_blocks_percent(GDALRasterBand& band) {
  int bw = 0, bh = 0;
  band.GetBlockSize(&bw, &bh);
  const int w = band.GetXSize(), h = band.GetYSize();
  if (bw < 1 || bh < 1 || w < 1 || h < 1) return 0;
  double missing = 0;
  for (int by = 0; by * bh < h; ++by)
    for (int bx = 0; bx * bw < w; ++bx) {
      const std::string at = std::to_string(bx) + "_" + std::to_string(by);
      const char* offset = band.GetMetadataItem(("BLOCK_OFFSET_" + at).c_str(), "TIFF");
      const char* size = band.GetMetadataItem(("BLOCK_SIZE_" + at).c_str(), "TIFF");
      if (!offset || !size || std::atoll(offset) == 0 || std::atoll(size) == 0)
        missing += double(std::min(bw, w - bx * bw)) * double(std::min(bh, h - by * bh));
    }
  return 100.0 * missing / (double(w) * double(h));
}

}  // namespace

std::optional<GeoRasterInfo> probe_georaster(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return std::nullopt;  // the OpenImageIO path names the problem
  GdalQuiet gdal;
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds || ds->GetRasterCount() < 1) return std::nullopt;
  GeoRasterInfo info;
  info.driver = ds->GetDriver() ? ds->GetDriver()->GetDescription() : "";
  info.width = ds->GetRasterXSize();
  info.height = ds->GetRasterYSize();
  info.bands = ds->GetRasterCount();
  info.has_geotransform = ds->GetGeoTransform(info.geotransform.data()) == CE_None;
  if (const OGRSpatialReference* srs = ds->GetSpatialRef(); srs && !srs->IsEmpty()) {
    char* wkt = nullptr;
    const char* const options[] = {"FORMAT=WKT2_2019", nullptr};
    if (srs->exportToWkt(&wkt, options) == OGRERR_NONE && wkt) info.crs_wkt = wkt;
    CPLFree(wkt);
    if (const char* name = srs->GetName()) info.crs_name = name;
    info.geographic = srs->IsGeographic() != 0;
    if (info.geographic) {
      const char* unit = nullptr;
      info.angular_unit_radians = srs->GetAngularUnits(&unit);
      if (unit) info.angular_unit = unit;
    }
    if (srs->IsProjected()) {
      const char* unit = nullptr;
      info.linear_unit_metres = srs->GetLinearUnits(&unit);
      if (unit) info.linear_unit = unit;
    }
  }
  if (!info.has_geotransform) {
    if (ds->GetGCPCount() > 0)
      info.placed_by = "ground control points";
    else if (ds->GetMetadata("RPC"))
      info.placed_by = "RPCs";
    else if (ds->GetMetadata("GEOLOCATION"))
      info.placed_by = "geolocation arrays";
  }
  // An image without georeferencing stays with OpenImageIO, but for a TIFF whose values OpenImageIO would
  // change or whose holes it would not see: a declared NoData value, or MinIsWhite samples (OpenImageIO
  // inverts them; GDAL reads them as stored); and for a binary PNM of 16-bit samples (maxval above 255),
  // which OpenImageIO stretches over 0..65535 inexactly (a maxval of 40000 read as 0..32768).
  const auto gdal_only = [&] {
    if (info.driver == "PNM") return ds->GetRasterBand(1)->GetRasterDataType() == GDT_UInt16;
    if (info.driver != "GTiff") return false;
    if (const char* w = ds->GetMetadataItem("MINISWHITE", "IMAGE_STRUCTURE"); w && CPLTestBool(w))
      return true;
    for (int b = 1; b <= info.bands; ++b) {
      int has = 0;
      ds->GetRasterBand(b)->GetNoDataValue(&has);
      if (has) return true;
    }
    return false;
  };
  if (!info.has_geotransform && info.crs_wkt.empty() && info.placed_by.empty() && asset_driver(info.driver) &&
      !gdal_only())
    return std::nullopt;
  info.palette = info.bands == 1 && palette_of(ds->GetRasterBand(1));
  for (int b = 1; b <= info.bands; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b);
    info.band_names.push_back(band->GetDescription());
    switch (band->GetColorInterpretation()) {
      case GCI_RedBand:
        info.band_colours.emplace_back("R");
        break;
      case GCI_GreenBand:
        info.band_colours.emplace_back("G");
        break;
      case GCI_BlueBand:
        info.band_colours.emplace_back("B");
        break;
      case GCI_AlphaBand:
        info.band_colours.emplace_back("A");
        break;
      default:
        info.band_colours.emplace_back();
        break;
    }
    // A palette's NoData index is read as a hole (PaletteReds), not compared with its reds.
    info.nodata.push_back(info.palette ? std::nullopt : band_nodata(*ds, band));
    int has = 0;
    const double scale = band->GetScale(&has);
    info.scale.push_back(has ? scale : 1.0);
    has = 0;
    const double offset = band->GetOffset(&has);
    info.offset.push_back(has ? offset : 0.0);
    const char* unit = band->GetUnitType();
    info.unit_types.emplace_back(unit ? unit : "");
    info.uncovered_percent.push_back(info.driver == "GTiff" ? missing_tiff_blocks_percent(*band)
                                                            : uncovered_percent(*band));
  }
  return info;
}

std::string geographic_unit_problem(const GeoRasterInfo& info) {
  constexpr double kDegree = 3.14159265358979323846 / 180;
  if (!info.geographic || std::fabs(info.angular_unit_radians - kDegree) <= 1e-12) return "";
  return "has a geographic CRS (" + info.crs_name + ") in " +
         (info.angular_unit.empty() ? std::string("an angular unit that is not the degree")
                                    : info.angular_unit + "s") +
         ", not degrees, which hfbake reads a geographic geotransform in: warp it to degrees first (gdalwarp "
         "-t_srs EPSG:4326 in.tif out.tif, or to a projected CRS)";
}

std::string uncovered_problem(const GeoRasterInfo& info, int band) {
  const std::size_t b = std::size_t(band);
  if (b >= info.uncovered_percent.size() || info.uncovered_percent[b] <= 0 || info.nodata[b]) return "";
  char pct[32];
  std::snprintf(pct, sizeof pct, "%.3g", info.uncovered_percent[b]);
  return std::string(pct) +
         " % of it is covered by none of its data (gaps between a mosaic's sources, or a sparse file's "
         "missing blocks), where GDAL reads 0 m: declare a NoData value for the gaps (gdalbuildvrt "
         "-vrtnodata -9999, or gdal_edit.py -a_nodata) so that they are read as holes, or crop "
         "them away";
}

Plane read_georaster_band(const fs::path& file, int band, const InputSite& site,
                          const ReadProgress& progress) {
  GdalQuiet gdal;
  const std::unique_ptr<GDALDataset> ds = open_raster(file, site, gdal);
  GDALRasterBand* b = band_of(*ds, file, band, site);
  Plane plane;
  plane.width = ds->GetRasterXSize();
  plane.height = ds->GetRasterYSize();
  plane.values.resize(std::size_t(plane.width) * std::size_t(plane.height));
  const GDALDataType type = b->GetRasterDataType();
  plane.sample_type = sample_type_of(b);
  plane.integer = GDALDataTypeIsInteger(type) != 0;
  int block_x = 0, block_y = 0;
  b->GetBlockSize(&block_x, &block_y);
  block_y = std::clamp(block_y, 1, plane.height);
  const PaletteReds reds(b);
  // Whole block rows, at least 256 rows (strips of one row would make a band per row).
  const int rows = (256 + block_y - 1) / block_y * block_y;
  for (int y0 = 0; y0 < plane.height; y0 += rows) {
    const int n = std::min(rows, plane.height - y0);
    float* dst = plane.values.data() + std::size_t(y0) * std::size_t(plane.width);
    if (!read_rows(b, 0, y0, plane.width, n, dst, file, site))
      throw InputError(site.job_file, site.pointer,
                       file.string() + ": cannot decode the raster (corrupt or truncated?) at row " +
                           std::to_string(y0) + ": " + gdal.error(file.string()));
    reds.apply(dst, std::size_t(n) * std::size_t(plane.width));
    ds->FlushCache();  // read-only: drops the cached blocks (of every band: pixel-interleaved files cache
                       // all)
    if (progress) progress(double(y0 + n) / plane.height);
  }
  return plane;
}

std::string georaster_metadata_item(const fs::path& file, const std::string& key) {
  GdalQuiet gdal;
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds) return "";
  const char* value = ds->GetMetadataItem(key.c_str());
  return value ? value : "";
}

GdalCacheLimit::GdalCacheLimit(std::size_t bytes) : previous_(GDALGetCacheMax64()) {
  GDALSetCacheMax64(GIntBig(bytes));
}

GdalCacheLimit::~GdalCacheLimit() {
  GDALSetCacheMax64(GIntBig(previous_));
}

Plane read_georaster_window(const fs::path& file, int band, int x0, int y0, int width, int height,
                            const InputSite& site) {
  GdalQuiet gdal;
  const std::unique_ptr<GDALDataset> ds = open_raster(file, site, gdal);
  GDALRasterBand* b = band_of(*ds, file, band, site);
  const std::string window = "columns " + std::to_string(x0) + ".." + std::to_string(x0 + width - 1) +
                             ", rows " + std::to_string(y0) + ".." + std::to_string(y0 + height - 1);
  if (width < 1 || height < 1 || x0 < 0 || y0 < 0 || x0 > ds->GetRasterXSize() - width ||
      y0 > ds->GetRasterYSize() - height)
    throw InputError(site.job_file, site.pointer, file.string() + ": has no " + window);
  Plane plane;
  plane.width = width;
  plane.height = height;
  plane.values.resize(std::size_t(width) * std::size_t(height));
  const GDALDataType type = b->GetRasterDataType();
  plane.sample_type = sample_type_of(b);
  plane.integer = GDALDataTypeIsInteger(type) != 0;
  if (!read_rows(b, x0, y0, width, height, plane.values.data(), file, site))
    throw InputError(site.job_file, site.pointer,
                     file.string() + ": cannot decode the raster (corrupt or truncated?) at " + window +
                         ": " + gdal.error(file.string()));
  PaletteReds(b).apply(plane.values.data(), plane.values.size());
  ds->FlushCache();
  return plane;
}

}  // namespace hfbake
