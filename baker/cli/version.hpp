#pragma once

namespace hfbake {

// "0.1.0" plus the git revision the binary was built from, when known ("0.1.0+g1a2b3c4").
const char* hfbake_version();

}  // namespace hfbake
