// The reference cache: path-traced references are the expensive part of a nightly run, and they depend only
// on the scene and the reference parameters, so they are kept between runs under a content hash of
// everything that determines them. An entry is checked (a regular file, its header against the file's
// length and the job's field size, then its checksum) when it is read; a damaged
// entry is removed and the reference is computed again. Entries are written atomically (temporary file,
// then rename), so concurrent jobs and interrupted runs never leave a half-written entry behind.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "core/layers.hpp"
#include "job/manifest.hpp"

namespace hfbake {

// Bump whenever baker/reference (or the procedural fields it sees) changes what it computes for the
// same inputs, or starts reading more of the job than reference_cache_key hashes: every cached reference
// then misses once and is recomputed.
// 3: ao from whole rays beside an obscurance; 4: receivers lifted vertically, not along the normal; 5: a
// path vertex near a facet edge starts its next rays on the arriving ray (bake_reference.cpp path_origin).
inline constexpr int kReferenceCodeVersion = 5;

// 16 hex digits: a hash of kReferenceCodeVersion, the job's height, surface (albedo, emission),
// environment, lights, bounces and reference parameters, the falloff and radius of every bake entry that
// has them (the reference's obscurance follows the first obscurance-family entry's), and the bytes of
// every input file the job names. The job's name, output and report settings, and the other method
// parameters (directions, layers, ...) do not enter it.
std::string reference_cache_key(const Job& job);

// $XDG_CACHE_HOME/hfbake/references, else $HOME/.cache/hfbake/references; nullopt when neither is set.
std::optional<std::filesystem::path> default_reference_cache_dir();

enum class CacheLookup { hit, miss, corrupt };
const char* cache_lookup_name(CacheLookup l);  // "hit", "miss", "corrupt"

class ReferenceCache {
 public:
  explicit ReferenceCache(std::filesystem::path dir) : dir_(std::move(dir)) {}
  const std::filesystem::path& dir() const { return dir_; }
  std::filesystem::path entry_path(const std::string& key) const { return dir_ / (key + ".hfref"); }

  struct Entry {
    LayerSet layers;
    double seconds = 0;  // what computing the reference took: the time a hit saves
  };
  // hit: `out` holds the entry. corrupt: the entry was unreadable, not a regular file (a FIFO or a device
  // is never opened blocking), of another field size than expect_width x expect_height (when given), or
  // its header disagreed with the file's length (checked before anything is allocated), or it failed its
  // checksum; it was removed.
  CacheLookup load(const std::string& key, Entry& out, int expect_width = 0, int expect_height = 0) const;
  // Writes the entry atomically (creating the folder). Returns "" or a one-line reason it could not;
  // a cache that cannot be written never fails a bake.
  std::string store(const std::string& key, const LayerSet& layers, double seconds) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace hfbake
