#include "io/geotiff_output.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <unistd.h>

#include <memory>
#include <stdexcept>

#include "core/error.hpp"
#include "io/gdal_quiet.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

}  // namespace

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
  DatasetPtr mem(mem_driver->Create("", w, h, nc, GDT_Float32, nullptr));
  if (!mem) fail("cannot make the raster in memory: " + gdal.error());

  std::vector<float> plane(n);
  for (int c = 0; c < nc; ++c) {
    for (std::size_t t = 0; t < n; ++t)
      plane[t] = holes && geo.holes[t] ? kGeoTiffNodata : layer.data[t * std::size_t(nc) + std::size_t(c)];
    GDALRasterBand* band = mem->GetRasterBand(c + 1);
    if (band->RasterIO(GF_Write, 0, 0, w, h, plane.data(), w, h, GDT_Float32, 0, 0, nullptr) != CE_None)
      fail("cannot fill the raster: " + gdal.error());
    band->SetDescription((layer.name + "." + layer.channels[std::size_t(c)]).c_str());
    if (holes) band->SetNoDataValue(kGeoTiffNodata);
  }
  std::array<double, 6> gt = geo.geotransform;
  mem->SetGeoTransform(gt.data());
  if (!geo.crs_wkt.empty()) {
    OGRSpatialReference srs;
    if (srs.importFromWkt(geo.crs_wkt.c_str()) != OGRERR_NONE) fail("cannot use the input's CRS");
    srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    mem->SetSpatialRef(&srs);
  }
  for (const auto& [key, value] : options.metadata) mem->SetMetadataItem(key.c_str(), value.c_str());

  std::string tmp_name(1, '.');  // (built up in steps: GCC 12 warns falsely on "." + string)
  tmp_name.append(file.filename().string()).append(".tmp-").append(std::to_string(getpid()));
  const fs::path tmp = file.parent_path() / tmp_name;
  const char* const cog_options[] = {"COMPRESS=DEFLATE",   "PREDICTOR=YES",    "BLOCKSIZE=512",
                                     "RESAMPLING=AVERAGE", "BIGTIFF=IF_SAFER", nullptr};
  DatasetPtr out(cog_driver->CreateCopy(tmp.c_str(), mem.get(), FALSE, const_cast<char**>(cog_options),
                                        nullptr, nullptr));
  if (!out) {
    std::error_code ec;
    fs::remove(tmp, ec);
    fail("cannot write the GeoTIFF: " + gdal.error());
  }
  out.reset();  // flushes and closes
  if (CPLGetLastErrorType() >= CE_Failure) {
    std::error_code ec;
    fs::remove(tmp, ec);
    fail("cannot write the GeoTIFF: " + gdal.error());
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec) {
    fs::remove(tmp, ec);
    fail("cannot move into place: " + ec.message());
  }
}

}  // namespace hfbake
