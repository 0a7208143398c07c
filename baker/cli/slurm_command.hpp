// `hfbake slurm`: a bake on a Slurm cluster. Writes two sbatch scripts beside the outputs (readable, so a
// user can resubmit by hand) and submits them: a job array with one task per (job, shard) running
// `hfbake bake JOB --shard I/N`, requeued by Slurm when a node fails (--requeue), then one merge job that
// runs `hfbake merge` once every task has succeeded (afterok).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace hfbake {

// The glibc tunable under which a farm's tasks take the SSE2 variants of glibc's math functions, whatever
// their machines have (docs/cluster.md): the same bits on every x86-64.
inline constexpr const char* kBaselineMathTunable = "glibc.cpu.hwcaps=-FMA,-FMA4";

struct SlurmOptions {
  std::vector<std::filesystem::path> inputs;  // jobs and suites
  int shards = 1;
  std::string partition, time, mem;  // empty: Slurm's default (mem: the method table's estimate)
  std::vector<std::string> sbatch_args;
  bool wait = false;     // wait for the merge and exit with its status
  bool resume = false;   // submit only the tasks whose shard file is not complete
  bool dry_run = false;  // print the scripts and the sbatch commands to stdout; write and submit nothing
  // bake's options, passed on to every task and the merge.
  std::optional<std::filesystem::path> out, cache;
  bool no_cache = false, quiet = false;
  int threads = 1;  // per task: --cpus-per-task and the tasks' --threads
  // --tile-size S (with --tiles): a tiled bake (cli/tile_command.hpp), `shards` tile tasks (bake --tiles
  // --tile-size S --tile-task I/N), then merge --tiles --tile-size S; each task's memory is the estimate of
  // one tile's read window. 0: not tiled.
  int tile_size = 0;
};

// 0 submitted (with wait: the merge's exit status; with dry_run: printed), 2 bad input or a failed
// submission.
int run_slurm(const SlurmOptions& options);

}  // namespace hfbake
