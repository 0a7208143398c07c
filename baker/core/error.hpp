// Errors that reach the user as one line: "hfbake: error: <file>: <where>: <what>".
#pragma once

#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>

namespace hfbake {

// Text from a file (a key, a name, a library's message) made fit for a one-line message: control bytes
// (a newline in a JSON key, a CR in a library's message) as \xNN.
inline std::string printable(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7f) {
      out.push_back(c);
    } else {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", unsigned(u));
      out += hex;
    }
  }
  return out;
}

// Bad input: a job, schema, image or value the user can fix. Exit code 2.
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string where, const std::string& what)
      : std::runtime_error(what), file_(std::move(file)), where_(std::move(where)) {}
  const std::string& file() const { return file_; }
  const std::string& where() const { return where_; }
  // "<file>: <where>: <what>" with empty parts left out, on one line (printable).
  std::string line() const {
    std::string s = file_;
    if (!where_.empty()) s += (s.empty() ? "" : ": ") + where_;
    return printable(s + (s.empty() ? "" : ": ") + what());
  }

 private:
  std::string file_, where_;
};

// An output that could not be written or moved into place (a full disk, an I/O error): one line like
// InputError's, but the job and its inputs are not at fault, so a bake reports it as status "failed", not
// "invalid" (a farm may retry it elsewhere).
class OutputError : public InputError {
 public:
  using InputError::InputError;
};

// A bake stopped because the user interrupted it (SIGINT). Exit code 130.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("interrupted") {}
};

}  // namespace hfbake
