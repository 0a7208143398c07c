#include "io/exr_output.hpp"

#include <unistd.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>

#include <atomic>
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
  if (layers.width <= 0 || layers.height <= 0) throw std::logic_error("write_exr: empty LayerSet");
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

  Imf::FrameBuffer frame;
  for (const Layer& l : layers.layers) {
    const int nc = l.channel_count();
    const std::size_t xstride = sizeof(float) * std::size_t(nc), ystride = xstride * std::size_t(w);
    for (int c = 0; c < nc; ++c) {
      const std::string name = l.name + "." + l.channels[c];
      if (header.channels().findChannel(name)) throw std::logic_error("write_exr: duplicate channel " + name);
      header.channels().insert(name, Imf::Channel(type));
      // OpenEXR converts the float frame buffer to the file's half channels itself.
      frame.insert(name, Imf::Slice(Imf::FLOAT, (char*)(l.data.data() + c), xstride, ystride));
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
    out.setFrameBuffer(frame);
    out.writePixels(h);
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
