#include "io/preview.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "core/error.hpp"
#include "io/color.hpp"
#include "io/exr_output.hpp"
#include "io/oiio_codec.hpp"

namespace hfbake {
namespace fs = std::filesystem;

PreviewSize preview_size(int width, int height, int max_size) {
  PreviewSize size{width, height, 1};
  const int longer = std::max(width, height);
  if (max_size <= 0 || longer <= max_size) return size;
  size.factor = (longer + max_size - 1) / max_size;
  size.width = (width + size.factor - 1) / size.factor;
  size.height = (height + size.factor - 1) / size.factor;
  return size;
}

namespace {

// The layer as linear RGB at the preview's size: a copy when it fits, else the f x f box means of the finite
// values, accumulated one band of f rows at a time (memory: the preview's, plus one row of sums).
std::vector<float> preview_rgb(const LayerSet& layers, const Layer& layer, const PreviewSize& size) {
  const int w = layers.width, h = layers.height, nc = layer.channel_count();
  const std::size_t out_n = std::size_t(size.width) * std::size_t(size.height);
  std::vector<float> rgb(out_n * 3);
  if (size.factor == 1) {
    for (std::size_t i = 0; i < out_n; ++i)
      for (int c = 0; c < 3; ++c) rgb[3 * i + c] = layer.data[i * nc + (nc == 1 ? 0 : c)];
    return rgb;
  }
  const int f = size.factor;
  std::vector<double> sum(std::size_t(size.width) * nc);
  std::vector<int> count(sum.size());
  for (int py = 0; py < size.height; ++py) {
    std::fill(sum.begin(), sum.end(), 0.0);
    std::fill(count.begin(), count.end(), 0);
    for (int y = py * f; y < std::min(h, py * f + f); ++y) {
      const float* row = layer.data.data() + std::size_t(y) * std::size_t(w) * nc;
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < nc; ++c) {
          const float v = row[std::size_t(x) * nc + c];
          if (!std::isfinite(v)) continue;
          const std::size_t k = std::size_t(x / f) * nc + c;
          sum[k] += v;
          ++count[k];
        }
    }
    for (int px = 0; px < size.width; ++px)
      for (int c = 0; c < 3; ++c) {
        const std::size_t k = std::size_t(px) * nc + (nc == 1 ? 0 : c);
        rgb[(std::size_t(py) * size.width + px) * 3 + c] =
            count[k] ? float(sum[k] / count[k]) : std::numeric_limits<float>::quiet_NaN();
      }
  }
  return rgb;
}

}  // namespace

bool is_previewed(std::string_view name, int channels) {
  const std::string_view stderr_tail = "_stderr";
  const bool stderr_layer =
      name.size() > stderr_tail.size() && name.substr(name.size() - stderr_tail.size()) == stderr_tail;
  return (channels == 1 || channels == 3) && !stderr_layer;
}

void write_preview(const fs::path& file, const LayerSet& layers, const Layer& layer,
                   const PreviewOptions& options) {
  const int nc = layer.channel_count();
  const std::size_t n = std::size_t(layers.width) * layers.height;
  if ((nc != 1 && nc != 3) || layer.data.size() != n * std::size_t(nc))
    throw std::logic_error("write_preview: layer " + layer.name +
                           " is not a 1- or 3-channel layer of the set's size");
  const PreviewSize size = preview_size(layers.width, layers.height, options.max_size);
  const int w = size.width, h = size.height;
  std::vector<float> rgb = preview_rgb(layers, layer, size);
  const bool direction = is_direction_layer(layer.name);
  std::string description;
  if (options.stretch && !direction) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (const float v : rgb)
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    for (float& v : rgb) v = !std::isfinite(v) ? v : hi > lo ? (v - lo) / (hi - lo) : 0.5f;
    char range[160];
    std::snprintf(range, sizeof range, "%s: black %.6g, white %.6g", layer.name.c_str(), lo, hi);
    if (lo <= hi) description = range;
  } else if (direction) {
    for (float& v : rgb) v = 0.5f + 0.5f * v;
  } else {
    convert_to_display(rgb, options.display, options.view, InputSite{file.string(), ""});
  }
  std::vector<std::uint8_t> bytes(rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    const float v = std::isfinite(rgb[i]) ? std::clamp(rgb[i], 0.0f, 1.0f) : 0.0f;
    bytes[i] = std::uint8_t(std::lround(v * 255.0f));
  }

  std::error_code ec;
  const fs::path tmp = temporary_sibling(file);
  // The temporary name must still end in .png so OpenImageIO picks the PNG writer.
  const fs::path tmp_png = tmp.string() + ".png";
  OiioWrite png;
  png.format = "png";
  png.width = w, png.height = h, png.channels = 3;
  png.text_attributes = {{"oiio:ColorSpace", direction || options.stretch ? "Raw" : "sRGB"}};
  if (!description.empty()) png.text_attributes.emplace_back("ImageDescription", description);
  std::string err;
  if (!oiio_codec().write(tmp_png.string(), png, bytes.data(), err)) {
    if (const auto nl = err.find('\n'); nl != std::string::npos) err.resize(nl);
    fs::remove(tmp_png, ec);
    throw OutputError(file.string(), "", "cannot write the preview: " + err);
  }
  fs::rename(tmp_png, file, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp_png, ignored);
    throw OutputError(file.string(), "", "cannot move the preview into place: " + ec.message());
  }
}

std::string encode_png(int width, int height, int channels, const std::vector<std::uint8_t>& pixels) {
  if (width <= 0 || height <= 0 || (channels != 1 && channels != 3) ||
      pixels.size() != std::size_t(width) * height * channels)
    throw std::invalid_argument("encode_png: bad image size or channel count");
  std::string png, err;
  if (!oiio_codec().encode_png(width, height, channels, pixels.data(), png, err))
    throw std::runtime_error("encode_png: " + err);
  return png;
}

std::vector<float> resize_pixels(const std::vector<float>& pixels, int width, int height, int channels,
                                 int out_width, int out_height, const std::string& filter) {
  if (width <= 0 || height <= 0 || channels <= 0 || out_width <= 0 || out_height <= 0 ||
      pixels.size() != std::size_t(width) * height * channels)
    throw std::invalid_argument("resize_pixels: bad image size or channel count");
  if (out_width == width && out_height == height) return pixels;
  std::vector<float> out;
  std::string err;
  if (!oiio_codec().resize(pixels.data(), width, height, channels, out_width, out_height, filter, out, err))
    throw std::runtime_error("resize_pixels: " + err);
  return out;
}

}  // namespace hfbake
