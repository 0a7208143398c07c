// How the jobs of one call share the process's memory budget (--memory-limit; default the available memory):
// jobs bake together only while their combined estimate fits the budget, else in turns, one after another.
// `validate` prints the plan and `bake` follows it (docs/contract.md).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace hfbake {

// What one job of the call plans for.
struct JobMemory {
  std::size_t peak = 0;     // its estimate alone (cli/scene_loader.hpp estimate_peak_bytes)
  std::size_t process = 0;  // the process's part of it (estimate_process_bytes), held once per process
};

// The peak of jobs baked together in one process: the largest process part once, and each job's own part
// (its estimate less its process part) on top. Each job's peak is counted as if they all coincided.
std::size_t combined_peak_bytes(const std::vector<JobMemory>& jobs);

struct BakeTurns {
  // Indices into the jobs, in their order: the jobs of one turn bake together (sharing the cores), the turns
  // one after another.
  std::vector<std::vector<std::size_t>> turns;
  std::size_t peak = 0;  // the largest turn's combined_peak_bytes: the peak the call plans for
  std::size_t all = 0;   // combined_peak_bytes of every job at once
  bool fits = true;      // peak is within the budget (else the call is refused: bake_turns_text says so)
};

// The jobs in order, each joining the current turn while the turn's combined peak with it fits `budget`,
// else starting the next turn. Every turn counts the largest process part of the call: the libraries each
// job's inputs are read with are loaded before any job bakes, and stay (the memory a turn frees is handed
// back to the system before the next one starts). A job that does not fit alone has a turn of its own
// (check_job_memory refuses it); a call whose jobs do not fit even one at a time beside the call's libraries
// does not fit (BakeTurns::fits).
BakeTurns plan_bake_turns(const std::vector<JobMemory>& jobs, std::size_t budget);

// "266 MiB", or "1.5 GiB" from a GiB on: a memory figure in messages.
std::string memory_size_text(std::size_t bytes);

// The plan in one line for `validate` (without "hfbake: "): "3 jobs bake together: about 266 MiB at the
// peak, within <budget>" or "3 jobs bake in 2 turns (2 + 1 jobs): about 266 MiB at the peak, within
// <budget> (all at once: about 370 MiB)"; `budget` as check_job_memory names it ("the 170 MiB of
// --memory-limit").
std::string bake_turns_text(const BakeTurns& turns, const std::string& budget);

}  // namespace hfbake
