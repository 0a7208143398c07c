#include "io/texture_output.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"
#include "io/exr_output.hpp"
#include "io/oiio_codec.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

// sRGB's encoding curve (IEC 61966-2-1) of a linear value in [0, 1].
double srgb_encode(double v) {
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
}

int source_index(int x, int n, int padding, bool repeat) {
  const int s = x - padding;
  if (repeat) return ((s % n) + n) % n;
  return std::clamp(s, 0, n - 1);
}

}  // namespace

namespace {

// One channel's source: a layer's channel (data, stride) or a constant.
struct Tap {
  const float* data = nullptr;
  int stride = 0;
  float constant = 0;
};

// The clipping of the layers' values (the field's texels, not the padding) times the exposure: two passes,
// the second a histogram of 4096 bins up to the largest value for the 99th percentile (the upper edge of the
// bin that reaches it), so nothing of the field's size is allocated.
// +inf (a horizon_distance with no caster) is stored as 1 by the format's rule, not clipped.
TextureClipping clipping(const std::vector<Tap>& taps, std::size_t n, double exposure) {
  TextureClipping c;
  std::size_t finite = 0;
  for (const Tap& t : taps) {
    if (!t.data) continue;
    for (std::size_t i = 0; i < n; ++i) {
      const double v = double(t.data[i * std::size_t(t.stride)]) * exposure;
      if (std::isnan(v)) continue;
      ++c.values;
      finite += std::isfinite(v);
      if (v > 1 && std::isfinite(v)) ++c.clipped;
      if (v < -1e-6) ++c.negative;  // a rounding below 0 of a fraction (an ao of -1e-9) is no signed value
      if (std::isfinite(v)) c.largest = std::max(c.largest, v);
    }
  }
  if (c.clipped == 0) return c;
  constexpr int kBins = 4096;
  std::vector<std::size_t> bins(kBins, 0);
  for (const Tap& t : taps) {
    if (!t.data) continue;
    for (std::size_t i = 0; i < n; ++i) {
      const double v = double(t.data[i * std::size_t(t.stride)]) * exposure;
      if (!std::isfinite(v)) continue;
      ++bins[std::size_t(std::clamp(v / c.largest * kBins, 0.0, kBins - 1.0))];
    }
  }
  const double want = 0.99 * double(finite);
  double seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += double(bins[b]);
    if (seen >= want) {
      c.p99 = c.largest * (b + 1) / kBins;
      break;
    }
  }
  return c;
}

}  // namespace

namespace {

// Each channel's source in `layers` (checked against the spec's shape).
std::vector<Tap> texture_taps(const LayerSet& layers, const TextureSpec& spec) {
  const int nc = int(spec.channels.size());
  if (nc != 1 && nc != 3 && nc != 4) throw std::logic_error("texture: 1, 3 or 4 channels");
  if (spec.normal_map && nc != 3) throw std::logic_error("texture: a normal map has 3 channels");
  std::vector<Tap> taps(nc);
  const std::size_t n = std::size_t(layers.width) * std::size_t(layers.height);
  for (int c = 0; c < nc; ++c) {
    const TextureSource& s = spec.channels[c];
    if (s.layer.empty()) {
      taps[c].constant = s.constant;
      continue;
    }
    const Layer* layer = layers.find(s.layer);
    if (!layer || s.channel < 0 || s.channel >= layer->channel_count() ||
        layer->data.size() != n * std::size_t(layer->channel_count()))
      throw std::logic_error("texture: no channel " + std::to_string(s.channel) + " in layer " + s.layer);
    taps[c] = {layer->data.data() + s.channel, layer->channel_count(), 0};
  }
  return taps;
}

// Calls emit(i, c, v) for every value of the (padded) texture, rows top first, i the texel's index: v is the
// channel's value times the exposure, or a normal map's 0.5 + 0.5 n; neither the transfer curve nor the
// clamp.
template <class Emit>
void for_each_texture_value(const LayerSet& layers, const TextureSpec& spec, const std::vector<Tap>& taps,
                            Emit&& emit) {
  const int nc = int(taps.size()), p = spec.padding;
  const int width = layers.width + 2 * p, height = layers.height + 2 * p;
  // The sign of each channel in the chosen frame (normal maps): tangent space with OpenGL's green looks
  // along image up, -y.
  const double sign[3] = {
      1,
      spec.normal_map && spec.space == NormalSpace::tangent && spec.green == GreenAxis::opengl ? -1.0 : 1.0,
      1};
  for (int y = 0; y < height; ++y) {
    const int sy = source_index(y, layers.height, p, spec.repeat);
    for (int x = 0; x < width; ++x) {
      const int sx = source_index(x, layers.width, p, spec.repeat);
      const std::size_t src = std::size_t(sy) * std::size_t(layers.width) + std::size_t(sx);
      const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
      for (int c = 0; c < nc; ++c) {
        double v = taps[c].data ? double(taps[c].data[src * std::size_t(taps[c].stride)]) : taps[c].constant;
        if (!spec.normal_map && taps[c].data) v *= spec.exposure;
        // 0 encodes as 0.5, an exact rounding tie (127.5, 32767.5): float noise of a bake (a flat field's
        // bent normal has |y| ~ 1e-9) would pick either side of it, so components within 1e-6 of 0 are 0.
        if (spec.normal_map) v = 0.5 + 0.5 * sign[c] * (std::abs(v) < 1e-6 ? 0.0 : v);
        emit(i, c, v);
      }
    }
  }
}

// A texture of the layers' size plus the padding on each side, `nc` channels, its values zero.
template <class Texture>
Texture sized_texture(const LayerSet& layers, const TextureSpec& spec, int nc) {
  Texture out;
  out.width = layers.width + 2 * spec.padding;
  out.height = layers.height + 2 * spec.padding;
  out.channels = nc;
  out.values.resize(std::size_t(out.width) * std::size_t(out.height) * std::size_t(nc));
  return out;
}

}  // namespace

TexturePixels texture_pixels(const LayerSet& layers, const TextureSpec& spec) {
  if (spec.bits != 8 && spec.bits != 16) throw std::logic_error("texture_pixels: 8 or 16 bits");
  const std::vector<Tap> taps = texture_taps(layers, spec);
  const int nc = int(taps.size());
  TexturePixels out = sized_texture<TexturePixels>(layers, spec, nc);
  const double top = spec.bits == 8 ? 255.0 : 65535.0;
  for_each_texture_value(layers, spec, taps, [&](std::size_t i, int c, double v) {
    // NaN is 0; an infinity clamps like any value (+inf: a horizon_distance with no caster, as far as any).
    v = std::isnan(v) ? 0.0 : std::clamp(v, 0.0, 1.0);
    if (!spec.normal_map && spec.transfer == Transfer::srgb) v = srgb_encode(v);
    out.values[i * nc + c] = std::uint16_t(std::round(v * top));
  });
  if (!spec.normal_map)
    out.clipping = clipping(taps, std::size_t(layers.width) * std::size_t(layers.height), spec.exposure);
  return out;
}

TextureValues texture_values(const LayerSet& layers, const TextureSpec& spec) {
  const std::vector<Tap> taps = texture_taps(layers, spec);
  const int nc = int(taps.size());
  TextureValues out = sized_texture<TextureValues>(layers, spec, nc);
  for_each_texture_value(layers, spec, taps, [&](std::size_t i, int c, double v) {
    out.values[i * nc + c] = std::isnan(v) ? 0.0f : float(v);  // an infinity stays one (half holds it)
  });
  return out;
}

namespace {

// A half-float OpenEXR texture (float when a value exceeds half's range): the values as they are
// (texture_values), ZIP-compressed; Y, RGB or RGBA.
void write_exr_texture(const fs::path& tmp, const fs::path& file, const LayerSet& layers,
                       const TextureSpec& spec) {
  const TextureValues v = texture_values(layers, spec);
  OiioWrite w;
  w.format = "exr";
  w.width = v.width, w.height = v.height, w.channels = v.channels;
  // Half holds at most 65504: a texture with a larger value (a light map under a bright sun) is stored as
  // float, as the bake's own EXRs are, never as infinity (an infinity in the layer stays one in half).
  float largest = 0;
  for (const float x : v.values)
    if (std::isfinite(x)) largest = std::max(largest, std::abs(x));
  w.stored = largest > 65504.0f ? OiioSample::float32 : OiioSample::half, w.given = OiioSample::float32;
  w.channel_names = v.channels == 1   ? std::vector<std::string>{"Y"}
                    : v.channels == 3 ? std::vector<std::string>{"R", "G", "B"}
                                      : std::vector<std::string>{"R", "G", "B", "A"};
  w.alpha_channel = v.channels == 4 ? 3 : -1;
  w.text_attributes = {{"compression", "zip"}};
  std::string err;
  if (!oiio_codec().write(tmp.string(), w, v.values.data(), err)) {
    if (const auto nl = err.find('\n'); nl != std::string::npos) err.resize(nl);
    std::error_code ec;
    fs::remove(tmp, ec);
    throw OutputError(file.string(), "", "cannot write the texture: " + err);
  }
}

}  // namespace

TextureClipping write_texture(const fs::path& file, const LayerSet& layers, const TextureSpec& spec) {
  const std::string ext = file.extension().string();
  if (ext == ".exr") {
    const fs::path tmp = temporary_sibling(file).string() + ext;
    write_exr_texture(tmp, file, layers, spec);
    std::error_code ec;
    fs::rename(tmp, file, ec);
    if (ec) {
      std::error_code ignored;
      fs::remove(tmp, ignored);
      throw OutputError(file.string(), "", "cannot move the texture into place: " + ec.message());
    }
    return {};  // nothing clipped
  }
  const TexturePixels px = texture_pixels(layers, spec);
  if (spec.bits == 16 && ext == ".tga") throw std::logic_error("write_texture: TGA holds 8 bits");
  OiioWrite w;
  w.format = ext.substr(1);
  w.width = px.width, w.height = px.height, w.channels = px.channels;
  w.stored = w.given = spec.bits == 8 ? OiioSample::uint8 : OiioSample::uint16;
  if (px.channels == 4) w.alpha_channel = 3;
  // Data, not colour, unless the sRGB curve was asked for: no gAMA/sRGB chunk that a viewer would apply.
  if (spec.transfer == Transfer::srgb && !spec.normal_map)
    w.text_attributes.push_back({"oiio:ColorSpace", "sRGB"});
  if (ext == ".tif") w.text_attributes.push_back({"compression", "zip"});
  if (ext == ".tga") w.text_attributes.push_back({"compression", "rle"});
  // A packed RGBA texture's alpha is data of its own: never premultiplied into RGB.
  w.int_attributes.push_back({"oiio:UnassociatedAlpha", 1});
  std::vector<std::uint8_t> bytes;
  const void* data = px.values.data();
  if (spec.bits == 8) {
    bytes.assign(px.values.begin(), px.values.end());
    data = bytes.data();
  }
  const fs::path tmp = temporary_sibling(file).string() + ext;  // keeps the extension: it picks the writer
  std::error_code ec;
  std::string err;
  if (!oiio_codec().write(tmp.string(), w, data, err)) {
    if (const auto nl = err.find('\n'); nl != std::string::npos) err.resize(nl);
    fs::remove(tmp, ec);
    throw OutputError(file.string(), "", "cannot write the texture: " + err);
  }
  fs::rename(tmp, file, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw OutputError(file.string(), "", "cannot move the texture into place: " + ec.message());
  }
  return px.clipping;
}

}  // namespace hfbake
