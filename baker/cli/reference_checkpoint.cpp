#include "cli/reference_checkpoint.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string_view>

#include "cli/reference_cache.hpp"
#include "cli/scene_inputs.hpp"
#include "core/safe_file.hpp"
#include "farm/build_id.hpp"
#include "job/content_hash.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

// File layout: the magic line, the key (16 hex digits and a newline), the band (uint32) and the float count
// (uint64), the floats, then the checksum (uint64: FNV-1a of everything before it). Little-endian, as in
// memory (hfbake builds only for little-endian machines).
constexpr char kCheckpointMagic[] = "hfbake reference checkpoint 1\n";
constexpr std::size_t kCheckpointMagicBytes = sizeof kCheckpointMagic - 1;
constexpr std::size_t kKeyBytes = 17;
constexpr std::size_t kHeaderBytes =
    kCheckpointMagicBytes + kKeyBytes + sizeof(std::uint32_t) + sizeof(std::uint64_t);

std::string header_bytes(const std::string& key, int band, std::size_t count) {
  std::string h(kCheckpointMagic, kCheckpointMagicBytes);
  h += key.substr(0, 16);
  h.resize(kCheckpointMagicBytes + 16, '0');
  h += '\n';
  const std::uint32_t b = std::uint32_t(band);
  const std::uint64_t n = count;
  h.append(reinterpret_cast<const char*>(&b), sizeof b);
  h.append(reinterpret_cast<const char*>(&n), sizeof n);
  return h;
}

std::uint64_t checksum(const std::string& header, const void* floats, std::size_t count) {
  ContentHash h;
  h.add(header);
  h.add(std::string_view(static_cast<const char*>(floats), count * sizeof(float)));
  return h.value();
}

}  // namespace

std::string reference_checkpoint_key(const Job& job, const ReferenceOptions& options, int width, int height) {
  ContentHash h;
  h.add("hfbake reference checkpoint\n");
  h.add(job_content_hash(job) + "\n");
  h.add(reference_cache_key(job) + "\n");  // the reference code version and what the reference reads
  h.add(executable_build_id() + "\n");
  const nlohmann::json layout = {{"resolved", options.resolved},
                                 {"layers", options.layers},
                                 {"tile_size", options.tile_size},
                                 {"row_begin", options.row_begin},
                                 {"row_end", options.row_end},
                                 {"width", width},
                                 {"height", height}};
  h.add(layout.dump());
  return h.hex();
}

fs::path ReferenceCheckpoint::band_path(int band) const {
  return dir_ / ("band-" + std::to_string(band) + ".hfckpt");
}

bool ReferenceCheckpoint::load(int band, std::span<float> values) const {
  const fs::path file = band_path(band);
  // O_NONBLOCK: a FIFO in a band's place must not hang the bake; fstat then refuses anything irregular.
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  const std::uint64_t expect = kHeaderBytes + values.size() * sizeof(float) + sizeof(std::uint64_t);
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || std::uint64_t(st.st_size) != expect) return false;
  auto read_exactly = [&](void* to, std::size_t n) {
    char* dst = static_cast<char*>(to);
    while (n > 0) {
      const ssize_t got = ::read(fd, dst, std::min<std::size_t>(n, 1u << 30));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      dst += got, n -= std::size_t(got);
    }
    return true;
  };
  const std::string want = header_bytes(key_, band, values.size());
  std::string header(kHeaderBytes, '\0');
  if (!read_exactly(header.data(), header.size()) || header != want) return false;  // foreign or damaged
  std::uint64_t sum = 0;
  if (!read_exactly(values.data(), values.size_bytes()) || !read_exactly(&sum, sizeof sum)) return false;
  return sum == checksum(header, values.data(), values.size());
}

std::string ReferenceCheckpoint::store(int band, std::span<const float> values) const {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) return "cannot create " + dir_.string() + ": " + ec.message();
  const fs::path file = band_path(band);
  const std::string header = header_bytes(key_, band, values.size());
  const std::uint64_t sum = checksum(header, values.data(), values.size());
  try {  // complete or absent
    TempFile tmp(file);
    if (!tmp.write(header) || !tmp.write(values.data(), values.size_bytes()) || !tmp.write(&sum, sizeof sum))
      return "cannot write " + tmp.path().string();
    tmp.commit();
  } catch (const std::system_error& e) {
    return e.what();
  }
  return "";
}

ReferenceResume ReferenceCheckpoint::resume(std::string* problem) const {
  ReferenceResume r;
  // Copies of the folder and key: the callbacks outlive nothing they need.
  r.load = [self = *this](int band, std::span<float> values) { return self.load(band, values); };
  auto guard = std::make_shared<std::mutex>();
  r.store = [self = *this, problem, guard](int band, std::span<const float> values) {
    std::string p;
    try {
      p = self.store(band, values);
    } catch (const std::exception& e) {
      p = e.what();
    }
    std::lock_guard lock(*guard);
    if (!p.empty() && problem && problem->empty()) *problem = p;
  };
  return r;
}

}  // namespace hfbake
