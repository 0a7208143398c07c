#include "cli/bake_turns.hpp"

#include <algorithm>
#include <cstdio>

namespace hfbake {

std::string memory_size_text(std::size_t bytes) {
  char buf[32];
  if (bytes < (std::size_t(1) << 30))
    std::snprintf(buf, sizeof buf, "%.0f MiB", double(bytes) / double(1ull << 20));
  else
    std::snprintf(buf, sizeof buf, "%.1f GiB", double(bytes) / double(1ull << 30));
  return buf;
}

namespace {

// The jobs' own parts: each estimate less its process part.
std::size_t own_bytes(const std::vector<JobMemory>& jobs) {
  std::size_t own = 0;
  for (const JobMemory& j : jobs) own += j.peak - std::min(j.process, j.peak);
  return own;
}

}  // namespace

std::size_t combined_peak_bytes(const std::vector<JobMemory>& jobs) {
  std::size_t process = 0;
  for (const JobMemory& j : jobs) process = std::max(process, j.process);
  return jobs.empty() ? 0 : process + own_bytes(jobs);
}

BakeTurns plan_bake_turns(const std::vector<JobMemory>& jobs, std::size_t budget) {
  BakeTurns plan;
  std::vector<JobMemory> turn;
  // Every job's inputs are probed before any bakes, which loads the libraries each reads them with: every
  // turn holds the largest process part of the call beside its jobs' own parts.
  std::size_t loaded = 0;
  for (const JobMemory& j : jobs) loaded = std::max(loaded, j.process);
  auto with_loaded = [loaded](const std::vector<JobMemory>& t) { return loaded + own_bytes(t); };
  for (std::size_t k = 0; k < jobs.size(); ++k) {
    turn.push_back(jobs[k]);
    if (plan.turns.empty() || (turn.size() > 1 && with_loaded(turn) > budget)) {
      plan.turns.emplace_back();
      turn = {jobs[k]};
    }
    plan.turns.back().push_back(k);
    plan.peak = std::max(plan.peak, with_loaded(turn));
  }
  plan.all = combined_peak_bytes(jobs);
  plan.fits = plan.peak <= budget;
  return plan;
}

std::string bake_turns_text(const BakeTurns& turns, const std::string& budget) {
  std::size_t jobs = 0;
  std::string sizes;
  for (const std::vector<std::size_t>& t : turns.turns) {
    jobs += t.size();
    sizes += (sizes.empty() ? "" : " + ") + std::to_string(t.size());
  }
  if (!turns.fits)
    return std::to_string(jobs) + " jobs need about " + memory_size_text(turns.peak) +
           " at the peak even one at a time (the libraries every job's inputs load stay loaded through the "
           "call), more than " +
           budget + ": bake them in calls of their own";
  const std::string peak = ": about " + memory_size_text(turns.peak) + " at the peak, within " + budget;
  if (turns.turns.size() <= 1) return std::to_string(jobs) + " jobs bake together" + peak;
  return std::to_string(jobs) + " jobs bake in " + std::to_string(turns.turns.size()) + " turns (" + sizes +
         " jobs)" + peak + " (all at once: about " + memory_size_text(turns.all) + ")";
}

}  // namespace hfbake
