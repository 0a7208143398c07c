#include "farm/build_id.hpp"

#include <elf.h>
#include <link.h>

#include <cstdio>
#include <cstring>

namespace hfbake {
namespace {

// The NT_GNU_BUILD_ID note of the first object dl_iterate_phdr lists (the executable itself).
int find_build_id(dl_phdr_info* info, std::size_t, void* data) {
  std::string& out = *static_cast<std::string*>(data);
  for (int p = 0; p < info->dlpi_phnum; ++p) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[p];
    if (ph.p_type != PT_NOTE) continue;
    const char* at = reinterpret_cast<const char*>(info->dlpi_addr + ph.p_vaddr);
    const char* end = at + ph.p_memsz;
    while (at + sizeof(ElfW(Nhdr)) <= end) {
      ElfW(Nhdr) n;
      std::memcpy(&n, at, sizeof n);
      const char* name = at + sizeof n;
      const char* desc = name + ((n.n_namesz + 3) & ~3u);
      if (desc + n.n_descsz > end) break;
      if (n.n_type == NT_GNU_BUILD_ID && n.n_namesz == 4 && std::memcmp(name, "GNU", 4) == 0) {
        char hex[3];
        for (unsigned i = 0; i < n.n_descsz; ++i) {
          std::snprintf(hex, sizeof hex, "%02x", static_cast<unsigned char>(desc[i]));
          out += hex;
        }
        return 1;
      }
      at = desc + ((n.n_descsz + 3) & ~3u);
    }
  }
  return 1;  // only the first object: the executable
}

}  // namespace

std::string executable_build_id() {
  static const std::string id = [] {
    std::string s;
    dl_iterate_phdr(find_build_id, &s);
    return s;
  }();
  return id;
}

}  // namespace hfbake
