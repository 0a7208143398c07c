// Runs the built hfbake binary (HFBAKE_BINARY) as a user's shell would, for the end-to-end tests.
#pragma once

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace hfbake::cli_test {

struct Result {
  int exit_code = -1;
  std::string err;  // stderr
  std::vector<std::string> error_lines() const {
    std::vector<std::string> lines;
    std::istringstream in(err);
    for (std::string l; std::getline(in, l);)
      if (l.rfind("hfbake: error: ", 0) == 0) lines.push_back(l);
    return lines;
  }
};

// `hfbake ARGS` with stderr captured through a file in `dir` and stdout discarded.
inline Result run_hfbake(const std::filesystem::path& dir, const std::string& args) {
  const std::filesystem::path err = dir / "stderr.txt";
  const std::string cmd = std::string(HFBAKE_BINARY) + " " + args + " 2>" + err.string() + " >/dev/null";
  const int status = std::system(cmd.c_str());
  Result r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::stringstream ss;
  ss << in.rdbuf();
  r.err = ss.str();
  return r;
}

// The estimate `hfbake validate JOB` prints ("valid (WxH, about 12.3 MiB to bake: ..."), in MiB; -1 when
// validate fails or prints none.
inline double validate_estimate_mib(const std::filesystem::path& dir, const std::filesystem::path& job) {
  const Result v = run_hfbake(dir, "validate " + job.string());
  const auto at = v.err.find("about ");
  if (v.exit_code != 0 || at == std::string::npos) return -1;
  std::size_t used = 0;
  const double value = std::stod(v.err.substr(at + 6), &used);
  const std::string unit = v.err.substr(at + 6 + used, 4);
  return unit == " GiB" ? value * 1024 : unit == " MiB" ? value : -1;
}

// `hfbake ARGS` in `dir` (stderr discarded), waited for alone: its exit code (-1: it did not exit) and its
// own peak resident memory in MiB (wait4's ru_maxrss; getrusage's RUSAGE_CHILDREN would give the largest of
// every child this process ever waited for).
struct BakePeak {
  int exit_code = -1;
  double peak_mib = 0;
};
inline BakePeak run_peak(const std::filesystem::path& dir, const std::vector<std::string>& args) {
  BakePeak r;
  std::vector<char*> argv{const_cast<char*>("hfbake")};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return r;
  if (pid == 0) {
    if (chdir(dir.c_str()) != 0 || !freopen("/dev/null", "w", stderr)) _exit(126);
    execv(HFBAKE_BINARY, argv.data());
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid) return r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.peak_mib = double(usage.ru_maxrss) / 1024.0;
  return r;
}
// `hfbake bake --quiet --no-cache JOB` as run_peak runs it.
inline BakePeak bake_peak(const std::filesystem::path& dir, const std::filesystem::path& job) {
  return run_peak(dir, {"bake", "--quiet", "--no-cache", job.string()});
}

}  // namespace hfbake::cli_test
