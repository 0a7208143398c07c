// The result of a bake: named layers of per-texel values, what the EXR writer stores.
#pragma once

#include <cstddef>
#include <deque>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hfbake {

// One layer, e.g. "ao" (1 channel, suffix "Y"), "direct" (R, G, B), "horizon" (K channels "000".."K-1").
// Values are interleaved per texel: data[(j * width + i) * channels.size() + c], row j = image row j.
struct Layer {
  std::string name;
  std::vector<std::string> channels;  // channel suffixes; the EXR channel is name + "." + suffix
  std::vector<float> data;

  int channel_count() const { return int(channels.size()); }
};

// Layer channel suffix sets used across hfbake (see docs/contract.md).
inline std::vector<std::string> mono_channels() {
  return {"Y"};
}
inline std::vector<std::string> rgb_channels() {
  return {"R", "G", "B"};
}
inline std::vector<std::string> xyz_channels() {
  return {"X", "Y", "Z"};
}
std::vector<std::string> indexed_channels(int count);  // "000", "001", ... (zero-padded to 3 digits)

// The layer table: what every output layer name means to the rest of hfbake (docs/contract.md lists them).
// One line per layer; the EXR writer, the memory estimate, the output checks, the report and the reference's
// plan read it. A layer's values come from its producer (a method's bake, and for a scored layer the
// reference's step that `trace` names).

// Its channels: one, three colours, a direction, one per azimuth of the entry's directions (K), or a fixed
// number of indexed channels.
enum class LayerChannels { mono, rgb, xyz, per_direction, indexed };

// How the report scores a method's layer against the reference's layer of the same name.
enum class LayerScore {
  none,        // never scored
  values,      // per-channel value metrics (report/compare.hpp)
  directions,  // and the angle between unit vectors (bent normals)
  elevations,  // and the elevation angles of sines of elevation (horizons)
};

// What the reference computes for a layer some bake entry writes.
enum class LayerTrace {
  none,           // nothing: the layer is never scored
  path_traced,    // traced with the reference's paths (reference/bake_reference: ReferenceOptions::layers)
  horizons,       // bisected horizons at the entry's K (reference/horizon_reference)
  sh_visibility,  // the SH projection of bisected horizons (reference/sh_visibility_reference)
  relief,         // relief's radius-limited horizons, with the first relief entry's settings
                  // (reference/relief_reference)
};

// What limits the distance a layer looks to, and so which reference layer measures the same quantity.
enum class LayerReach {
  unlimited,  // nothing
  falloff,    // the entry's obscurance falloff and radius (and weighting): scored only when the reference's
              // obscurance used the same
  falloff_against_unlimited,  // limited by the entry's falloff when it has one; the reference's has no
                              // limit, so it is scored only for an entry without a falloff (bent normals)
  search_radius,  // the entry's search radius, directions and azimuths: scored only when the reference
                  // traced it with the same (relief)
};

// The unit of a layer's values, as a GeoTIFF band declares it (GDAL's unit type).
enum class LayerUnit {
  none,      // a fraction, a sine, a colour, a direction: no unit
  degree,    // angles in degrees
  distance,  // world units: the CRS's linear unit (metres for a geographic raster's local frame)
};

// The values a layer holds, checked before it is written (cli/outputs check_layers_finite).
enum class LayerValues {
  finite,    // any finite number
  fraction,  // a fraction of the sky, in [0, 1] up to a quadrature's error
  distance,  // finite, or +inf where nothing lies behind the texel
};

struct LayerKind {
  std::string_view name;
  bool numbered = false;  // a family: name followed by 1, 2, ... ("indirect_b" names indirect_b1, ...)
  LayerChannels channels = LayerChannels::mono;
  int indexed = 0;  // LayerChannels::indexed: how many
  LayerScore score = LayerScore::none;
  LayerTrace trace = LayerTrace::none;
  LayerReach reach = LayerReach::unlimited;
  LayerValues values = LayerValues::finite;
  // Stored as float in an EXR whatever the job's pixel_type: angles in degrees, where half's steps (0.03°
  // to 0.06° above 32°) would be coarser than the method (docs/gis.md).
  bool float_storage = false;
  LayerUnit unit = LayerUnit::none;
};

// Every layer kind, the table's lines first.
std::span<const LayerKind> layer_kinds();
// The kind of layer `name` (a numbered family's member included); nullptr for a name the table lacks.
const LayerKind* find_layer_kind(std::string_view name);
// The channels of layer `name` for an entry of `directions` azimuths (a name the table lacks: one).
int layer_channel_count(std::string_view name, int directions);
// Whether layer `name` holds unit directions (written as normal maps, previewed as 0.5 + 0.5 v).
bool is_direction_layer(std::string_view name);

// Adds a kind to layer_kinds() for the object's lifetime: how a test adds a layer through the table. Not
// for bakes; not thread-safe (construct it before anything reads the table).
class ExtraLayerKind {
 public:
  explicit ExtraLayerKind(const LayerKind& kind);
  ~ExtraLayerKind();
  ExtraLayerKind(const ExtraLayerKind&) = delete;
  ExtraLayerKind& operator=(const ExtraLayerKind&) = delete;
};

struct LayerSet {
  int width = 0, height = 0;
  std::deque<Layer> layers;  // a deque: add() never moves the layers already there
  // Metadata written into the EXR header as string attributes (method, parameters, ...).
  std::vector<std::pair<std::string, std::string>> attributes;

  // Adds a zero-filled layer and returns it. The reference stays valid as more layers are added (several
  // tests and bakes fill layers they added earlier: AddressSanitizer found one reading a moved layer).
  Layer& add(std::string name, std::vector<std::string> channels);
  // Adds a layer holding `data` (moved in, not copied: width * height * channels values, checked).
  Layer& adopt(std::string name, std::vector<std::string> channels, std::vector<float> data);
  const Layer* find(const std::string& name) const;
  Layer* find(const std::string& name);
};

}  // namespace hfbake
