// Content hashes: what identifies a job's inputs (EXR metadata, reference cache keys).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "job/manifest.hpp"

namespace hfbake {

// 64-bit FNV-1a, incremental.
class ContentHash {
 public:
  void add(std::string_view bytes);
  void add_file(const std::filesystem::path& file);  // streams the file's bytes; InputError if unreadable
  std::uint64_t value() const { return h_; }
  std::string hex() const;  // 16 hex digits

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ull;
};

// Hash of the job document (canonical JSON) and the bytes of `files`, in order: every file a bake of the job
// reads (cli/scene_inputs.hpp job_content_hash gives them).
std::string content_hash_of(const Job& job, const std::vector<std::filesystem::path>& files);

}  // namespace hfbake
