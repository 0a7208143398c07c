// hfbake as a child process, for the tests that kill bakes (SIGKILL at random moments, killed references that
// resume): start it with its stderr in a file, wait for its exit, and tell a staging folder by its name.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace hfbake_test {

// `hfbake args...` with stderr to `err` and stdout to /dev/null; in `cwd` when given; with `alarm_seconds`, a
// hang ends in SIGALRM instead of stalling the suite; `in_child` runs in the child just before exec (it knows
// the process id hfbake will have).
inline pid_t start_hfbake(const std::vector<std::string>& args, const std::filesystem::path& err,
                          const std::filesystem::path& cwd = {}, unsigned alarm_seconds = 0,
                          const std::function<void()>& in_child = {}) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (!freopen(err.c_str(), "w", stderr) || !freopen("/dev/null", "w", stdout)) _exit(126);
    if (!cwd.empty() && chdir(cwd.c_str()) != 0) _exit(126);
    if (in_child) in_child();
    if (alarm_seconds) alarm(alarm_seconds);
    std::vector<char*> argv{const_cast<char*>("hfbake")};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(HFBAKE_BINARY, argv.data());
    _exit(127);
  }
  return pid;
}

// The exit code, or minus the signal that ended the process.
inline int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

inline bool is_stage(const std::filesystem::path& p) {
  return p.filename().string().rfind(".hfbake-staging-", 0) == 0;
}

// How many staging folders `dir` holds.
inline int stages_in(const std::filesystem::path& dir) {
  int n = 0;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    n += is_stage(it->path());
  return n;
}

}  // namespace hfbake_test
