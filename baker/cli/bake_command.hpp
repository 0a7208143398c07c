// `hfbake bake` and `hfbake validate`: load jobs, bake them task-parallel, write outputs whole or not at all.
#pragma once

#include <atomic>
#include <filesystem>
#include <optional>
#include <vector>

namespace hfbake {

struct BakeOptions {
  std::vector<std::filesystem::path> jobs;
  std::optional<std::filesystem::path> out;      // --out: replaces every job's output.dir
  std::optional<std::filesystem::path> summary;  // --summary: machine-readable JSON summary
  bool quiet = false;
  // The reference cache (cli/reference_cache.hpp): --cache DIR, default under the user's cache home;
  // --no-cache turns it off.
  std::optional<std::filesystem::path> cache;
  bool no_cache = false;
};

// Exit status per the contract: 0 all baked and thresholds held, 1 a threshold or baseline regressed,
// 2 bad input or a failed job, 130 interrupted (`cancel` was set).
int run_bake(const BakeOptions& options, const std::atomic<bool>& cancel);

// Schema and file checks without baking: 0 all valid, 2 otherwise. Prints one line per problem.
int run_validate(const std::vector<std::filesystem::path>& jobs, bool quiet);

}  // namespace hfbake
