#include "job/content_hash.hpp"

#include <cstdio>
#include <fstream>

#include "core/error.hpp"

namespace hfbake {

void ContentHash::add(std::string_view bytes) {
  for (unsigned char c : bytes) {
    h_ ^= c;
    h_ *= 0x100000001b3ull;
  }
}

void ContentHash::add_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "", "cannot read file");
  char buf[1 << 16];
  while (in) {
    in.read(buf, sizeof buf);
    add(std::string_view(buf, std::size_t(in.gcount())));
  }
}

std::string ContentHash::hex() const {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h_));
  return buf;
}

std::string content_hash_of(const Job& job, const std::vector<std::filesystem::path>& files) {
  ContentHash h;
  h.add(job.doc.dump());  // nlohmann objects are key-sorted: a canonical form
  for (const std::filesystem::path& file : files) h.add_file(file);
  return h.hex();
}

}  // namespace hfbake
