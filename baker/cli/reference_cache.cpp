#include "cli/reference_cache.hpp"

#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <system_error>

#include "job/content_hash.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

// File layout: the magic line, one line of JSON (the header), then the payload: every layer's float data
// in header order, little-endian float32 as in memory (hfbake builds only for little-endian machines).
constexpr char kMagic[] = "hfbake reference cache 1\n";

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
  if (const int b = reference_falloff_entry(job.doc); b >= 0) {
    const auto& e = job.doc["bake"][b];
    nlohmann::json f = nlohmann::json::object();
    for (const char* key : {"falloff", "radius"})
      if (e.contains(key)) f[key] = e[key];
    falloffs.push_back({{"method", e.value("method", "")}, {"falloff", f}});
  }
  determining["bake_falloffs"] = std::move(falloffs);
  // Which layers it traces (without "layers", the ones the job's methods are scored against).
  if (job.reference_resolved.is_object() && job.reference_resolved.contains("layers"))
    determining["reference_layers"] = job.reference_resolved["layers"];
  h.add(determining.dump());  // objects are key-sorted: a canonical form
  for (const auto& [pointer, path] : job_input_files(job.doc)) {
    h.add("\n" + pointer + "\n");
    h.add_file(job.resolve(path));
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

CacheLookup ReferenceCache::load(const std::string& key, Entry& out) const {
  const fs::path file = entry_path(key);
  std::ifstream in(file, std::ios::binary);
  if (!in) return CacheLookup::miss;
  auto corrupt = [&] {
    in.close();
    std::error_code ec;
    fs::remove(file, ec);
    return CacheLookup::corrupt;
  };
  try {
    std::string magic(sizeof kMagic - 1, '\0');
    in.read(magic.data(), std::streamsize(magic.size()));
    if (!in || magic != kMagic) return corrupt();
    std::string header_line;
    if (!std::getline(in, header_line)) return corrupt();
    const nlohmann::json header = nlohmann::json::parse(header_line);
    if (header.at("key").get<std::string>() != key) return corrupt();
    Entry e;
    e.seconds = header.at("seconds").get<double>();
    e.layers.width = header.at("width").get<int>();
    e.layers.height = header.at("height").get<int>();
    if (e.layers.width <= 0 || e.layers.height <= 0) return corrupt();
    const std::size_t texels = std::size_t(e.layers.width) * std::size_t(e.layers.height);
    for (const auto& l : header.at("layers")) {
      Layer& layer =
          e.layers.add(l.at("name").get<std::string>(), l.at("channels").get<std::vector<std::string>>());
      if (layer.channels.empty()) return corrupt();
      in.read(reinterpret_cast<char*>(layer.data.data()),
              std::streamsize(texels * layer.channels.size() * sizeof(float)));
      if (!in) return corrupt();
    }
    if (in.peek() != std::ifstream::traits_type::eof()) return corrupt();  // trailing bytes
    for (const auto& a : header.at("attributes"))
      e.layers.attributes.emplace_back(a.at(0).get<std::string>(), a.at(1).get<std::string>());
    if (payload_checksum(e.layers) != header.at("checksum").get<std::string>()) return corrupt();
    out = std::move(e);
    return CacheLookup::hit;
  } catch (const std::exception&) {  // malformed header, huge sizes: the entry is not usable
    return corrupt();
  }
}

std::string ReferenceCache::store(const std::string& key, const LayerSet& layers, double seconds) const {
  static std::atomic<unsigned> counter{0};
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) return "cannot create " + dir_.string() + ": " + ec.message();
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
  const fs::path tmp =
      file.string() + ".tmp-" + std::to_string(getpid()) + "-" + std::to_string(counter.fetch_add(1));
  {
    std::ofstream out(tmp, std::ios::binary);
    out.write(kMagic, sizeof kMagic - 1);
    out << header.dump() << '\n';
    for (const Layer& l : layers.layers)
      out.write(reinterpret_cast<const char*>(l.data.data()), std::streamsize(l.data.size() * sizeof(float)));
    out.close();
    if (!out) {
      fs::remove(tmp, ec);
      return "cannot write " + tmp.string();
    }
  }
  fs::rename(tmp, file, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    return "cannot rename into " + file.string() + ": " + ec.message();
  }
  return "";
}

}  // namespace hfbake
