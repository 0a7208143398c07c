// The running executable's GNU build id (the linker's hash of the binary: `readelf -n hfbake`), in hex;
// "" when the binary has none. The farm puts it in every shard's version, so shards of two different builds
// are never merged, even when both report the same hfbake version (the version and git revision are fixed
// when CMake configures, not when the binary is linked).
#pragma once

#include <string>

namespace hfbake {

std::string executable_build_id();

}  // namespace hfbake
