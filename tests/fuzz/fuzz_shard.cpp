// libFuzzer harness: a shard file (farm/shard_file.hpp) as `hfbake merge` and `bake --shard` read it, for a
// 16x16 job named "t": the header against the job's identity and field, then every part's layers. A file
// that is not such a shard is an InputError with one line naming it; anything else (an uncaught exception, a
// crash, UB, an allocation beyond the file's own size, a descriptor left open) is a finding. An input that
// ends in a shard trailer gets its header's checksum line added (sealed) before it is read, so that mutated
// headers reach the header's parser rather than stopping at the checksum; the corpus holds unsealed files.
#include <fcntl.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "farm/shard_file.hpp"
#include "fuzz_support.hpp"
#include "job/content_hash.hpp"

using namespace hfbake;

// The lowest free file descriptor: it grows when a read leaves a descriptor open.
int lowest_free_fd() {
  const int fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
  if (fd >= 0) close(fd);
  return fd;
}

// The input with the checksum line of the header its trailer points at inserted before the trailer (the
// writer's layout: farm/shard_file.hpp); an input without a trailer as it is.
std::vector<std::uint8_t> sealed(const std::uint8_t* data, std::size_t size) {
  constexpr std::size_t kTrailer = 24;
  std::vector<std::uint8_t> out(data, data + size);
  if (size < kTrailer || std::memcmp(data + size - kTrailer, "hfbake shard end", 16) != 0) return out;
  std::uint64_t at = 0;
  for (int b = 0; b < 8; ++b) at |= std::uint64_t(data[size - 8 + std::size_t(b)]) << (8 * b);
  if (at > size - kTrailer) return out;
  ContentHash h;
  h.add(std::string_view(reinterpret_cast<const char*>(data + at), size - kTrailer - at));
  const std::string line = h.hex() + "\n";
  out.insert(out.end() - kTrailer, line.begin(), line.end());
  return out;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> bytes = sealed(data, size);
  const std::filesystem::path file =
      fuzz::write_scratch("t.shard-0-of-1.hfshard", bytes.data(), bytes.size());
  const int free_fd = lowest_free_fd();
  ShardIdentity identity;
  identity.job_name = "t";
  identity.job_hash = "0123456789abcdef";
  identity.version = "fuzz";
  identity.id = {0, 1};
  identity.width = 16, identity.height = 16;
  try {
    ShardReader reader(file, identity);
    for (std::size_t i = 0; i < reader.parts().size(); ++i) {
      const LayerSet layers = reader.load(i);
      if (std::uint64_t(layers.width) * std::uint64_t(layers.height) > 16 * 16)
        fuzz::finding("a part larger than the field was loaded");
    }
  } catch (const InputError& e) {
    fuzz::check_error_line(e.line(), file.string());
  }
  if (lowest_free_fd() != free_fd) fuzz::finding("the shard file was left open");
  return 0;
}
