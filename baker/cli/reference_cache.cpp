#include "cli/reference_cache.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <system_error>

#include "cli/outputs.hpp"
#include "cli/scene_inputs.hpp"
#include "core/safe_file.hpp"
#include "io/color.hpp"
#include "job/content_hash.hpp"
#include "job/manifest.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

// File layout: the magic line, one line of JSON (the header), then the payload: every layer's float data
// in header order, little-endian float32 as in memory (hfbake builds only for little-endian machines).
constexpr char kCacheMagic[] = "hfbake reference cache 1\n";
// Bounds of an entry, checked before anything is allocated: the header line (layer names, attributes),
// the field's sides (what Embree's grid and the sweeps support), the channels of one layer.
constexpr std::size_t kMaxHeaderBytes = 1u << 20;
constexpr std::int64_t kMaxEntrySide = 1 << 20;
constexpr std::uint64_t kMaxEntryChannels = 4096;

std::string payload_checksum(const LayerSet& layers) {
  ContentHash h;
  for (const Layer& l : layers.layers)
    h.add(std::string_view(reinterpret_cast<const char*>(l.data.data()), l.data.size() * sizeof(float)));
  return h.hex();
}

}  // namespace

const char* cache_lookup_name(CacheLookup l) {
  switch (l) {
    case CacheLookup::hit:
      return "hit";
    case CacheLookup::miss:
      return "miss";
    case CacheLookup::corrupt:
      return "corrupt";
  }
  return "?";
}

std::string reference_cache_key(const Job& job) {
  ContentHash h;
  h.add("hfbake reference v" + std::to_string(kReferenceCodeVersion) + "\n");
  nlohmann::json determining = nlohmann::json::object();
  for (const char* key : {"height", "surface", "environment", "lights", "bounces", "reference"})
    if (job.doc.contains(key)) determining[key] = job.doc[key];
  // From the bake list the reference reads only the falloff and radius of one obscurance-family entry
  // (reference_falloff_entry): adding a method, another obscurance entry or sweeping directions keeps the
  // key.
  nlohmann::json falloffs = nlohmann::json::array();
  std::vector<const MethodConfig*> entries;
  for (const BakeEntry& e : job.bakes) {
    if (!e.config)
      throw std::logic_error("reference_cache_key: bake entry " + e.pointer + " was not resolved");
    entries.push_back(e.config.get());
  }
  if (const int b = reference_falloff_entry(job.doc.value("reference", nlohmann::json::object()), entries);
      b >= 0) {
    const MethodConfig& e = *entries[std::size_t(b)];
    falloffs.push_back(
        {{"method", e.method->name},
         {"falloff",
          {{"falloff", falloff_kind_name(e.obscurance->kind)}, {"radius", e.obscurance->radius}}}});
  }
  determining["bake_falloffs"] = std::move(falloffs);
  // Which layers it traces (without "layers", the ones the job's methods are scored against).
  if (job.reference_options) determining["reference_layers"] = job.reference_options->layers;
  h.add(determining.dump());  // objects are key-sorted: a canonical form
  for (const auto& [pointer, file] : job_read_files(job)) {
    h.add("\n" + pointer + "\n");
    h.add_file(file);
  }
  // The colour spaces the images are read in are the OpenColorIO config's ($OCIO or the built-in one):
  // its text and the LUT files it reads.
  const OcioIdentity ocio = ocio_identity();
  h.add("\nocio\n" + ocio.text);
  for (const std::string& lut : ocio.files) {
    h.add("\n" + lut + "\n");
    h.add_file(lut);
  }
  return h.hex();
}

std::optional<fs::path> default_reference_cache_dir() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && *xdg && fs::path(xdg).is_absolute()) return fs::path(xdg) / "hfbake" / "references";
  const char* home = std::getenv("HOME");
  if (home && *home) return fs::path(home) / ".cache" / "hfbake" / "references";
  return std::nullopt;
}

CacheLookup ReferenceCache::load(const std::string& key, Entry& out, int expect_width,
                                 int expect_height) const {
  const fs::path file = entry_path(key);
  // O_NONBLOCK: a FIFO (or a device) in an entry's place must not hang the bake in open(); fstat then
  // refuses anything but a regular file.
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return errno == ENOENT || errno == ENOTDIR ? CacheLookup::miss : CacheLookup::corrupt;
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  auto corrupt = [&] {
    std::error_code ec;
    fs::remove(file, ec);
    return CacheLookup::corrupt;
  };
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return corrupt();
  const std::uint64_t file_bytes = std::uint64_t(st.st_size);
  // Reads exactly n bytes (false: a short file or an error).
  auto read_exactly = [&](char* dst, std::uint64_t n) {
    while (n > 0) {
      const ssize_t got = ::read(fd, dst, std::size_t(std::min<std::uint64_t>(n, 1u << 30)));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      dst += got, n -= std::uint64_t(got);
    }
    return true;
  };
  try {
    std::string magic(sizeof kCacheMagic - 1, '\0');
    if (!read_exactly(magic.data(), magic.size()) || magic != kCacheMagic) return corrupt();
    // The header line, at most kMaxHeaderBytes: read a bounded prefix, keep up to the newline.
    std::string header_line;
    std::uint64_t offset = magic.size();
    for (char c = 0;;) {
      if (header_line.size() >= kMaxHeaderBytes || !read_exactly(&c, 1)) return corrupt();
      ++offset;
      if (c == '\n') break;
      header_line.push_back(c);
    }
    const nlohmann::json header = parse_json_text(header_line, file.string());  // a key given twice: damage
    if (header.at("key").get<std::string>() != key) return corrupt();
    Entry e;
    e.seconds = header.at("seconds").get<double>();
    const std::int64_t width = header.at("width").get<std::int64_t>();
    const std::int64_t height = header.at("height").get<std::int64_t>();
    if (width <= 0 || height <= 0 || width > kMaxEntrySide || height > kMaxEntrySide) return corrupt();
    // The job's field: an entry of another size is not this job's reference, whatever its key says.
    if ((expect_width > 0 && width != expect_width) || (expect_height > 0 && height != expect_height))
      return corrupt();
    // The payload the header describes must be exactly what follows it in the file, checked in 64-bit
    // before anything is allocated: a header claiming 60000 x 60000 on a small file is damage, not 14 GB.
    const std::uint64_t texels = std::uint64_t(width) * std::uint64_t(height);
    std::uint64_t payload = 0;
    std::vector<std::pair<std::string, std::vector<std::string>>> shapes;
    for (const auto& l : header.at("layers")) {
      shapes.emplace_back(l.at("name").get<std::string>(), l.at("channels").get<std::vector<std::string>>());
      const std::uint64_t channels = shapes.back().second.size();
      if (channels == 0 || channels > kMaxEntryChannels) return corrupt();
      payload += texels * channels * sizeof(float);  // <= 2^20 * 2^20 * 2^12 * 4 = 2^54 a layer: no overflow
      if (payload > file_bytes) return corrupt();
    }
    if (payload != file_bytes - offset) return corrupt();  // truncated or trailing bytes
    e.layers.width = int(width);
    e.layers.height = int(height);
    for (auto& [name, channels] : shapes) {
      Layer& layer = e.layers.add(name, std::move(channels));
      if (!read_exactly(reinterpret_cast<char*>(layer.data.data()), layer.data.size() * sizeof(float)))
        return corrupt();
    }
    for (const auto& a : header.at("attributes"))
      e.layers.attributes.emplace_back(a.at(0).get<std::string>(), a.at(1).get<std::string>());
    if (payload_checksum(e.layers) != header.at("checksum").get<std::string>()) return corrupt();
    out = std::move(e);
    return CacheLookup::hit;
  } catch (const std::exception&) {  // malformed header: the entry is not usable
    return corrupt();
  }
}

std::string ReferenceCache::store(const std::string& key, const LayerSet& layers, double seconds) const {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) return "cannot create " + dir_.string() + ": " + ec.message();
  remove_stale_temporaries(dir_);  // a killed bake's half-written entries (never read as entries)
  nlohmann::json header = {{"key", key},
                           {"seconds", seconds},
                           {"width", layers.width},
                           {"height", layers.height},
                           {"checksum", payload_checksum(layers)},
                           {"reference_code_version", kReferenceCodeVersion}};
  header["layers"] = nlohmann::json::array();
  for (const Layer& l : layers.layers)
    header["layers"].push_back({{"name", l.name}, {"channels", l.channels}});
  header["attributes"] = nlohmann::json::array();
  for (const auto& [k, v] : layers.attributes) header["attributes"].push_back({k, v});

  const fs::path file = entry_path(key);
  try {
    TempFile tmp(file);
    bool ok = tmp.write(kCacheMagic, sizeof kCacheMagic - 1) && tmp.write(header.dump() + "\n");
    for (const Layer& l : layers.layers) ok = ok && tmp.write(l.data.data(), l.data.size() * sizeof(float));
    if (!ok) return "cannot write " + tmp.path().string();
    tmp.commit();
  } catch (const std::system_error& e) {
    return e.what();
  }
  return "";
}

}  // namespace hfbake
