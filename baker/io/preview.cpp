#include "io/preview.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "core/error.hpp"
#include "io/color.hpp"
#include "io/exr_output.hpp"

namespace hfbake {
namespace fs = std::filesystem;

void write_preview(const fs::path& file, const LayerSet& layers, const Layer& layer,
                   const PreviewOptions& options) {
  const int w = layers.width, h = layers.height, nc = layer.channel_count();
  const std::size_t n = std::size_t(w) * h;
  if ((nc != 1 && nc != 3) || layer.data.size() != n * std::size_t(nc))
    throw std::logic_error("write_preview: layer " + layer.name +
                           " is not a 1- or 3-channel layer of the set's size");
  std::vector<float> rgb(n * 3);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = layer.data[i * nc + (nc == 1 ? 0 : c)];
  const bool direction = layer.name == "bent_normal";
  if (direction) {
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
  auto out = OIIO::ImageOutput::create("png");
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", direction ? "Raw" : "sRGB");
  if (!out || !out->open(tmp_png.string(), spec) || !out->write_image(OIIO::TypeDesc::UINT8, bytes.data()) ||
      !out->close()) {
    std::string err = out ? out->geterror() : OIIO::geterror();
    if (const auto nl = err.find('\n'); nl != std::string::npos) err.resize(nl);
    fs::remove(tmp_png, ec);
    throw InputError(file.string(), "", "cannot write the preview: " + err);
  }
  fs::rename(tmp_png, file, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp_png, ignored);
    throw InputError(file.string(), "", "cannot move the preview into place: " + ec.message());
  }
}

std::string encode_png(int width, int height, int channels, const std::vector<std::uint8_t>& pixels) {
  if (width <= 0 || height <= 0 || (channels != 1 && channels != 3) ||
      pixels.size() != std::size_t(width) * height * channels)
    throw std::invalid_argument("encode_png: bad image size or channel count");
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  // The name only selects the PNG writer; nothing is written to disk through the proxy.
  auto out = OIIO::ImageOutput::create("memory.png");
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
  if (!out || !out->supports("ioproxy") || !out->set_ioproxy(&proxy) || !out->open("memory.png", spec) ||
      !out->write_image(OIIO::TypeDesc::UINT8, pixels.data()) || !out->close()) {
    std::string err = out ? out->geterror() : OIIO::geterror();
    if (err.empty()) err = "the PNG writer does not write to memory";
    throw std::runtime_error("encode_png: " + err);
  }
  return std::string(bytes.begin(), bytes.end());
}

std::vector<float> resize_pixels(const std::vector<float>& pixels, int width, int height, int channels,
                                 int out_width, int out_height, const std::string& filter) {
  if (width <= 0 || height <= 0 || channels <= 0 || out_width <= 0 || out_height <= 0 ||
      pixels.size() != std::size_t(width) * height * channels)
    throw std::invalid_argument("resize_pixels: bad image size or channel count");
  if (out_width == width && out_height == height) return pixels;
  const OIIO::ImageSpec in_spec(width, height, channels, OIIO::TypeDesc::FLOAT);
  // Wraps the caller's pixels without a copy (ImageBuf only reads them here).
  const OIIO::ImageBuf src(in_spec, const_cast<float*>(pixels.data()));
  OIIO::ImageSpec out_spec(out_width, out_height, channels, OIIO::TypeDesc::FLOAT);
  OIIO::ImageBuf dst(out_spec);
  // nthreads = 1: the result must not depend on how many threads happen to be free.
  if (!OIIO::ImageBufAlgo::resize(dst, src, filter, 0.0f, OIIO::ROI(), 1))
    throw std::runtime_error("resize_pixels: " + dst.geterror());
  std::vector<float> out(std::size_t(out_width) * out_height * channels);
  if (!dst.get_pixels(OIIO::ROI(0, out_width, 0, out_height, 0, 1, 0, channels), OIIO::TypeDesc::FLOAT,
                      out.data()))
    throw std::runtime_error("resize_pixels: " + dst.geterror());
  return out;
}

}  // namespace hfbake
