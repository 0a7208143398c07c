#include "cli/slurm_command.hpp"

#include <sys/wait.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <tuple>

#include "cli/method_dispatch.hpp"
#include "cli/outputs.hpp"
#include "cli/scene_loader.hpp"
#include "cli/shard_command.hpp"
#include "cli/shell_words.hpp"
#include "cli/suite.hpp"
#include "cli/tile_command.hpp"
#include "core/safe_file.hpp"
#include "farm/shard_file.hpp"
#include "job/content_hash.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

fs::path own_executable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path("hfbake") : p;
}

// Runs a command, returns its exit status and its standard output.
int run_capture(const std::string& command, std::string* output) {
  FILE* p = popen(command.c_str(), "r");
  if (!p) return 127;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) output->append(buf, n);
  const int status = pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

// A command's output as one line (errors are one line): line breaks become "; ", the last one dropped.
std::string one_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  std::string out;
  for (char c : text) {
    if (c == '\r') continue;
    if (c == '\n')
      out += "; ";
    else
      out += c;
  }
  return out;
}

struct Task {
  fs::path job;  // as given (the scripts run in the submission's folder: --chdir)
  fs::path out;  // the job's output folder
  int shard = 0;
  int stages = 0;  // the job's most stages (0: none staged)
  // Per stage: this task's pieces of the staged entries (farm/shard_plan.hpp stage_work); a job's entry in
  // `jobs` holds every shard's, shard after shard.
  std::vector<std::vector<StageItem>> items;
  std::shared_ptr<const Job> loaded;  // the job as read and resolved at submission (its files' names)
};

// Compact Slurm array list: "0-3,5,7-8".
std::string array_list(const std::vector<int>& ids) {
  std::string s;
  for (std::size_t i = 0; i < ids.size();) {
    std::size_t j = i;
    while (j + 1 < ids.size() && ids[j + 1] == ids[j] + 1) ++j;
    // Appended piece by piece (GCC 12's -Wrestrict misfires on "literal" + std::string).
    if (!s.empty()) s += ',';
    s += std::to_string(ids[i]);
    if (j > i) s.append(1, '-').append(std::to_string(ids[j]));
    i = j + 1;
  }
  return s;
}

std::string bake_flags(const SlurmOptions& o) {
  std::string f;
  if (o.no_cache) f += " --no-cache";
  if (o.cache) f += " --cache " + shell_quoted(fs::absolute(*o.cache).string());
  return f;
}

void write_file(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  TempFile tmp(file);
  if (!tmp.write(text)) throw std::runtime_error("cannot write " + tmp.path().string());
  fs::permissions(tmp.path(), fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add);
  tmp.commit();
}

}  // namespace

int run_slurm(const SlurmOptions& o) {
  auto fail = [](const std::string& line) {
    std::fprintf(stderr, "hfbake: error: %s\n", line.c_str());
    return 2;
  };
  if (o.shards < 1 || o.shards > 4096) return fail("command line: --shards must be 1..4096");
  // The jobs, each with the output folder bake would give it (suites: <suite out>/<job stem>).
  std::vector<Task> jobs;
  const CallJobs call = call_jobs(o.inputs, o.out);
  if (!call.errors.empty()) return fail(call.errors.front());
  for (const Suite& suite : call.suites)
    for (const std::string& s : suite.skipped) std::fprintf(stderr, "hfbake: note: %s\n", s.c_str());
  std::size_t plain = 0;
  for (const CallJob& member : call.jobs) plain += member.suite < 0;
  fs::path common;
  std::size_t need_bytes = 0;
  // The estimate of a task's bake on its --cpus-per-task threads (its per-thread scratch).
  const tbb::global_control task_threads(tbb::global_control::max_allowed_parallelism,
                                         std::size_t(o.threads));
  for (const CallJob& member : call.jobs) {
    if (member.suite >= 0 && common.empty()) common = call.suites[std::size_t(member.suite)].output_dir;
    const fs::path& file = member.file;
    const std::optional<fs::path>& out = member.out;
    JobLoad load = load_job(file, out);
    if (load.job) load.errors = resolve_job(*load.job);
    if (!load.job || !load.errors.empty()) {
      for (const std::string& e : load.errors) std::fprintf(stderr, "hfbake: error: %s\n", e.c_str());
      return 2;
    }
    const Job& job = *load.job;
    if (o.tile_size > 0) {  // a tiled bake's task holds one tile's read window at a time
      try {
        check_tiled_job(job);
        // tiles/ as its tasks and merge will find it (they run without --overwrite)
        check_tiles_folder(job, false);
        const TilePlan plan = plan_job_tiles(job, std::numeric_limits<std::size_t>::max(), o.tile_size);
        need_bytes = std::max(need_bytes, tiled_peak_bytes(job, plan));
      } catch (const InputError& e) {
        return fail(e.line());
      }
    } else {
      try {
        // As its tasks and merge will find the folder (they run without --overwrite).
        check_output_owner(job, false);
        check_shards_owner(job, false);
        check_shards_folder(job, o.shards);
      } catch (const InputError& e) {
        return fail(e.line());
      }
      need_bytes = std::max(need_bytes, estimate_peak_bytes(job, probe_field_size(job)));
    }
    const int stages = job_stages(job);
    std::vector<std::vector<StageItem>> items;
    for (int s = 0; s < o.shards; ++s)
      for (int st = 0; st < stages; ++st) items.push_back(stage_work(job, {s, o.shards}, st));
    jobs.push_back(
        {file, out ? *out : job.output.dir, 0, stages, std::move(items), std::make_shared<Job>(job)});
    if (common.empty()) common = fs::absolute(job.output.dir);
  }
  if (jobs.empty()) return fail("command line: no jobs");
  if (o.out && plain > 1) common = fs::absolute(*o.out);
  const fs::path dir = common / "slurm";

  // Tasks: job-major, shard-minor. Stage 0 of every task (the shard), then stage s = 1, 2, ... of the
  // tasks whose shard runs a staged entry (p2) with that stage; with --resume only the tasks whose files
  // are not complete on disk.
  std::vector<Task> tasks;
  for (const Task& j : jobs)
    for (int s = 0; s < o.shards; ++s) {
      const auto first = j.items.begin() + std::ptrdiff_t(s) * j.stages;
      tasks.push_back({j.job, j.out, s, j.stages, {first, first + j.stages}, j.loaded});
    }
  int stage_count = 1;
  for (const Task& j : jobs) stage_count = std::max(stage_count, j.stages);
  // Task t's pieces of stage `stage`.
  auto items_of = [&](const Task& t, int stage) -> const std::vector<StageItem>& {
    static const std::vector<StageItem> none;
    return stage < t.stages ? t.items[std::size_t(stage)] : none;
  };
  // Whether task t has work in stage `stage`, and (--resume) whether that work is not on disk yet.
  auto has_stage = [&](const Task& t, int stage) { return stage == 0 || !items_of(t, stage).empty(); };
  std::map<std::tuple<fs::path, fs::path, int, int>, bool> rebuild;  // (job, out, entry, stage)
  auto complete = [&](const Task& t, int stage) {
    if (o.tile_size > 0) return false;  // tile tasks are re-run whole
    const Job& job = *t.loaded;
    const FieldSize size = probe_field_size(job);
    const ShardId id{t.shard, o.shards};
    if (stage == 0 &&
        !shard_is_complete(shard_path(job, id), shard_identity(job, id, size.width, size.height)))
      return false;
    for (const StageItem& item : items_of(t, stage))
      if (!shard_is_complete(stage_item_path(job, stage, item),
                             stage_item_identity(job, stage, item, size.width, size.height)))
        return false;
    // The state file before the stage, which the stage's tasks make again (read once per entry and stage).
    for (const StageItem& item : items_of(t, stage)) {
      const auto key = std::make_tuple(t.job, t.out, item.entry, stage);
      auto known = rebuild.find(key);
      if (known == rebuild.end())
        known = rebuild.emplace(key, stage_state_to_rebuild(job, item.entry, stage, size.width, size.height))
                    .first;
      if (known->second) return false;
    }
    return true;
  };
  std::vector<std::vector<int>> submit(static_cast<std::size_t>(stage_count));  // per stage: task indices
  for (int stage = 0; stage < stage_count; ++stage)
    for (std::size_t t = 0; t < tasks.size(); ++t)
      if (has_stage(tasks[t], stage) && !(o.resume && complete(tasks[t], stage)))
        submit[std::size_t(stage)].push_back(int(t));

  const std::string mem =
      !o.mem.empty()
          ? o.mem
          : std::to_string(std::max<std::size_t>(512, (need_bytes + need_bytes / 5) >> 20) + 1) + "M";
  const std::string exe = shell_quoted(own_executable().string());
  const std::string name = jobs.size() == 1 ? jobs.front().job.stem().string() : common.filename().string();
  // What goes into the scripts' comment and #SBATCH lines unquoted: a line break (or another control
  // character) there would end the line and start a command of its own.
  {
    std::vector<std::pair<std::string, std::string>> lines = {
        {"the output folder", dir.string()},
        {"the working folder", fs::current_path().string()},
        {"the job name", name},
        {"--mem", mem},
        {"--partition", o.partition},
        {"--time", o.time}};
    for (const std::string& a : o.sbatch_args) lines.push_back({"--sbatch-arg", a});
    for (const Task& t : tasks) {
      lines.push_back({"the job file", t.job.string()});
      lines.push_back({t.job.string() + ": the output folder (output.dir or --out)", t.out.string()});
    }
    for (const auto& [what, text] : lines)
      if (std::any_of(text.begin(), text.end(), [](char c) { return (unsigned char)c < 0x20 || c == 0x7f; }))
        return fail(what + " \"" + text.substr(0, text.find_first_of("\r\n")) +
                    "...\" holds a line break or control character: it cannot go into a Slurm script");
    // The #SBATCH values themselves (--chdir, --output, --job-name): Slurm splits them at a blank, expands
    // a % (%j, %A, ...) in a file name, takes quotes and backslashes out and ends the line at a # (a
    // comment): another folder's name, where the tasks would bake another folder's job file.
    for (const auto& [what, text] : {lines[0], lines[1], lines[2]})
      if (text.find_first_of(" \t%\"'\\#") != std::string::npos)
        return fail(
            what + " \"" + text +
            "\" holds a blank, a %, a #, a quote or a backslash: Slurm's #SBATCH lines would split, " +
            "expand, cut or unquote it; use a folder and job file whose names have none");
    // Every other #SBATCH line ends at a # too: what follows it would be dropped without a word.
    for (std::size_t n = 3; n < lines.size(); ++n)
      if (lines[n].first.rfind("--", 0) == 0 && lines[n].second.find('#') != std::string::npos)
        return fail(lines[n].first + " \"" + lines[n].second +
                    "\" holds a #: Slurm reads the rest of its #SBATCH line as a comment");
  }
  // What the scripts set themselves (the logs' names, the working folder, the array, the chain): an
  // --sbatch-arg may not set it too, or the tasks would run elsewhere and the merge's log be missed.
  struct Owned {
    const char* short_name;  // "" where sbatch has none
    const char* long_name;
    const char* instead;
  };
  static constexpr Owned kOwned[] = {
      {"-J", "--job-name", "the job file's name names the jobs"},
      {"-o", "--output", "the logs go to <output>/slurm/logs"},
      {"-e", "--error", "the logs go to <output>/slurm/logs"},
      {"-D", "--chdir", "the tasks run in the folder hfbake slurm runs in"},
      {"-a", "--array", "the tasks are the shards: give --shards"},
      {"-d", "--dependency", "hfbake slurm chains the stages and the merge"},
      {"", "--kill-on-invalid-dep", "hfbake slurm chains the stages and the merge"},
      {"-W", "--wait", "give --wait"},
      {"", "--parsable", "hfbake slurm reads sbatch's answer itself"},
      {"-c", "--cpus-per-task", "give --threads"},
      {"", "--mem", "give --mem"},
      {"", "--mem-per-cpu", "give --mem"},
  };
  for (const std::string& a : o.sbatch_args) {
    const std::string opt = a.substr(0, a.find_first_of("= "));
    for (const Owned& n : kOwned) {
      // A short option may carry its value: -ofile is -o file.
      const bool as_short = *n.short_name && (opt == n.short_name ||
                                              (a.size() > 2 && a.rfind(n.short_name, 0) == 0 && a[2] != '-'));
      if (as_short || opt == n.long_name)
        return fail("--sbatch-arg \"" + a + "\": the scripts set " + (as_short ? n.short_name : n.long_name) +
                    " themselves (" + n.instead + ")");
    }
  }
  // A job path as the scripts pass it: one that starts with '-' would be read as an option.
  const auto as_argument = [](const fs::path& p) {
    const std::string s = p.string();
    return shell_quoted(!s.empty() && s[0] == '-' ? "./" + s : s);
  };
  std::ostringstream head;
  auto common_head = [&](std::ostringstream& s, const std::string& job_name, const char* log) {
    s << "#SBATCH --job-name=" << job_name << "\n";
    s << "#SBATCH --chdir=" << fs::current_path().string() << "\n";  // job paths are as given
    s << "#SBATCH --output=" << (dir / "logs" / log).string() << "\n";
    s << "#SBATCH --mem=" << mem << "\n";
    s << "#SBATCH --cpus-per-task=" << o.threads << "\n";
    if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
    if (!o.time.empty()) s << "#SBATCH --time=" << o.time << "\n";
    for (const std::string& a : o.sbatch_args) s << "#SBATCH " << a << "\n";
  };

  // glibc's double math functions (sin, exp, pow, atan2, ...) give other last bits in 1 input in 1400 to 3700
  // with their FMA variants than with their SSE2 ones: every task and the merge take the SSE2 ones, so the
  // farm's bits do not depend on which machines have FMA (docs/cluster.md). Appended to the tunables the
  // task has; a glibc.cpu.hwcaps of its own given before is replaced by this one.
  const std::string baseline_math = "export GLIBC_TUNABLES=\"${GLIBC_TUNABLES:+$GLIBC_TUNABLES:}" +
                                    std::string(kBaselineMathTunable) + "\"\n";
  std::ostringstream bake;
  bake << "#!/bin/bash\n"
       << "# Written by hfbake " << shard_version() << " (hfbake slurm): one array task per (job, shard).\n"
       << "# Each task bakes one shard into <output>/shards/ (a re-run of a finished shard does nothing).\n"
       << "# Resubmit some tasks by hand: sbatch --array=2,5 " << (dir / "bake.sbatch").string() << "\n"
       << "# Argument: the stage (default 0; p2's bounce b is stage b, its direction blocks across the "
          "tasks,\n"
       << "# run after stage b - 1 of every task:\n"
       << "#   sbatch --array=0-1 --dependency=afterok:<stage 0's job id> " << (dir / "bake.sbatch").string()
       << " 1).\n"
       << "# Memory: the job's estimate (hfbake validate) + 20 %; every task holds whole-field layers.\n";
  common_head(bake, "hfbake-" + name, "%x-%A_%a.out");
  bake << "#SBATCH --array=0-" << tasks.size() - 1 << "\n"
       << "#SBATCH --requeue\n"
       << "set -euo pipefail\n"
       << "N=" << o.shards << "\n"
       << "JOBS=(\n";
  for (const Task& t : tasks) bake << "  " << as_argument(t.job) << "\n";
  bake << ")\nOUTS=(\n";
  for (const Task& t : tasks) bake << "  " << shell_quoted(t.out.string()) << "\n";
  bake << ")\nSHARDS=(";
  for (const Task& t : tasks) bake << " " << t.shard;
  bake << " )\n"
       << baseline_math << "i=${SLURM_ARRAY_TASK_ID:?run me with sbatch --array}\n"
       << "STAGE=${1:-0}\n"
       << "exec " << exe << " bake \"${JOBS[$i]}\" "
       << (o.tile_size > 0
               ? "--tiles --tile-size " + std::to_string(o.tile_size) + " --tile-task \"${SHARDS[$i]}/$N\""
               : std::string("--shard \"${SHARDS[$i]}/$N\" --stage \"$STAGE\""))
       << " --out \"${OUTS[$i]}\""
       << " --threads \"${SLURM_CPUS_PER_TASK:-" << o.threads << "}\"" << bake_flags(o)
       << (o.quiet ? " --quiet" : "") << "\n";

  std::ostringstream merge;
  merge << "#!/bin/bash\n"
        << "# Written by hfbake " << shard_version()
        << " (hfbake slurm): merges the shards into the outputs\n"
        << "# `hfbake bake` writes (bit-identical). It names any shard that is missing or damaged.\n"
        << "# Run it by hand after resubmitting tasks: sbatch " << (dir / "merge.sbatch").string() << "\n";
  common_head(merge, "hfbake-merge-" + name, "%x-%j.out");
  merge << "set -euo pipefail\n" << baseline_math << "exec " << exe << " merge";
  for (const fs::path& f : o.inputs) merge << " " << as_argument(f);
  if (o.out) merge << " --out " << shell_quoted(o.out->string());
  if (o.tile_size > 0) merge << " --tiles --tile-size " << o.tile_size;
  merge << " --threads \"${SLURM_CPUS_PER_TASK:-" << o.threads << "}\"" << bake_flags(o)
        << (o.quiet ? " --quiet" : "") << "\n";

  // The sbatch command of stage `stage`'s array (tasks `list`) after job `after` (empty: none), and of the
  // merge: what is run below, and what --dry-run prints.
  auto array_command = [&](const std::vector<int>& list, const std::string& after, int stage) {
    std::string cmd = "sbatch --parsable --array=" + array_list(list);
    if (!after.empty()) cmd += " --dependency=afterok:" + after + " --kill-on-invalid-dep=yes";
    cmd.append(1, ' ').append(shell_quoted((dir / "bake.sbatch").string()));
    if (stage > 0) cmd.append(1, ' ').append(std::to_string(stage));
    return cmd;
  };
  auto merge_command = [&](const std::string& after) {
    std::string cmd = "sbatch --parsable";
    if (!after.empty()) cmd += " --dependency=afterok:" + after + " --kill-on-invalid-dep=yes";
    if (o.wait) cmd += " --wait";
    return cmd.append(1, ' ').append(shell_quoted((dir / "merge.sbatch").string()));
  };
  if (o.dry_run) {
    std::printf("# ---- %s\n%s\n# ---- %s\n%s\n# ---- the submissions (job ids in <>)\n",
                (dir / "bake.sbatch").c_str(), bake.str().c_str(), (dir / "merge.sbatch").c_str(),
                merge.str().c_str());
    std::string after;
    for (int stage = 0; stage < stage_count; ++stage) {
      const std::vector<int>& list = submit[std::size_t(stage)];
      if (list.empty()) continue;
      std::printf("%s\n", array_command(list, after, stage).c_str());
      after = "<stage " + std::to_string(stage) + " array>";
    }
    std::printf("%s\n", merge_command(after).c_str());
    return 0;
  }

  try {
    // The scripts and the logs go inside the output folder only: a link at slurm/ or logs/ is refused.
    for (const fs::path& d : {dir, dir / "logs"}) {
      fs::create_directories(d);
      if (!is_real_directory(d))
        return fail(d.string() + ": not a folder (a link?): the scripts are written inside " +
                    common.string() + " only");
    }
    write_file(dir / "bake.sbatch", bake.str());
    write_file(dir / "merge.sbatch", merge.str());
  } catch (const std::exception& e) {
    return fail(dir.string() + ": " + e.what());
  }

  // One array per stage, each after the previous (afterok: every task of it succeeded).
  std::string array_id;
  for (int stage = 0; stage < stage_count; ++stage) {
    const std::vector<int>& list = submit[std::size_t(stage)];
    if (list.empty()) continue;
    std::string out;
    const std::string cmd = array_command(list, array_id, stage) + " 2>&1";
    if (run_capture(cmd, &out) != 0)
      return fail((dir / "bake.sbatch").string() + ": sbatch failed: " + one_line(out));
    array_id = out.substr(0, out.find_first_of(";\n"));
    if (!o.quiet)
      std::fprintf(stderr, "hfbake: submitted %zu task%s of stage %d as array job %s (%s)\n", list.size(),
                   list.size() == 1 ? "" : "s", stage, array_id.c_str(), (dir / "bake.sbatch").c_str());
  }
  if (array_id.empty() && !o.quiet)
    std::fprintf(stderr, "hfbake: every shard is complete; submitting the merge only\n");
  const std::string cmd = merge_command(array_id) + " 2>&1";
  std::string out;
  int status = run_capture(cmd, &out);
  const std::string merge_id = out.substr(0, out.find_first_of(";\n"));
  if (!o.wait) {
    if (status != 0) return fail((dir / "merge.sbatch").string() + ": sbatch failed: " + one_line(out));
    if (!o.quiet) std::fprintf(stderr, "hfbake: submitted the merge as job %s (afterok)\n", merge_id.c_str());
    return 0;
  }
  // `sbatch --wait` exits 0 for a merge that Slurm cancelled because a task failed (its afterok can never
  // be met: Slurm 22.05): a merge that ran has its log, which Slurm opens when the job starts.
  const fs::path merge_log = dir / "logs" / ("hfbake-merge-" + name + "-" + merge_id + ".out");
  bool merge_ran = true;
  if (status == 0 && !fs::exists(merge_log)) {
    merge_ran = false;
    status = 2;
  }
  if (status != 0 && o.tile_size == 0) {
    // Name what is missing: the shards no task completed (named as at submission: the job file may have
    // changed or gone since).
    for (const Task& t : tasks) {
      const Job& job = *t.loaded;
      const fs::path p = shard_path(job, {t.shard, o.shards});
      if (!fs::exists(p))
        std::fprintf(stderr, "hfbake: error: %s: shard %d/%d is missing (its task failed: see %s)\n",
                     p.c_str(), t.shard, o.shards, (dir / "logs").c_str());
      // Staged entries: the pieces of this shard of the first stage where one is missing.
      for (int st = 0; st < t.stages; ++st) {
        bool missing = false;
        for (const StageItem& item : items_of(t, st)) {
          const fs::path sp = stage_item_path(job, st, item);
          if (fs::exists(sp) || (item.block >= 0 && fs::exists(stage_path(job, item.entry, st)))) continue;
          missing = true;
          std::fprintf(
              stderr, "hfbake: error: %s: %s of %s is missing (its task failed: see %s)\n", sp.c_str(),
              (item.block < 0 ? "stage " + std::to_string(st)
                              : "block " + std::to_string(item.block) + " of stage " + std::to_string(st))
                  .c_str(),
              job.bakes[std::size_t(item.entry)].stem.c_str(), (dir / "logs").c_str());
        }
        if (missing) break;
      }
    }
  }
  if (!merge_ran)
    std::fprintf(stderr,
                 "hfbake: error: %s: the merge job %s never ran: Slurm cancelled it because a task failed "
                 "(logs: %s)\n",
                 (dir / "merge.sbatch").c_str(), merge_id.c_str(), (dir / "logs").c_str());
  else if (status != 0)
    std::fprintf(stderr, "hfbake: error: %s: the merge job %s ended with status %d (log: %s)\n",
                 (dir / "merge.sbatch").c_str(), merge_id.c_str(), status, (dir / "logs").c_str());
  return status;
}

}  // namespace hfbake
