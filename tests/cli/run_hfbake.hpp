// Runs the built hfbake binary (HFBAKE_BINARY) as a user's shell would, for the end-to-end tests.
#pragma once

#include <sys/wait.h>

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

}  // namespace hfbake::cli_test
