// Errors that reach the user as one line: "hfbake: error: <file>: <where>: <what>".
#pragma once

#include <cstddef>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>

namespace hfbake {

// Text from a file (a key, a name, a library's message) made fit for a one-line message: control bytes
// (a newline in a JSON key, a CR in a library's message) and bytes that are not well-formed UTF-8 (a job
// file in Latin-1) as \xNN; well-formed UTF-8 is kept.
inline std::string printable(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  auto escape = [&out](unsigned char u) {
    char hex[5];
    std::snprintf(hex, sizeof hex, "\\x%02x", unsigned(u));
    out += hex;
  };
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char u = static_cast<unsigned char>(s[i]);
    if (u < 0x80) {
      if (u >= 0x20 && u != 0x7f)
        out.push_back(char(u));
      else
        escape(u);
      ++i;
      continue;
    }
    // A sequence's length from its lead byte, and the range of its second byte (no overlong forms, no
    // surrogates, nothing beyond U+10FFFF).
    const std::size_t n = u >= 0xc2 && u <= 0xdf   ? 2
                          : u >= 0xe0 && u <= 0xef ? 3
                          : u >= 0xf0 && u <= 0xf4 ? 4
                                                   : 0;
    const unsigned char lo = u == 0xe0 ? 0xa0 : u == 0xf0 ? 0x90 : 0x80;
    const unsigned char hi = u == 0xed ? 0x9f : u == 0xf4 ? 0x8f : 0xbf;
    bool ok = n > 0 && i + n <= s.size();
    for (std::size_t k = 1; ok && k < n; ++k) {
      const unsigned char c = static_cast<unsigned char>(s[i + k]);
      ok = k == 1 ? c >= lo && c <= hi : c >= 0x80 && c <= 0xbf;
    }
    if (ok) {
      out.append(s.substr(i, n));
      i += n;
    } else {
      escape(u);
      ++i;
    }
  }
  return out;
}

// Whether s is well-formed UTF-8 (what printable keeps as it is, control characters aside): text JSON can
// hold, so a path that is not (a folder named in Latin-1) cannot be named in report.json or a summary.
inline bool is_utf8(std::string_view s) {
  std::string kept;
  for (const char c : s) kept.push_back(static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? ' ' : c);
  return printable(kept) == kept;
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
