// Writing one layer of a LayerSet as a float32 Cloud-Optimised GeoTIFF (GDAL's COG driver), with the
// input's CRS and geotransform and NoData where the input had holes.
#pragma once

#include <filesystem>
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

// `layer` of `layers` as <file>: one float32 band per channel (band description "<layer>.<suffix>"),
// DEFLATE with the floating-point predictor, 512x512 tiles, overviews (average) as the COG driver makes
// them; the CRS and geotransform of `geo`; texels marked in geo.holes (when not empty) are NoData
// (kGeoTiffNodata, declared on every band) and the NoData tag is written only then. Written under a
// temporary name beside `file` and renamed into place. Failure -> InputError naming the file.
void write_geotiff(const std::filesystem::path& file, const LayerSet& layers, const Layer& layer,
                   const Georeference& geo, const GeoTiffOptions& options = {});

}  // namespace hfbake
