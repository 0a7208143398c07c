// Text as one word of a POSIX shell command line: what hfbake prints or writes for a person or a script to
// run (hfbake init's next step, hfbake slurm's scripts).
#pragma once

#include <string>
#include <string_view>

namespace hfbake {

// 'text', with each ' as '\''.
inline std::string shell_quoted(const std::string& text) {
  std::string q = "'";
  for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// text itself when a shell reads it as one word unchanged (letters, digits and _ . / - + = : , @ %, not
// starting with -), else shell_quoted.
inline std::string shell_word(const std::string& text) {
  bool plain = !text.empty() && text[0] != '-';
  for (char c : text)
    plain = plain && ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      std::string_view("_./-+=:,@%").find(c) != std::string_view::npos);
  return plain ? text : shell_quoted(text);
}

}  // namespace hfbake
