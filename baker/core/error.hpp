// Errors that reach the user as one line: "hfbake: error: <file>: <where>: <what>".
#pragma once

#include <stdexcept>
#include <string>

namespace hfbake {

// Bad input: a job, schema, image or value the user can fix. Exit code 2.
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string where, const std::string& what)
      : std::runtime_error(what), file_(std::move(file)), where_(std::move(where)) {}
  const std::string& file() const { return file_; }
  const std::string& where() const { return where_; }
  // "<file>: <where>: <what>" with empty parts left out.
  std::string line() const {
    std::string s = file_;
    if (!where_.empty()) s += (s.empty() ? "" : ": ") + where_;
    return s + (s.empty() ? "" : ": ") + what();
  }

 private:
  std::string file_, where_;
};

// A bake stopped because the user interrupted it (SIGINT). Exit code 130.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("interrupted") {}
};

}  // namespace hfbake
