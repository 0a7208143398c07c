// hfbake: bakes ambient occlusion and lighting for height fields. See README.md and the contract.
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>
#include <thread>

#include "cli/bake_command.hpp"
#include "cli/compare_command.hpp"
#include "cli/version.hpp"
#include "io/exr_output.hpp"

namespace {

// The process-wide state a signal handler may touch (both lock-free atomics).
std::atomic<bool> g_interrupted{false};
std::atomic<int> g_signal{0};  // the first signal that stopped the bake: its exit status is 128 + it
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free);

// SIGINT (Ctrl-C), SIGTERM (kill, timeout, cron, CI) and SIGHUP (the terminal went away) all stop the bake
// at its next check; the staging folders are removed on the way out. A second signal stops at once: the
// staging folders left behind carry this process's id and the next bake of that folder removes them.
extern "C" void on_stop_signal(int sig) {
  int none = 0;
  g_signal.compare_exchange_strong(none, sig);
  if (g_interrupted.exchange(true)) std::_Exit(128 + sig);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hfbake: offline baker of ambient occlusion and lighting for height fields"};
  app.require_subcommand(0, 1);
  app.set_version_flag("--version", std::string("hfbake ") + hfbake::hfbake_version());

  hfbake::BakeOptions bake;
  int threads = 0;
  std::vector<std::string> bake_jobs, validate_jobs;
  std::string out, summary;
  bool validate_quiet = false;

  CLI::App* bake_cmd = app.add_subcommand("bake", "Bake every job (continues past a failed job)");
  bake_cmd->add_option("jobs", bake_jobs, "Job files (JSON)")->required()->check(CLI::ExistingFile);
  bake_cmd->add_option("--threads", threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  bake_cmd->add_option("--out", out, "Output folder, replacing each job's output.dir");
  bake_cmd->add_flag("--quiet", bake.quiet, "No progress output (errors are still printed)");
  bake_cmd->add_option("--summary", summary, "Write a machine-readable JSON summary to FILE");
  std::string cache_dir;
  bake_cmd->add_option("--cache", cache_dir,
                       "Reference cache folder (default: $XDG_CACHE_HOME/hfbake/references or "
                       "~/.cache/hfbake/references)");
  bake_cmd->add_flag("--no-cache", bake.no_cache,
                     "Always compute references; do not read or write the cache");
  const auto memory_size = CLI::Validator(
      [](std::string& text) {
        return hfbake::parse_memory_size(text) ? std::string()
                                               : "not a size (e.g. 512M, 8G, 1.5GiB, or bytes): " + text;
      },
      "SIZE");
  std::string memory_limit;
  bake_cmd
      ->add_option("--memory-limit", memory_limit,
                   "Refuse a job whose memory estimate exceeds SIZE (default: the available memory)")
      ->check(memory_size);

  hfbake::CompareOptions compare;
  std::string compare_json;
  CLI::App* compare_cmd = app.add_subcommand(
      "compare",
      "Compare a report.json (or every report.json under a folder) with a baseline; exit 1 on regression");
  compare_cmd
      ->add_option("new", compare.now, "The new report.json (or a folder of them, e.g. a suite's output)")
      ->required();
  compare_cmd->add_option("baseline", compare.baseline, "The baseline report.json (or folder)")->required();
  compare_cmd->add_option("--tolerance", compare.tolerances,
                          "METRIC=REL[,ABS]: check METRIC (mae, rmse, rel_mae, excess_rmse, p99, max, psnr, "
                          "bias, noise_rmse, seconds) with these tolerances (default: mae, rmse, excess_rmse "
                          "at 0.05,1e-5)");
  compare_cmd->add_flag("--all", compare.all, "List every checked metric, not only the changes");
  compare_cmd->add_flag("--update-baseline", compare.update_baseline,
                        "After comparing, write NEW over BASELINE (the only way a baseline changes)");
  compare_cmd->add_flag("--allow-different-job", compare.allow_different_job,
                        "Compare even when BASELINE is a report of another job (other name, field, scene or "
                        "reference settings); the differences are printed");
  compare_cmd->add_option("--json", compare_json, "Also write the comparison as JSON to FILE");
  compare_cmd->add_flag("--quiet", compare.quiet, "Print only errors");

  CLI::App* validate_cmd = app.add_subcommand("validate", "Check jobs against the schema and their files");
  validate_cmd->add_option("jobs", validate_jobs, "Job files (JSON)")->required();
  validate_cmd->add_flag("--quiet", validate_quiet, "Print only problems");
  std::string validate_memory_limit;
  validate_cmd->add_option("--memory-limit", validate_memory_limit, "As bake's --memory-limit")
      ->check(memory_size);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::fprintf(stderr, "hfbake: error: command line: %s\n", e.what());
    return 2;
  }
  if (app.got_subcommand(validate_cmd)) {
    std::vector<std::filesystem::path> files(validate_jobs.begin(), validate_jobs.end());
    return hfbake::run_validate(
        files, validate_quiet,
        validate_memory_limit.empty() ? std::nullopt : hfbake::parse_memory_size(validate_memory_limit));
  }
  if (app.got_subcommand(compare_cmd)) {
    if (!compare_json.empty()) compare.json = compare_json;
    return hfbake::run_compare(compare);
  }
  if (!app.got_subcommand(bake_cmd)) {
    std::fputs(app.help().c_str(), stdout);
    return 2;
  }

  bake.jobs.assign(bake_jobs.begin(), bake_jobs.end());
  if (!out.empty()) bake.out = out;
  if (!summary.empty()) bake.summary = summary;
  if (!cache_dir.empty()) bake.cache = cache_dir;
  if (!memory_limit.empty()) bake.memory_limit = hfbake::parse_memory_size(memory_limit);
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  std::size_t(threads));
  // EXR outputs compress their chunks on OpenEXR's thread pool, as many workers as the bake has (the files'
  // bytes do not depend on it).
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  hfbake::start_exr_thread_pool(threads > 0 ? threads : int(cores));
  bake.interrupt_signal = &g_signal;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;
    sigaction(sig, &action, nullptr);
  }
  return hfbake::run_bake(bake, g_interrupted);
}
