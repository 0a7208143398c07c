// Writing a LayerSet as one multi-layer OpenEXR file, atomically.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/layers.hpp"

namespace hfbake {

// The longest side an output EXR is written as scanlines; a larger field's are tiles of 256 (cli/outputs.cpp
// says why).
inline constexpr int kLargestScanlineExr = 2048;

struct ExrOptions {
  bool float_pixels = false;        // half by default
  std::string compression = "zip";  // "zip", "piz", "dwaa", "dwab" (lossy on half colour channels) or "none"
  // Tile edge in texels (a tiled, single-level file); 0: scanlines. The file's pixels are the same either
  // way.
  int tile_size = 0;
  // Chunks (scanline blocks or tiles) compressed at once, by OpenEXR's thread pool (which the program starts:
  // start_exr_thread_pool); 0: the pool's size. Never changes the file's bytes.
  int threads = 0;
  // Written after LayerSet::attributes (same name: this one wins), as string attributes.
  std::vector<std::pair<std::string, std::string>> attributes;
};

// Writes every layer as channels "<layer>.<suffix>" (increasing y, data window = the field; scanlines, or
// tiles of options.tile_size), a band of rows at a time, plus the string attributes. In a half file, a
// channel holding a finite value beyond half's range
// (|v| > 65504) is stored as float rather than turned into infinity. An attribute whose name OpenEXR reserves
// ("compression", "channels", ...) is stored as "hfbake.<name>". The file is written under a temporary name
// in the same folder and renamed into place, so a crash never leaves a partial file. Unwritable folder or
// disk error -> InputError naming the file; inconsistent layers (wrong data size) -> std::logic_error.
void write_exr(const std::filesystem::path& file, const LayerSet& layers, const ExrOptions& options = {});

// The most memory write_exr holds beside the layers for a file of width x height texels with
// `half_channels` half and `float_channels` float channels: the band of half values it converts, and
// OpenEXR's chunk buffers (two per thread, each with a compressor's two buffers of a chunk when the file is
// compressed; measured on 1025-channel files: docs/large-fields.md).
double exr_writing_bytes(int width, int height, std::size_t half_channels, std::size_t float_channels,
                         const ExrOptions& options);

// The compression a job gets when its output names none: "piz" for a file holding a per-direction stack
// (horizon, horizon_distance, horizon_deg: many channels of smooth float data, where PIZ writes about twice
// as fast as ZIP in half and three times in float, and smaller in float; docs/large-fields.md, "EXR
// outputs"), "zip" for the rest (lossless, the smallest half files of scalars and colours).
std::string default_exr_compression(const LayerSet& layers);
std::string default_exr_compression(const std::vector<std::string>& layer_names);

// Starts (or resizes) OpenEXR's process-wide thread pool to `threads` workers (0: none, everything in the
// calling thread). Process state: called once by the program (the CLI's main), never by library code.
void start_exr_thread_pool(int threads);

// A temporary name beside `file`, unique in this process: ".<name>.tmp-<pid>-<n>".
std::filesystem::path temporary_sibling(const std::filesystem::path& file);

}  // namespace hfbake
