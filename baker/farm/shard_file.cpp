#include "farm/shard_file.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <climits>
#include <cstdint>
#include <cstring>
#include <system_error>

#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "job/content_hash.hpp"
#include "job/manifest.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

constexpr char kMagic[] = "hfbake shard 2\n";
constexpr char kEnd[] = "hfbake shard end";  // 16 bytes, then the header offset (8 bytes)
constexpr std::size_t kTrailer = 16 + 8;
// A header lists parts and layers by name: far less than this, whatever the job.
constexpr std::uint64_t kMaxShardHeaderBytes = 64u << 20;

std::string text_checksum(std::string_view text) {
  ContentHash h;
  h.add(text);
  return h.hex();
}

std::string bytes_checksum(const float* data, std::size_t count) {
  return text_checksum(std::string_view(reinterpret_cast<const char*>(data), count * sizeof(float)));
}

}  // namespace

ShardWriter::ShardWriter(fs::path final_path, ShardIdentity identity, std::string owner)
    : final_(std::move(final_path)), identity_(std::move(identity)) {
  fs::create_directories(final_.parent_path());
  if (owner.empty()) owner = std::to_string(getpid()) + "@" + host_name();
  try {
    out_ = std::make_unique<TempFile>(final_, owner);
  } catch (const std::system_error& e) {
    throw std::runtime_error(e.what());
  }
  ok_ = out_->write(kMagic, sizeof kMagic - 1);
  offset_ = sizeof kMagic - 1;
}

ShardWriter::~ShardWriter() = default;  // the TempFile removes itself unless committed

void ShardWriter::add(ShardPart part, const LayerSet& layers) {
  part.width = layers.width, part.height = layers.height;
  part.layers = nlohmann::json::array();
  for (const Layer& l : layers.layers) {
    part.layers.push_back({{"name", l.name},
                           {"channels", l.channels},
                           {"offset", offset_},
                           {"floats", l.data.size()},
                           {"checksum", bytes_checksum(l.data.data(), l.data.size())}});
    ok_ = ok_ && out_->write(l.data.data(), l.data.size() * sizeof(float));
    offset_ += l.data.size() * sizeof(float);
  }
  part.attributes = layers.attributes;
  if (!ok_) throw std::runtime_error("cannot write " + out_->path().string());
  parts_.push_back(std::move(part));
}

void ShardWriter::commit() {
  nlohmann::json header = {{"job", identity_.job_name},           {"job_hash", identity_.job_hash},
                           {"hfbake_version", identity_.version}, {"shard", identity_.id.index},
                           {"shards", identity_.id.count},        {"width", identity_.width},
                           {"height", identity_.height}};
  header["parts"] = nlohmann::json::array();
  for (const ShardPart& p : parts_) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& [k, v] : p.attributes) a.push_back({k, v});
    header["parts"].push_back({{"entry", p.entry},
                               {"kind", p.kind},
                               {"block", p.block},
                               {"stage", p.stage},
                               {"row_begin", p.row_begin},
                               {"row_end", p.row_end},
                               {"seconds", p.seconds},
                               {"cpu_seconds", p.cpu_seconds},
                               {"width", p.width},
                               {"height", p.height},
                               {"layers", p.layers},
                               {"attributes", a}});
  }
  // The header's line, then its checksum's: a byte of the header changed is damage, as a byte of a part's
  // data is.
  const std::string line = header.dump() + "\n";
  const std::string text = line + text_checksum(line) + "\n";
  unsigned char off[8];
  for (int b = 0; b < 8; ++b) off[b] = static_cast<unsigned char>(offset_ >> (8 * b));
  ok_ = ok_ && out_->write(text) && out_->write(kEnd, 16) && out_->write(off, 8);
  if (!ok_) throw std::runtime_error("cannot write " + out_->path().string());
  try {
    out_->commit();
  } catch (const std::system_error& e) {
    throw std::runtime_error(e.what());
  }
}

ShardReader::ShardReader(ShardReader&& other) noexcept
    : file_(std::move(other.file_)),
      fd_(other.fd_),
      parts_(std::move(other.parts_)),
      which_(std::move(other.which_)),
      redo_(std::move(other.redo_)) {
  other.fd_ = -1;
}

ShardReader::~ShardReader() {
  if (fd_ >= 0) close(fd_);
}

ShardReader::ShardReader(const fs::path& file, const ShardIdentity& expected) : file_(file) {
  try {
    read_header(expected);
  } catch (...) {  // the destructor does not run for a constructor that throws
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
    throw;
  }
}

void ShardReader::read_header(const ShardIdentity& expected) {
  const fs::path& file = file_;
  const std::string name = file.string();
  const std::string which = expected.what.empty() ? "shard " + shard_id_text(expected.id) : expected.what;
  const std::string redo =
      expected.redo.empty() ? "bake it with --shard " + shard_id_text(expected.id) : expected.redo;
  which_ = which, redo_ = redo;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(file, ec)))
    throw InputError(name, "", which + " is missing (" + redo + ")");
  // A link to nothing stands where the shard goes: missing too, and the bake that makes it replaces the link.
  if (fs::is_symlink(fs::symlink_status(file, ec)) && !fs::exists(fs::status(file, ec)))
    throw InputError(name, "", which + " is missing (a link to nothing stands there; " + redo + ")");
  std::string why;
  fd_ = open_regular_file(file, why);
  if (fd_ < 0) throw InputError(name, "", "cannot read " + which + ": " + why);
  struct stat st {};
  if (fstat(fd_, &st) != 0) throw InputError(name, "", "cannot read " + which);
  const std::uint64_t size = std::uint64_t(st.st_size);
  auto damaged = [&](const std::string& why) {
    return InputError(name, "", which + " is truncated or damaged (" + why + "): " + redo);
  };
  char magic[sizeof kMagic - 1];
  if (size < sizeof magic + kTrailer || !read_at(fd_, magic, sizeof magic, 0) ||
      std::memcmp(magic, kMagic, sizeof magic) != 0)
    throw damaged("no shard header");
  char trailer[kTrailer];
  if (!read_at(fd_, trailer, kTrailer, size - kTrailer) || std::memcmp(trailer, kEnd, 16) != 0)
    throw damaged("no end marker");
  std::uint64_t header_at = 0;
  for (int b = 0; b < 8; ++b)
    header_at |= std::uint64_t(static_cast<unsigned char>(trailer[16 + b])) << (8 * b);
  if (header_at < sizeof magic || header_at >= size - kTrailer) throw damaged("bad header offset");
  if (size - kTrailer - header_at > kMaxShardHeaderBytes) throw damaged("a header beyond any shard's");
  std::string text(std::size_t(size - kTrailer - header_at), '\0');
  if (!read_at(fd_, text.data(), text.size(), header_at)) throw damaged("unreadable header");
  const std::size_t line_end = text.size() >= 2 ? text.rfind('\n', text.size() - 2) : std::string::npos;
  if (line_end == std::string::npos || text.back() != '\n' ||
      text.compare(line_end + 1, text.size() - line_end - 2, text_checksum(text.substr(0, line_end + 1))) !=
          0)
    throw damaged("header checksum");
  text.resize(line_end + 1);
  nlohmann::json h;
  try {
    // The parser of every JSON file hfbake reads, which refuses a key given twice; the header's size bounds
    // its strings and arrays (a relief part's azimuth list is longer than a job file's strings may be).
    h = parse_json_text(text, name, {kMaxJsonDepth, SIZE_MAX, SIZE_MAX});
  } catch (const InputError& e) {
    throw damaged("header " + e.where() + ": " + e.what());
  }
  // A header field, named in messages by its JSON pointer (`at` the pointer of the object holding it):
  // present and of the kind asked, else damage.
  enum class Is { text, number, list };
  auto field = [&](const nlohmann::json& in, const std::string& at, const std::string& key,
                   Is kind) -> const nlohmann::json& {
    const auto it = in.find(key);
    if (it == in.end()) throw damaged("no header field " + at + "/" + key);
    if (kind == Is::text ? !it->is_string() : kind == Is::number ? !it->is_number() : !it->is_array())
      throw damaged("header field " + at + "/" + key + " is not " +
                    (kind == Is::text     ? "a string"
                     : kind == Is::number ? "a number"
                                          : "an array"));
    return *it;
  };
  auto text_field = [&](const nlohmann::json& in, const std::string& at, const std::string& key) {
    return field(in, at, key, Is::text).get<std::string>();
  };
  // An integer of the header within [lo, hi]: a float or an integer out of range is damage (converting
  // it would be undefined).
  auto whole_number = [&](const nlohmann::json& in, const std::string& at, const std::string& key,
                          std::int64_t lo, std::int64_t hi) {
    const nlohmann::json& v = field(in, at, key, Is::number);
    const bool fits = v.is_number_unsigned()  ? v.get<std::uint64_t>() <= std::uint64_t(hi)
                      : v.is_number_integer() ? v.get<std::int64_t>() >= lo && v.get<std::int64_t>() <= hi
                                              : false;
    if (!fits) throw damaged("header field " + at + "/" + key + " is no whole number in range");
    return v.get<std::int64_t>();
  };
  auto object = [&](const nlohmann::json& v, const std::string& at) {
    if (!v.is_object())
      throw damaged(at.empty() ? "a header that is no JSON object"
                               : "header field " + at + " is not an object");
  };
  object(h, "");
  const std::string job = text_field(h, "", "job"), job_hash = text_field(h, "", "job_hash");
  if (job_hash != expected.job_hash || job != expected.job_name)
    throw InputError(name, "",
                     which + " belongs to another job (" + job + ", hash " + job_hash + "; this job's is " +
                         expected.job_hash + "): " + redo);
  const std::string version = text_field(h, "", "hfbake_version");
  if (version != expected.version)
    throw InputError(
        name, "",
        which + " was baked by hfbake " + version + ", not " + expected.version + ": bake it again");
  if (whole_number(h, "", "shard", 0, INT_MAX) != expected.id.index ||
      whole_number(h, "", "shards", 0, INT_MAX) != expected.id.count ||
      whole_number(h, "", "width", 0, INT_MAX) != expected.width ||
      whole_number(h, "", "height", 0, INT_MAX) != expected.height)
    throw damaged("header of another shard or field size");
  // Every claim against the job's field and the file's bytes: a part is the whole field (or its rows
  // [row_begin, row_end) for the reference), each layer width * height * channels floats inside the data.
  const std::uint64_t W = std::uint64_t(expected.width), H = std::uint64_t(expected.height);
  const nlohmann::json& parts = field(h, "", "parts", Is::list);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const nlohmann::json& p = parts[i];
    const std::string at = "/parts/" + std::to_string(i);
    object(p, at);
    ShardPart part;
    part.entry = int(whole_number(p, at, "entry", -1, INT_MAX));
    part.kind = text_field(p, at, "kind");
    part.block = int(whole_number(p, at, "block", 0, INT_MAX));
    part.stage = p.contains("stage") ? int(whole_number(p, at, "stage", 0, INT_MAX)) : 0;
    part.row_begin = int(whole_number(p, at, "row_begin", 0, INT_MAX));
    part.row_end = int(whole_number(p, at, "row_end", 0, INT_MAX));
    part.seconds = field(p, at, "seconds", Is::number).get<double>();
    part.cpu_seconds = field(p, at, "cpu_seconds", Is::number).get<double>();
    part.width = int(whole_number(p, at, "width", 0, INT_MAX));
    part.height = int(whole_number(p, at, "height", 0, INT_MAX));
    part.layers = field(p, at, "layers", Is::list);
    const bool rows = part.kind == "rows";
    if (!rows && part.kind != "whole" && part.kind != "block" && part.kind != "stage" &&
        part.kind != "stage-block")
      throw damaged("a part of unknown kind");
    if (part.entry < -1 || part.block < 0) throw damaged("a part of no entry");
    if (expected.part_entry != -2 && (part.entry != expected.part_entry || part.kind != expected.part_kind ||
                                      part.block != expected.part_block || part.stage != expected.part_stage))
      throw InputError(name, "",
                       which + " holds another piece (" + part.kind + " " + std::to_string(part.block) +
                           (part.kind == "stage-block" ? " of stage " + std::to_string(part.stage) : "") +
                           " of bake entry " + std::to_string(part.entry) + "): " + redo);
    // The times the merge sums into the report: non-negative and under 10^9 s (32 years) each, so that
    // no sum of them overflows (docs/cluster.md).
    if (!(part.seconds >= 0 && part.seconds < 1e9) || !(part.cpu_seconds >= 0 && part.cpu_seconds < 1e9))
      throw damaged("a part's seconds outside [0, 1e9)");
    if (rows && !(part.row_begin >= 0 && part.row_begin < part.row_end && std::uint64_t(part.row_end) <= H &&
                  part.height == part.row_end - part.row_begin))
      throw damaged("rows outside the field");
    if (std::uint64_t(part.width) != W || (!rows && std::uint64_t(part.height) != H))
      throw damaged("a part of another size than the field's " + std::to_string(W) + "x" + std::to_string(H));
    const std::uint64_t texels = W * std::uint64_t(part.height);
    if (texels == 0) throw damaged("a part of no texels");
    for (std::size_t k = 0; k < part.layers.size(); ++k) {
      const nlohmann::json& l = part.layers[k];
      const std::string lat = at + "/layers/" + std::to_string(k);
      object(l, lat);
      const std::string layer = text_field(l, lat, "name");
      const nlohmann::json& names = field(l, lat, "channels", Is::list);
      const std::uint64_t channels = names.size(),
                          floats = std::uint64_t(whole_number(l, lat, "floats", 0, INT64_MAX)),
                          offset = std::uint64_t(whole_number(l, lat, "offset", 0, INT64_MAX));
      text_field(l, lat, "checksum");
      if (layer.empty() || channels == 0) throw damaged("a layer without a name or channels");
      for (const auto& c : names)
        if (!c.is_string()) throw damaged("header field " + lat + "/channels holds a channel without a name");
      if (channels > header_at / 4 / texels || floats != texels * channels)
        throw damaged("layer " + layer + " of another size than the part's");
      if (offset < sizeof magic || offset > header_at || floats > (header_at - offset) / sizeof(float))
        throw damaged("a layer beyond the data");
    }
    const nlohmann::json& attributes = field(p, at, "attributes", Is::list);
    for (std::size_t k = 0; k < attributes.size(); ++k) {
      const nlohmann::json& a = attributes[k];
      if (!a.is_array() || a.size() != 2 || !a[0].is_string() || !a[1].is_string())
        throw damaged("header field " + at + "/attributes/" + std::to_string(k) +
                      " is not a pair of strings [name, value]");
      part.attributes.emplace_back(a[0].get<std::string>(), a[1].get<std::string>());
    }
    parts_.push_back(std::move(part));
  }
}

LayerSet ShardReader::load(std::size_t i) {
  const ShardPart& p = parts_.at(i);
  LayerSet out;
  out.width = p.width, out.height = p.height;
  for (const auto& l : p.layers) {
    Layer& layer = out.add(l.at("name").get<std::string>(), l.at("channels").get<std::vector<std::string>>());
    if (layer.data.size() != l.at("floats").get<std::size_t>())
      throw InputError(file_.string(), "", "layer " + layer.name + " has the wrong size");
    if (!read_at(fd_, layer.data.data(), layer.data.size() * sizeof(float),
                 l.at("offset").get<std::uint64_t>()) ||
        bytes_checksum(layer.data.data(), layer.data.size()) != l.at("checksum").get<std::string>())
      throw InputError(file_.string(), "",
                       which_ + " is damaged (the checksum of its layer " + layer.name + "): " + redo_);
  }
  out.attributes = p.attributes;
  return out;
}

bool shard_is_complete(const fs::path& file, const ShardIdentity& expected) {
  try {
    ShardReader r(file, expected);
    for (std::size_t i = 0; i < r.parts().size(); ++i) r.load(i);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace hfbake
