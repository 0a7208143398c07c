// Checkpoints of a reference being traced: each finished band of rows (bake_reference's ReferenceResume) is
// written as a file of its own into the job's staging folder, so a bake killed mid-reference (SIGKILL, the
// OOM killer, a node failure) loses only the bands in flight: the next bake of the same job into the same
// folder adopts the dead stage's checkpoints (OutputStage) and traces only the bands they lack. The bits are
// those of an uninterrupted bake: a band's texels depend on (seed, texel) alone.
//
// A band file is complete or absent (written to a temporary, then renamed) and carries the job's checkpoint
// key (the job's content hash, the executable's build id, the reference's resolved parameters and layout),
// its band number, its float count and a checksum of all of them: a damaged, truncated or foreign file (an
// earlier version of the job, another build) is ignored and its band traced again.
#pragma once

#include <filesystem>
#include <span>
#include <string>

#include "job/manifest.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake {

// 16 hex digits: what a band's bits depend on. Bands of another key are never read.
std::string reference_checkpoint_key(const Job& job, const ReferenceOptions& options, int width, int height);

class ReferenceCheckpoint {
 public:
  ReferenceCheckpoint(std::filesystem::path dir, std::string key)
      : dir_(std::move(dir)), key_(std::move(key)) {}
  const std::filesystem::path& dir() const { return dir_; }
  std::filesystem::path band_path(int band) const;

  // Fills `values` from the band's file: true only for a regular file of exactly this key, band, float count
  // and checksum (nothing larger than `values` is read or allocated).
  bool load(int band, std::span<float> values) const;
  // Writes the band's file atomically (creating the folder); "" or a one-line reason it could not (a
  // checkpoint that cannot be written never fails a bake: it only cannot be resumed).
  std::string store(int band, std::span<const float> values) const;

  // A ReferenceResume over this folder; store problems go to `problem` (the first one is kept).
  ReferenceResume resume(std::string* problem) const;

 private:
  std::filesystem::path dir_;
  std::string key_;
};

}  // namespace hfbake
