// Writing a LayerSet as one multi-layer OpenEXR file, atomically.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/layers.hpp"

namespace hfbake {

struct ExrOptions {
  bool float_pixels = false;        // half by default
  std::string compression = "zip";  // "zip", "piz" or "none"
  // Written after LayerSet::attributes (same name: this one wins), as string attributes.
  std::vector<std::pair<std::string, std::string>> attributes;
};

// Writes every layer as channels "<layer>.<suffix>" (scanline, increasing y, data window = the field),
// plus the string attributes. In a half file, a channel holding a finite value beyond half's range
// (|v| > 65504) is stored as float rather than turned into infinity. An attribute whose name OpenEXR reserves
// ("compression", "channels", ...) is stored as "hfbake.<name>". The file is written under a temporary name
// in the same folder and renamed into place, so a crash never leaves a partial file. Unwritable folder or
// disk error -> InputError naming the file; inconsistent layers (wrong data size) -> std::logic_error.
void write_exr(const std::filesystem::path& file, const LayerSet& layers, const ExrOptions& options = {});

// A temporary name beside `file`, unique in this process: ".<name>.tmp-<pid>-<n>".
std::filesystem::path temporary_sibling(const std::filesystem::path& file);

}  // namespace hfbake
