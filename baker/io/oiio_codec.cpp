#include "io/oiio_codec.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <filesystem>
#include <iterator>
#include <mutex>
#include <stdexcept>

namespace hfbake {
namespace fs = std::filesystem;

std::size_t oiio_sample_bytes(OiioSample s) {
  // In OiioSample's order: other, uint8, int8, uint16, int16, uint32, int32, uint64, int64, half, float32,
  // float64.
  constexpr std::size_t kBytes[] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 2, 4, 8};
  const auto at = std::size_t(s);
  return at < std::size(kBytes) ? kBytes[at] : 0;
}

namespace {

constexpr const char* kModule = "libhfbake_oiio.so";

// The folder of the shared object (or executable) this function is in.
fs::path own_folder() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&own_folder), &info) && info.dli_fname && *info.dli_fname) {
    std::error_code ec;
    const fs::path p = fs::canonical(info.dli_fname, ec);
    if (!ec) return p.parent_path();
  }
  return {};
}

fs::path executable_folder() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : p.parent_path();
}

const OiioCodec* load() {
  std::vector<fs::path> tried;
  if (const fs::path own = own_folder(); !own.empty()) tried.push_back(own / kModule);
  if (const fs::path exe = executable_folder(); !exe.empty())
    tried.push_back(exe / HFBAKE_OIIO_MODULE_FROM_BINDIR / kModule);
  tried.push_back(fs::path(HFBAKE_OIIO_MODULE_BUILD_DIR) / kModule);
  std::string why;
  for (const fs::path& p : tried) {
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) continue;
    // RTLD_LOCAL: OpenImageIO's symbols stay the module's.
    void* handle = dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* e = dlerror();
      why = p.string() + ": " + (e ? e : "cannot load");
      continue;
    }
    using Entry = const OiioCodec* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(handle, "hfbake_oiio_codec"));
    const OiioCodec* codec = entry ? entry() : nullptr;
    if (codec && codec->version == kOiioCodecVersion) return codec;  // loaded for the process' lifetime
    why = p.string() + ": not this build's image module";
  }
  std::string paths;
  for (const fs::path& p : tried) paths += (paths.empty() ? "" : ", ") + p.string();
  throw std::runtime_error("cannot load hfbake's image module (OpenImageIO): " +
                           (why.empty() ? "none of " + paths + " exists" : why));
}

}  // namespace

const OiioCodec& oiio_codec() {
  static std::once_flag once;
  static const OiioCodec* codec = nullptr;
  std::call_once(once, [] { codec = load(); });  // a failure throws and the next call tries again
  return *codec;
}

}  // namespace hfbake
