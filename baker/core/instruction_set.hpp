// The widest instruction set hfbake's kernels may use on this machine. hfbake builds for the x86-64
// baseline (SSE2); a kernel with wider instructions runs only where the processor has them and the
// environment variable HFBAKE_ISA allows them (docs/cluster.md). Every kernel gives the same bits on each.
#pragma once

namespace hfbake {

enum class InstructionSet { sse2, avx2, avx512 };  // each includes the ones before it

// The cap HFBAKE_ISA sets (sse2, avx2 or avx512; unset or empty: avx512), read once. Throws
// std::invalid_argument naming the variable on any other value.
InstructionSet instruction_set_cap();

}  // namespace hfbake
