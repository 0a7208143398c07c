// hfbake init: a job file to edit, written for a height file and a preset (docs/presets.md), with the texel
// size and the height range read from the file; and the lists `hfbake --help` prints (methods with their
// layers, presets).
#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>

namespace hfbake {

struct InitPreset {
  const char* name;
  const char* summary;  // one line, for --help
};

// Every preset, in the order --help lists them.
std::span<const InitPreset> init_presets();

struct InitOptions {
  std::filesystem::path height_file;
  std::string preset;                        // one of init_presets()
  std::optional<std::filesystem::path> out;  // the job file; default <height file's stem>.json here
  bool force = false;                        // overwrite an existing job file
};

// Writes the job (validated as `validate` would, before it is written) and prints its heights line and the
// next commands. Exit 0; 2 for bad input (a missing or unreadable height file, an existing job file without
// --force), with one line naming the file.
int run_init(const InitOptions& options);

// For --help: each method with its one-line summary and the layers it writes (from its schema), then each
// preset.
std::string methods_and_presets_help();

}  // namespace hfbake
