#include "cli/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace hfbake {

Progress::Mode Progress::detect(bool quiet) {
  if (quiet) return Mode::quiet;
  return isatty(STDERR_FILENO) ? Mode::bar : Mode::lines;
}

void Progress::clear_bar_locked() {
  if (bar_visible_) {
    std::fputs("\r\033[2K", stderr);
    bar_visible_ = false;
  }
}

void Progress::begin(const std::string& job, const std::string& step) {
  if (mode_ == Mode::quiet) return;
  std::lock_guard lock(mutex_);
  clear_bar_locked();
  std::fprintf(stderr, "hfbake: %s: %s ...\n", job.c_str(), step.c_str());
  last_line_percent_ = 0;
  last_line_key_ = job + "/" + step;
}

void Progress::update(const std::string& job, const std::string& step, double fraction) {
  if (mode_ == Mode::quiet) return;
  fraction = fraction < 0 ? 0 : (fraction > 1 ? 1 : fraction);
  std::lock_guard lock(mutex_);
  if (mode_ == Mode::lines) {
    // Plain lines every 25 %, so logs stay short.
    const int percent = int(fraction * 4) * 25;
    const std::string key = job + "/" + step;
    if (key == last_line_key_ && percent <= last_line_percent_) return;
    if (percent == 0 || percent == 100) return;
    last_line_key_ = key;
    last_line_percent_ = percent;
    std::fprintf(stderr, "hfbake: %s: %s %d%%\n", job.c_str(), step.c_str(), percent);
    return;
  }
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100) && fraction < 1) return;
  last_draw_ = now;
  constexpr int width = 30;
  const int filled = int(fraction * width + 0.5);
  std::string bar(std::size_t(filled), '#');
  bar.append(std::size_t(width - filled), '-');
  std::fprintf(stderr, "\r\033[2K%s: %s [%s] %3d%%", job.c_str(), step.c_str(), bar.c_str(),
               int(fraction * 100));
  std::fflush(stderr);
  bar_visible_ = true;
}

void Progress::end(const std::string& job, const std::string& step, double seconds) {
  if (mode_ == Mode::quiet) return;
  std::lock_guard lock(mutex_);
  clear_bar_locked();
  std::fprintf(stderr, "hfbake: %s: %s done in %.2f s\n", job.c_str(), step.c_str(), seconds);
}

void Progress::message(const std::string& text) {
  if (mode_ == Mode::quiet) return;
  std::lock_guard lock(mutex_);
  clear_bar_locked();
  std::fprintf(stderr, "hfbake: %s\n", text.c_str());
}

void Progress::error(const std::string& line) {
  std::lock_guard lock(mutex_);
  clear_bar_locked();
  std::fprintf(stderr, "hfbake: error: %s\n", line.c_str());
}

}  // namespace hfbake
