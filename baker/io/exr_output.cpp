#include "io/exr_output.hpp"

#include <unistd.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>
#include <ImfTiledOutputFile.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include "core/error.hpp"
#include "io/half_planes.hpp"

namespace hfbake {
namespace fs = std::filesystem;

void start_exr_thread_pool(int threads) {
  Imf::setGlobalThreadCount(std::max(0, threads));
}

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

std::string default_exr_compression(const std::vector<std::string>& layer_names) {
  for (const std::string& name : layer_names)
    if (const LayerKind* k = find_layer_kind(name); k && k->channels == LayerChannels::per_direction)
      return "piz";
  return "zip";
}

std::string default_exr_compression(const LayerSet& layers) {
  std::vector<std::string> names;
  for (const Layer& layer : layers.layers) names.push_back(layer.name);
  return default_exr_compression(names);
}

namespace {

// Scanlines OpenEXR compresses together (one chunk of a scanline file).
int chunk_lines(Imf::Compression c) {
  switch (c) {
    case Imf::ZIP_COMPRESSION:
      return 16;
    case Imf::PIZ_COMPRESSION:
    case Imf::DWAA_COMPRESSION:
      return 32;
    case Imf::DWAB_COMPRESSION:
      return 256;
    default:
      return 1;
  }
}

// Rows handed to OpenEXR at once: whole chunks (a row of tiles, or scanline blocks of `chunk` rows), enough
// of them that every thread has one, and at least 64 rows. Half channels are converted one such band at a
// time, so the extra memory is bounded (channels x width x band halves) whatever the field size. No more
// rows than the image has (one band then holds it all): a 70000 x 2 field's tiled band of 256 rows took 35 MB
// a channel.
int band_rows_of(int chunk, bool tiled, int threads, int height) {
  int rows = std::max(64, chunk * (tiled ? 1 : threads));
  rows = (rows + chunk - 1) / chunk * chunk;
  return std::min(rows, height);
}

// The compression's name as OpenEXR's, or nullopt for a name it does not have.
std::optional<Imf::Compression> compression_named(const std::string& name) {
  if (name == "zip") return Imf::ZIP_COMPRESSION;
  if (name == "piz") return Imf::PIZ_COMPRESSION;
  if (name == "dwaa") return Imf::DWAA_COMPRESSION;
  if (name == "dwab") return Imf::DWAB_COMPRESSION;
  if (name == "none") return Imf::NO_COMPRESSION;
  return std::nullopt;
}

Imf::Compression compression_of(const std::string& name, const fs::path& file) {
  if (const std::optional<Imf::Compression> c = compression_named(name)) return *c;
  throw InputError(file.string(), "",
                   "unknown EXR compression \"" + name + "\" (zip, piz, dwaa, dwab or none)");
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

double exr_writing_bytes(int width, int height, std::size_t half_channels, std::size_t float_channels,
                         const ExrOptions& options) {
  const Imf::Compression c = compression_named(options.compression).value_or(Imf::ZIP_COMPRESSION);
  const int threads = std::max(1, options.threads > 0 ? options.threads : Imf::globalThreadCount());
  const bool tiled = options.tile_size > 0;
  const int chunk = tiled ? options.tile_size : chunk_lines(c);
  const double pixel = 2.0 * double(half_channels) + 4.0 * double(float_channels);
  const double chunk_bytes =
      pixel * (tiled ? double(options.tile_size) * options.tile_size : double(chunk) * double(width));
  const double buffers = 2.0 * threads * (c == Imf::NO_COMPRESSION ? 1.0 : 3.0) * chunk_bytes;
  const double band =
      2.0 * double(half_channels) * double(width) * band_rows_of(chunk, tiled, threads, height);
  return band + buffers;
}

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
    const std::size_t n = std::size_t(l.channel_count());
    const LayerKind* kind = find_layer_kind(l.name);
    const bool layer_float = type != Imf::HALF || (kind && kind->float_storage);
    // A finite value beyond half's range (65504, e.g. horizon distances on a large DEM) would become
    // infinite: such a channel is stored as float instead. The layer's values are read in their order
    // (texel by texel, every channel), once, without branches (an infinity or NaN counts as 0).
    std::vector<float> largest(n, 0.0f);
    const float finite = std::numeric_limits<float>::max();
    if (!layer_float)
      for (std::size_t i = 0; i < texels; ++i) {
        const float* v = l.data.data() + i * n;
        for (std::size_t c = 0; c < n; ++c) {
          const float a = std::abs(v[c]);
          largest[c] = std::max(largest[c], a <= finite ? a : 0.0f);
        }
      }
    for (std::size_t c = 0; c < n; ++c) {
      Channel ch{l.name + "." + l.channels[c], l.data.data() + c, n,
                 layer_float || largest[c] > float(HALF_MAX)};
      if (header.channels().findChannel(ch.name))
        throw std::logic_error("write_exr: duplicate channel " + ch.name);
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

  const int threads = std::max(1, options.threads > 0 ? options.threads : Imf::globalThreadCount());
  const bool tiled = options.tile_size > 0;
  if (tiled) {
    header.setTileDescription(Imf::TileDescription(unsigned(options.tile_size), unsigned(options.tile_size)));
    header.lineOrder() =
        Imf::INCREASING_Y;  // tiles stored row of tiles by row of tiles, whatever the threads
  }
  const int chunk = tiled ? options.tile_size : chunk_lines(header.compression());
  const int band_rows = band_rows_of(chunk, tiled, threads, h);

  std::error_code ec;
  if (!fs::is_directory(file.parent_path().empty() ? fs::path(".") : file.parent_path(), ec))
    throw InputError(file.string(), "", "cannot write: the folder does not exist");
  const fs::path tmp = temporary_sibling(file);
  try {
    std::unique_ptr<Imf::OutputFile> scan;
    std::unique_ptr<Imf::TiledOutputFile> tiles;
    if (tiled)
      tiles = std::make_unique<Imf::TiledOutputFile>(tmp.string().c_str(), header, threads);
    else
      scan = std::make_unique<Imf::OutputFile>(tmp.string().c_str(), header, threads);
    // Float channels are read straight from the layers.
    const auto float_slice = [&](const Channel& ch) {
      return Imf::Slice(Imf::FLOAT, (char*)ch.data, sizeof(float) * ch.stride,
                        sizeof(float) * ch.stride * std::size_t(w));
    };
    std::size_t half_channels = 0;
    for (const Channel& ch : channels) half_channels += ch.as_float ? 0 : 1;
    const std::size_t band_values = std::size_t(w) * std::size_t(band_rows);
    // Channels a cache line apart beyond a multiple of 4 KiB: a texel's values go to every channel's band,
    // and bands a power of two apart would all fall in one cache set (a 64-channel horizon layer's
    // conversion was bound by those conflicts).
    const std::size_t band_stride = (band_values + 2047) / 2048 * 2048 + 32;
    std::vector<std::uint16_t> band(band_stride * half_channels);  // half bits
    for (int y0 = 0; y0 < h; y0 += band_rows) {
      const int rows = std::min(band_rows, h - y0);
      Imf::FrameBuffer frame;
      const std::size_t first = std::size_t(y0) * w, count = std::size_t(rows) * w;
      // The band's half channels, converted texel by texel (each layer's values in their order); a layer
      // whose channels are all half, by to_half_planes.
      std::size_t slot = 0;
      for (std::size_t c0 = 0; c0 < channels.size();) {
        const std::size_t stride = channels[c0].stride;  // a layer's channels are adjacent, stride of them
        std::size_t layer_halves = 0;
        for (std::size_t c = 0; c < stride; ++c) layer_halves += channels[c0 + c].as_float ? 0 : 1;
        if (layer_halves == stride) {
          to_half_planes(channels[c0].data + first * stride, stride, count, band.data() + slot * band_stride,
                         band_stride);
        } else {
          for (std::size_t i = 0; i < count; ++i) {
            const float* v = channels[c0].data + (first + i) * stride;
            std::size_t s2 = slot;
            for (std::size_t c = 0; c < stride; ++c)
              if (!channels[c0 + c].as_float) band[(s2++) * band_stride + i] = half(v[c]).bits();
          }
        }
        for (std::size_t c = 0; c < stride; ++c) {
          const Channel& ch = channels[c0 + c];
          if (ch.as_float) {
            frame.insert(ch.name, float_slice(ch));
            continue;
          }
          std::uint16_t* dst = band.data() + (slot++) * band_stride;
          // The slice's base is where row 0 would be, so row y0 lands at the band's start.
          char* base = (char*)dst - std::ptrdiff_t(sizeof(std::uint16_t)) * std::ptrdiff_t(first);
          frame.insert(ch.name, Imf::Slice(Imf::HALF, base, sizeof(std::uint16_t),
                                           sizeof(std::uint16_t) * std::size_t(w)));
        }
        c0 += stride;
      }
      if (tiled) {
        tiles->setFrameBuffer(frame);
        const int ty0 = y0 / options.tile_size, ty1 = (y0 + rows - 1) / options.tile_size;
        tiles->writeTiles(0, tiles->numXTiles() - 1, ty0, ty1);
      } else {
        scan->setFrameBuffer(frame);
        scan->writePixels(rows);
      }
    }
  } catch (const std::exception& e) {
    fs::remove(tmp, ec);
    std::string what = e.what();
    if (const auto nl = what.find('\n'); nl != std::string::npos) what.resize(nl);
    throw OutputError(file.string(), "", "cannot write the EXR: " + what);
  }
  // A full disk can fail the last buffered writes where OpenEXR does not look (its stream's flush when the
  // file closes: a 0-byte EXR was moved into place with exit 0). Read the header and the chunk table back:
  // only a whole file is moved into place.
  bool whole = false;
  try {
    Imf::InputFile written(tmp.string().c_str(), 1);
    whole = written.isComplete();
  } catch (const std::exception&) {
  }
  if (!whole) {
    fs::remove(tmp, ec);
    throw OutputError(file.string(), "",
                      "cannot write the EXR: the written file is not whole (is the disk full?)");
  }
  fs::rename(tmp, file, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw OutputError(file.string(), "", "cannot move the EXR into place: " + ec.message());
  }
}

}  // namespace hfbake
