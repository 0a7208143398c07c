#include "core/instruction_set.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace hfbake {

InstructionSet instruction_set_cap() {
  static const InstructionSet cap = [] {
    const char* v = std::getenv("HFBAKE_ISA");
    if (!v || !*v) return InstructionSet::avx512;
    const std::string s = v;
    if (s == "sse2") return InstructionSet::sse2;
    if (s == "avx2") return InstructionSet::avx2;
    if (s == "avx512") return InstructionSet::avx512;
    throw std::invalid_argument("HFBAKE_ISA=" + s + ": must be sse2, avx2 or avx512 (or unset)");
  }();
  return cap;
}

}  // namespace hfbake
