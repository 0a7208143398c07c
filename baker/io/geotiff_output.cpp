#include "io/geotiff_output.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "io/gdal_quiet.hpp"

namespace hfbake {
namespace fs = std::filesystem;

// Outside the anonymous namespace: TiledGeoTiff::Dataset (a class of external linkage) holds one.
struct GeoTiffDatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, GeoTiffDatasetCloser>;

namespace {

constexpr int kCogTile = 512;  // the COGs' tiles, kCogTile x kCogTile texels (copy_to_cog's BLOCKSIZE)

// The CRS and geotransform of `geo` and the metadata of `options` on `ds`.
template <class Fail>
void set_georeference(GDALDataset& ds, const Georeference& geo, const GeoTiffOptions& options, Fail fail) {
  std::array<double, 6> gt = geo.geotransform;
  ds.SetGeoTransform(gt.data());
  if (!geo.crs_wkt.empty()) {
    OGRSpatialReference srs;
    if (srs.importFromWkt(geo.crs_wkt.c_str()) != OGRERR_NONE) fail("cannot use the input's CRS");
    srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    ds.SetSpatialRef(&srs);
  }
  for (const auto& [key, value] : options.metadata) ds.SetMetadataItem(key.c_str(), value.c_str());
}

// Every band of `ds`, layer `layer`'s, declares the layer's unit (core/layers.hpp LayerUnit): "degree", or
// for a distance the CRS's linear unit ("metre" for a geographic raster's local frame; none without a CRS).
void set_band_units(GDALDataset& ds, const std::string& layer, const Georeference& geo) {
  const LayerKind* kind = find_layer_kind(layer);
  std::string unit;
  if (kind && kind->unit == LayerUnit::degree) unit = "degree";
  if (kind && kind->unit == LayerUnit::distance && !geo.crs_wkt.empty()) {
    OGRSpatialReference srs;
    if (srs.importFromWkt(geo.crs_wkt.c_str()) == OGRERR_NONE) {
      const char* name = nullptr;
      if (srs.IsGeographic())
        unit = "metre";
      else if (srs.IsProjected() && (srs.GetLinearUnits(&name), name))
        unit = name;
    }
  }
  if (unit.empty()) return;
  for (int b = 1; b <= ds.GetRasterCount(); ++b) ds.GetRasterBand(b)->SetUnitType(unit.c_str());
}

// `source` as the COG `file`: DEFLATE (level 1) with the floating-point predictor, 512x512 blocks, average
// overviews, written under a temporary name beside `file` and renamed into place. Failure -> InputError
// naming `file`. Level 1: the low bits of float results are noise to DEFLATE, and the default level 6
// spent about twice the CPU for files 2 % smaller (docs/gis.md).
void copy_to_cog(const fs::path& file, GDALDataset& source) {
  auto fail = [&](const std::string& what) { throw InputError(file.string(), "", what); };
  GdalQuiet gdal;
  GDALDriver* cog_driver = GetGDALDriverManager()->GetDriverByName("COG");
  if (!cog_driver) fail("GDAL has no COG driver");
  // GDAL creates the file by name (following a link there): in a folder made for it, named by mkdtemp, so
  // nothing in it can have been planted (docs/output_folders.md).
  std::string dot(1, '.');  // (built up in steps: GCC 12 warns falsely on "." + string)
  std::optional<TempFolder> folder;
  try {
    folder.emplace(file.parent_path() / dot.append(file.filename().string()));
  } catch (const std::system_error& e) {
    fail(e.what());
  }
  const fs::path tmp = folder->path() / file.filename();
  const std::string block_size = "BLOCKSIZE=" + std::to_string(kCogTile);
  const char* const cog_options[] = {
      "COMPRESS=DEFLATE",   "LEVEL=1",          "PREDICTOR=YES", block_size.c_str(),
      "RESAMPLING=AVERAGE", "BIGTIFF=IF_SAFER", nullptr};
  DatasetPtr out(
      cog_driver->CreateCopy(tmp.c_str(), &source, FALSE, const_cast<char**>(cog_options), nullptr, nullptr));
  // On any failure the folder's destructor removes what GDAL wrote.
  if (!out) throw OutputError(file.string(), "", "cannot write the GeoTIFF: " + gdal.error());
  out.reset();  // flushes and closes
  if (CPLGetLastErrorType() >= CE_Failure)
    throw OutputError(file.string(), "", "cannot write the GeoTIFF: " + gdal.error());
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec) throw OutputError(file.string(), "", "cannot move into place: " + ec.message());
}

}  // namespace

std::string geotiff_band_description(const std::string& layer, const std::vector<std::string>& channels,
                                     int c) {
  return channels.size() == 1 ? layer : layer + "." + channels[std::size_t(c)];
}

std::string geotiff_band_channel(const std::string& layer, const std::string& description) {
  if (description == layer) return mono_channels().front();
  return description.substr(std::min(description.size(), layer.size() + 1));
}

void write_geotiff(const fs::path& file, const LayerSet& layers, const Layer& layer, const Georeference& geo,
                   const GeoTiffOptions& options) {
  const int w = layers.width, h = layers.height, nc = layer.channel_count();
  const std::size_t n = std::size_t(w) * std::size_t(h);
  if (nc < 1 || layer.data.size() != n * std::size_t(nc))
    throw std::logic_error("write_geotiff: layer " + layer.name + " has the wrong size");
  const bool holes = geo.holes.size() == n;
  auto fail = [&](const std::string& what) { throw InputError(file.string(), "", what); };

  GdalQuiet gdal;
  GDALDriver* mem_driver = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* cog_driver = GetGDALDriverManager()->GetDriverByName("COG");
  if (!mem_driver || !cog_driver) fail("GDAL has no MEM or COG driver");
  // The raster GDAL copies from is the layer's own values, pixel-interleaved as they are (each band a view
  // of every nc-th float: no copy of a 64-channel stack's 256 MiB, and GDAL reads whole pixels into the
  // COG's pixel-interleaved tiles); with holes, a copy holding NoData there. GDAL only reads it.
  std::vector<float> with_holes;
  if (holes) {
    with_holes.resize(layer.data.size());
    for (std::size_t t = 0; t < n; ++t)
      for (int c = 0; c < nc; ++c)
        with_holes[t * std::size_t(nc) + std::size_t(c)] =
            geo.holes[t] ? kGeoTiffNodata : layer.data[t * std::size_t(nc) + std::size_t(c)];
  }
  float* values = holes ? with_holes.data() : const_cast<float*>(layer.data.data());
  DatasetPtr mem(mem_driver->Create("", w, h, 0, GDT_Float32, nullptr));
  if (!mem) fail("cannot make the raster in memory: " + gdal.error());
  const std::string pixel = "PIXELOFFSET=" + std::to_string(sizeof(float) * std::size_t(nc));
  const std::string line = "LINEOFFSET=" + std::to_string(sizeof(float) * std::size_t(nc) * std::size_t(w));
  for (int c = 0; c < nc; ++c) {
    char pointer[64];
    std::snprintf(pointer, sizeof pointer, "DATAPOINTER=%p", static_cast<void*>(values + c));
    const char* const band_options[] = {pointer, pixel.c_str(), line.c_str(), nullptr};
    if (mem->AddBand(GDT_Float32, const_cast<char**>(band_options)) != CE_None)
      fail("cannot make the raster in memory: " + gdal.error());
    GDALRasterBand* band = mem->GetRasterBand(c + 1);
    band->SetDescription(geotiff_band_description(layer.name, layer.channels, c).c_str());
    if (holes) band->SetNoDataValue(kGeoTiffNodata);
  }
  set_georeference(*mem, geo, options, fail);
  set_band_units(*mem, layer.name, geo);
  copy_to_cog(file, *mem);
}

double cog_band_bytes(int width, int height) {
  const double tile = 4.0 * kCogTile * kCogTile;
  const double window = 4.0 * std::min(width, kCogTile) * std::min(height, kCogTile);
  return 4 * tile + 2 * window + 512.0 * (double(width) + double(height));
}

double geotiff_writing_bytes(int width, int height, int channels, bool holes) {
  double overview_texels = 0;
  for (long long w = width, h = height; w > kCogTile || h > kCogTile;) {
    w /= 2, h /= 2;
    overview_texels += double(w) * double(h);
  }
  const double overviews = std::min(4.0 * channels * overview_texels, double(GDALGetCacheMax64()));
  const double copy = holes ? 4.0 * channels * double(width) * double(height) : 0.0;
  return cog_band_bytes(width, height) * channels + overviews + copy;
}

struct TiledGeoTiff::Dataset {
  DatasetPtr ds;
};

TiledGeoTiff::TiledGeoTiff(const fs::path& work, int width, int height, const std::string& layer,
                           const std::vector<std::string>& channels, const Georeference& geo,
                           const GeoTiffOptions& options)
    : dataset_(std::make_unique<Dataset>()), work_(work), channels_(int(channels.size())) {
  auto fail = [&](const std::string& what) { throw InputError(work.string(), "", what); };
  if (channels_ < 1 || width < 1 || height < 1) throw std::logic_error("TiledGeoTiff: empty raster");
  GdalQuiet gdal;
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (!driver) fail("GDAL has no GTiff driver");
  const char* const create_options[] = {"TILED=YES",        "BLOCKXSIZE=256",  "BLOCKYSIZE=256",
                                        "COMPRESS=DEFLATE", "ZLEVEL=1",        "PREDICTOR=3",
                                        "BIGTIFF=YES",      "INTERLEAVE=BAND", nullptr};
  dataset_->ds.reset(driver->Create(work.c_str(), width, height, channels_, GDT_Float32,
                                    const_cast<char**>(create_options)));
  if (!dataset_->ds) fail("cannot create the work file: " + gdal.error());
  for (int c = 0; c < channels_; ++c)
    dataset_->ds->GetRasterBand(c + 1)->SetDescription(geotiff_band_description(layer, channels, c).c_str());
  set_georeference(*dataset_->ds, geo, options, fail);
  set_band_units(*dataset_->ds, layer, geo);
}

TiledGeoTiff::~TiledGeoTiff() {
  if (!dataset_->ds) return;
  GdalQuiet gdal;  // closing flushes the cache: on a full disk, GDAL's messages are not hfbake's line
  dataset_->ds.reset();
  std::error_code ec;
  fs::remove(work_, ec);
}

void TiledGeoTiff::write(int x0, int y0, int width, int height, const float* texels, std::size_t stride) {
  GdalQuiet gdal;
  const GSpacing pixel = GSpacing(sizeof(float)) * channels_, line = pixel * GSpacing(stride);
  for (int c = 0; c < channels_; ++c)
    if (dataset_->ds->GetRasterBand(c + 1)->RasterIO(GF_Write, x0, y0, width, height,
                                                     const_cast<float*>(texels + c), width, height,
                                                     GDT_Float32, pixel, line, nullptr) != CE_None)
      throw OutputError(work_.string(), "", "cannot write: " + gdal.error());
}

void TiledGeoTiff::set_metadata(const std::string& key, const std::string& value) {
  dataset_->ds->SetMetadataItem(key.c_str(), value.c_str());
}

void TiledGeoTiff::finish(const fs::path& file) {
  GdalQuiet gdal;
  dataset_->ds->FlushCache();
  if (CPLGetLastErrorType() >= CE_Failure)
    throw OutputError(work_.string(), "", "cannot write: " + gdal.error());
  copy_to_cog(file, *dataset_->ds);
  dataset_->ds.reset();
  std::error_code ec;
  fs::remove(work_, ec);
}

}  // namespace hfbake
