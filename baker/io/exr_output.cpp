#include "io/exr_output.hpp"

#include <unistd.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/error.hpp"

namespace hfbake {
namespace fs = std::filesystem;

fs::path temporary_sibling(const fs::path& file) {
  static std::atomic<unsigned> counter{0};
  std::string name(1, '.');  // built with append: GCC 12 warns (-Wrestrict) on "." + std::string
  name.append(file.filename().string());
  name.append(".tmp-");
  name.append(std::to_string(getpid()));
  name.append("-");
  name.append(std::to_string(counter.fetch_add(1)));
  return file.parent_path() / name;
}

namespace {

Imf::Compression compression_of(const std::string& name, const fs::path& file) {
  if (name == "zip") return Imf::ZIP_COMPRESSION;
  if (name == "piz") return Imf::PIZ_COMPRESSION;
  if (name == "none") return Imf::NO_COMPRESSION;
  throw InputError(file.string(), "", "unknown EXR compression \"" + name + "\" (zip, piz or none)");
}

void check_layers(const LayerSet& layers) {
  if (layers.width <= 0 || layers.height <= 0 || layers.layers.empty())
    throw std::logic_error("write_exr: empty LayerSet");
  const std::size_t texels = std::size_t(layers.width) * layers.height;
  for (const Layer& l : layers.layers)
    if (l.channels.empty() || l.data.size() != texels * l.channels.size())
      throw std::logic_error("write_exr: layer " + l.name + " has " + std::to_string(l.data.size()) +
                             " values for " + std::to_string(texels) + " texels x " +
                             std::to_string(l.channels.size()) + " channels");
}

}  // namespace

void write_exr(const fs::path& file, const LayerSet& layers, const ExrOptions& options) {
  check_layers(layers);
  const int w = layers.width, h = layers.height;
  Imf::Header header(w, h);
  header.compression() = compression_of(options.compression, file);
  const Imf::PixelType type = options.float_pixels ? Imf::FLOAT : Imf::HALF;

  struct Channel {
    std::string name;
    const float* data;   // first value of this channel in the layer's interleaved data
    std::size_t stride;  // values between texels
    bool as_float;       // written as float (float files, or a channel half cannot hold)
  };
  const std::size_t texels = std::size_t(w) * std::size_t(h);
  std::vector<Channel> channels;
  for (const Layer& l : layers.layers) {
    for (int c = 0; c < l.channel_count(); ++c) {
      Channel ch{l.name + "." + l.channels[c], l.data.data() + c, std::size_t(l.channel_count()), true};
      if (header.channels().findChannel(ch.name))
        throw std::logic_error("write_exr: duplicate channel " + ch.name);
      if (type == Imf::HALF) {
        // A finite value beyond half's range (65504, e.g. horizon distances on a large DEM) would become
        // infinite: such a channel is stored as float instead.
        float largest = 0;
        for (std::size_t i = 0; i < texels; ++i) {
          const float v = std::abs(ch.data[i * ch.stride]);
          if (std::isfinite(v)) largest = std::max(largest, v);
        }
        ch.as_float = largest > float(HALF_MAX);
      }
      header.channels().insert(ch.name, Imf::Channel(ch.as_float ? Imf::FLOAT : Imf::HALF));
      channels.push_back(std::move(ch));
    }
  }
  const auto put = [&](const std::string& key, const std::string& value) {
    std::string name = key;
    const auto existing = header.find(name);
    if (existing != header.end() && std::strcmp(existing.attribute().typeName(), "string") != 0)
      name = "hfbake." + key;
    header.insert(name, Imf::StringAttribute(value));
  };
  for (const auto& [k, v] : layers.attributes) put(k, v);
  for (const auto& [k, v] : options.attributes) put(k, v);

  std::error_code ec;
  if (!fs::is_directory(file.parent_path().empty() ? fs::path(".") : file.parent_path(), ec))
    throw InputError(file.string(), "", "cannot write: the folder does not exist");
  const fs::path tmp = temporary_sibling(file);
  try {
    Imf::OutputFile out(tmp.string().c_str(), header);
    // Float channels are read straight from the layers.
    const auto float_slice = [&](const Channel& ch) {
      return Imf::Slice(Imf::FLOAT, (char*)ch.data, sizeof(float) * ch.stride,
                        sizeof(float) * ch.stride * std::size_t(w));
    };
    std::size_t half_channels = 0;
    for (const Channel& ch : channels) half_channels += ch.as_float ? 0 : 1;
    if (half_channels == 0) {
      Imf::FrameBuffer frame;
      for (const Channel& ch : channels) frame.insert(ch.name, float_slice(ch));
      out.setFrameBuffer(frame);
      out.writePixels(h);
    } else {
      // Half channels (OpenEXR does not convert on output): a band of rows at a time, so the extra memory
      // is bounded (channels x width x kBand halves) whatever the field size.
      constexpr int kBand = 64;
      const std::size_t band_values = std::size_t(w) * kBand;
      std::vector<half> band(band_values * half_channels);
      for (int y0 = 0; y0 < h; y0 += kBand) {
        const int rows = std::min(kBand, h - y0);
        Imf::FrameBuffer frame;
        std::size_t slot = 0;
        for (std::size_t k = 0; k < channels.size(); ++k) {
          const Channel& ch = channels[k];
          if (ch.as_float) {
            frame.insert(ch.name, float_slice(ch));
            continue;
          }
          half* dst = band.data() + (slot++) * band_values;
          const std::size_t first = std::size_t(y0) * w;
          for (std::size_t i = 0; i < std::size_t(rows) * w; ++i)
            dst[i] = half(ch.data[(first + i) * ch.stride]);
          // The slice's base is where row 0 would be, so row y0 lands at the band's start.
          char* base = (char*)dst - std::ptrdiff_t(sizeof(half)) * std::ptrdiff_t(first);
          frame.insert(ch.name, Imf::Slice(Imf::HALF, base, sizeof(half), sizeof(half) * std::size_t(w)));
        }
        out.setFrameBuffer(frame);
        out.writePixels(rows);
      }
    }
  } catch (const std::exception& e) {
    fs::remove(tmp, ec);
    std::string what = e.what();
    if (const auto nl = what.find('\n'); nl != std::string::npos) what.resize(nl);
    throw InputError(file.string(), "", "cannot write the EXR: " + what);
  }
  fs::rename(tmp, file, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw InputError(file.string(), "", "cannot move the EXR into place: " + ec.message());
  }
}

}  // namespace hfbake
