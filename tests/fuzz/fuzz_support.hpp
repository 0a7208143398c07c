// Shared by the libFuzzer harnesses (tests/fuzz/fuzz_*.cpp): the checks every harness makes of what hfbake
// says about a bad input, and a scratch file for the loaders that read paths.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace hfbake::fuzz {

// A finding: print it and abort (libFuzzer saves the input as a crasher).
[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "hfbake fuzz finding: %s\n", what.c_str());
  std::abort();
}

// The contract for bad input: one line ("hfbake: error: <file>: <pointer>: <what>"), naming the file.
inline void check_error_line(const std::string& line, const std::string& file) {
  if (line.find('\n') != std::string::npos || line.find('\r') != std::string::npos)
    finding("an error message spans lines: " + line);
  if (line.rfind(file, 0) != 0)
    finding("an error message does not start with the file " + file + ": " + line);
}

// A per-process scratch folder (in $TMPDIR, /dev/shm when there is one: no disk writes per input).
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    std::error_code ec;
    std::filesystem::path base = std::filesystem::is_directory("/dev/shm", ec)
                                     ? std::filesystem::path("/dev/shm")
                                     : std::filesystem::temp_directory_path();
    const std::filesystem::path d = base / ("hfbake-fuzz-" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

// Writes the bytes to <scratch>/<name> and returns the path.
inline std::filesystem::path write_scratch(const std::string& name, const unsigned char* data,
                                           std::size_t size) {
  const std::filesystem::path p = scratch_dir() / name;
  std::ofstream(p, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), std::streamsize(size));
  return p;
}

}  // namespace hfbake::fuzz
