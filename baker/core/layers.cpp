#include "core/layers.hpp"

#include <stdexcept>

#include <cstdio>

namespace hfbake {

namespace {

using C = LayerChannels;
using S = LayerScore;
using T = LayerTrace;
using R = LayerReach;
using V = LayerValues;

using U = LayerUnit;

// name, numbered, channels, indexed, score, trace, reach, values, float_storage, unit
std::vector<LayerKind>& kinds() {
  static std::vector<LayerKind> table = {
      {"ao", false, C::mono, 0, S::values, T::path_traced, R::unlimited, V::fraction},
      {"vsky", false, C::mono, 0, S::values, T::path_traced, R::unlimited, V::fraction},
      {"obscurance", false, C::mono, 0, S::values, T::path_traced, R::falloff, V::fraction},
      {"direct", false, C::rgb, 0, S::values, T::path_traced, R::unlimited, V::finite},
      {"indirect", false, C::rgb, 0, S::values, T::path_traced, R::unlimited, V::finite},
      {"total", false, C::rgb, 0, S::values, T::path_traced, R::unlimited, V::finite},
      {"bent_normal", false, C::xyz, 0, S::directions, T::path_traced, R::falloff_against_unlimited,
       V::finite},
      {"sh_irradiance", false, C::indexed, 48, S::values, T::path_traced, R::unlimited, V::finite},
      {"indirect_b", true, C::rgb, 0, S::values, T::path_traced, R::unlimited, V::finite},
      {"horizon", false, C::per_direction, 0, S::elevations, T::horizons, R::unlimited, V::finite},
      {"horizon_distance", false, C::per_direction, 0, S::values, T::horizons, R::unlimited, V::distance,
       false, U::distance},
      {"sh_visibility", false, C::indexed, 16, S::values, T::sh_visibility, R::unlimited, V::finite},
      {"svf", false, C::mono, 0, S::values, T::relief, R::search_radius, V::fraction},
      {"openness_positive", false, C::mono, 0, S::values, T::relief, R::search_radius, V::finite, true,
       U::degree},
      {"openness_negative", false, C::mono, 0, S::values, T::relief, R::search_radius, V::finite, true,
       U::degree},
      {"horizon_deg", false, C::per_direction, 0, S::values, T::relief, R::search_radius, V::finite, true,
       U::degree},
      {"normal", false, C::xyz, 0, S::none, T::none, R::unlimited, V::finite},  // the height field's own
  };
  return table;
}

bool names(const LayerKind& k, std::string_view name) {
  if (!k.numbered) return name == k.name;
  if (name.size() <= k.name.size() || name.substr(0, k.name.size()) != k.name) return false;
  const std::string_view n = name.substr(k.name.size());
  if (n.front() == '0') return false;
  for (const char c : n)
    if (c < '0' || c > '9') return false;
  return true;
}

}  // namespace

std::span<const LayerKind> layer_kinds() {
  return kinds();
}

const LayerKind* find_layer_kind(std::string_view name) {
  for (const LayerKind& k : kinds())
    if (names(k, name)) return &k;
  return nullptr;
}

int layer_channel_count(std::string_view name, int directions) {
  const LayerKind* k = find_layer_kind(name);
  if (!k) return 1;
  switch (k->channels) {
    case LayerChannels::mono:
      return 1;
    case LayerChannels::rgb:
    case LayerChannels::xyz:
      return 3;
    case LayerChannels::per_direction:
      return directions;
    case LayerChannels::indexed:
      return k->indexed;
  }
  return 1;
}

bool is_direction_layer(std::string_view name) {
  const LayerKind* k = find_layer_kind(name);
  return k && k->channels == LayerChannels::xyz;
}

ExtraLayerKind::ExtraLayerKind(const LayerKind& kind) {
  kinds().push_back(kind);
}

ExtraLayerKind::~ExtraLayerKind() {
  kinds().pop_back();
}

std::vector<std::string> indexed_channels(int count) {
  std::vector<std::string> names;
  names.reserve(count);
  for (int k = 0; k < count; ++k) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%03d", k);
    names.emplace_back(buf);
  }
  return names;
}

Layer& LayerSet::add(std::string name, std::vector<std::string> channels) {
  Layer layer;
  layer.name = std::move(name);
  layer.data.assign(std::size_t(width) * std::size_t(height) * channels.size(), 0.0f);
  layer.channels = std::move(channels);
  layers.push_back(std::move(layer));
  return layers.back();
}

Layer& LayerSet::adopt(std::string name, std::vector<std::string> channels, std::vector<float> data) {
  if (data.size() != std::size_t(width) * std::size_t(height) * channels.size())
    throw std::logic_error("LayerSet::adopt: layer " + name + " has " + std::to_string(data.size()) +
                           " values for " + std::to_string(width) + "x" + std::to_string(height) +
                           " texels x " + std::to_string(channels.size()) + " channels");
  Layer layer;
  layer.name = std::move(name);
  layer.channels = std::move(channels);
  layer.data = std::move(data);
  layers.push_back(std::move(layer));
  return layers.back();
}

const Layer* LayerSet::find(const std::string& name) const {
  for (const Layer& l : layers)
    if (l.name == name) return &l;
  return nullptr;
}

Layer* LayerSet::find(const std::string& name) {
  for (Layer& l : layers)
    if (l.name == name) return &l;
  return nullptr;
}

}  // namespace hfbake
