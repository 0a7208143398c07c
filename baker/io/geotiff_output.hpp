// Writing one layer of a LayerSet as a float32 Cloud-Optimised GeoTIFF (GDAL's COG driver), with the
// input's CRS and geotransform and NoData where the input had holes.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/layers.hpp"
#include "field/georeference.hpp"

namespace hfbake {

// The NoData value of GeoTIFF outputs: outside every layer's range ([0, 1], sines in [-1, 1], XYZ unit
// vectors, SH coefficients of light-like quantities).
inline constexpr float kGeoTiffNodata = -9999.0f;

struct GeoTiffOptions {
  // Dataset metadata items (GDAL's default domain), e.g. {"HFBAKE_METHOD", "p1"}.
  std::vector<std::pair<std::string, std::string>> metadata;
};

// A band's description: the layer's name for a one-channel layer ("ao"), "<layer>.<channel>" for each band
// of a layer of several ("direct.R", "horizon.000"); and back, the channel a band described so holds
// (a one-channel layer's: its only channel, mono_channels()).
std::string geotiff_band_description(const std::string& layer, const std::vector<std::string>& channels,
                                     int c);
std::string geotiff_band_channel(const std::string& layer, const std::string& description);

// `layer` of `layers` as <file>: one float32 band per channel (described by geotiff_band_description),
// DEFLATE (level 1) with the floating-point predictor, 512x512 tiles, overviews (average) as the COG driver
// makes them; the CRS and geotransform of `geo`; texels marked in geo.holes (when not empty) are NoData
// (kGeoTiffNodata, declared on every band) and the NoData tag is written only then. Written under a
// temporary name beside `file` and renamed into place. Failure -> InputError naming the file.
void write_geotiff(const std::filesystem::path& file, const LayerSet& layers, const Layer& layer,
                   const Georeference& geo, const GeoTiffOptions& options = {});

// Bytes write_geotiff holds beside a width x height layer of `channels` channels, for the memory estimate:
// the COG driver's (GDAL's frmts/gtiff/cogdriver.cpp) buffers for the tile it assembles, for every band two
// of the layer's first tile (the window read from the layer and the band's cached block: a whole 512 x 512
// float tile on fields of at least a tile a side) and, fitted to measured peaks, four whole tiles and 512
// bytes per texel of the layer's width plus height (the tile buffer, its predicted and compressed copies,
// and the rows and columns GDAL reads around them: a tiled bake's COG of 16 bands held 6.1 MiB a band at
// 1000^2 and 8.1 at 4096^2, docs/large-fields.md); the overviews it first writes into a temporary GeoTIFF
// (each level half the last while the last is wider or taller than a tile), whose blocks GDAL's block cache
// keeps up to its size (GDAL_CACHEMAX); and with `holes`, the writer's copy of the layer holding NoData.
double geotiff_writing_bytes(int width, int height, int channels, bool holes);
// The per-band part of geotiff_writing_bytes: the COG driver's tile buffers for one band of a width x height
// layer (what a tiled bake's TiledGeoTiff::finish holds beside GDAL's block cache, for every band).
double cog_band_bytes(int width, int height);

// One layer as a COG written a window at a time, never whole in memory: what a tiled bake writes
// (cli/tile_command.hpp). The windows go into a work file (a tiled BigTIFF, 256x256 blocks, DEFLATE), which
// finish() copies into a COG as write_geotiff makes it (the same options, CRS, geotransform, band
// descriptions and metadata); the work file is removed then or on destruction.
class TiledGeoTiff {
 public:
  // `work`: the work file's path (created; InputError naming it when impossible); the raster is width x
  // height with one float32 band per channel of `layer`.
  TiledGeoTiff(const std::filesystem::path& work, int width, int height, const std::string& layer,
               const std::vector<std::string>& channels, const Georeference& geo,
               const GeoTiffOptions& options = {});
  ~TiledGeoTiff();
  TiledGeoTiff(const TiledGeoTiff&) = delete;
  TiledGeoTiff& operator=(const TiledGeoTiff&) = delete;

  // Writes columns [x0, x0 + width) and rows [y0, y0 + height) of the raster from `texels`: channel c of
  // the window's texel (i, j) at texels[(j * stride + i) * channels + c] (a layer's interleaving; `stride`
  // texels a row).
  void write(int x0, int y0, int width, int height, const float* texels, std::size_t stride);
  // A dataset metadata item (GDAL's default domain) the COG carries, set or replaced.
  void set_metadata(const std::string& key, const std::string& value);
  // The COG as `file` (under a temporary name beside it, renamed into place); the work file removed.
  void finish(const std::filesystem::path& file);

 private:
  struct Dataset;
  std::unique_ptr<Dataset> dataset_;
  std::filesystem::path work_;
  int channels_ = 0;
};

}  // namespace hfbake
