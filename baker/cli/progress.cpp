#include "cli/progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "core/error.hpp"

namespace hfbake {

Progress::Mode Progress::detect(bool quiet) {
  if (quiet) return Mode::quiet;
  return isatty(STDERR_FILENO) ? Mode::bar : Mode::lines;
}

void Progress::clear_bar_locked() {
  if (bar_visible_) {
    std::fputs("\r\033[2K", out_);
    bar_visible_ = false;
  }
}

void Progress::begin(const std::string& job, const std::string& step) {
  if (!shows_steps()) return;
  std::lock_guard lock(mutex_);
  clear_bar_locked();
  std::fprintf(out_, "hfbake: %s: %s ...\n", job.c_str(), step.c_str());
  const auto now = clock_();
  steps_[job + "/" + step] = StepLines{now, now, 0};
}

namespace {

// "45 s", "12 min", "1 h 05 min".
std::string duration_text(double seconds) {
  char text[32];
  if (seconds < 90)
    std::snprintf(text, sizeof text, "%.0f s", seconds);
  else if (seconds < 5400)
    std::snprintf(text, sizeof text, "%.0f min", seconds / 60);
  else
    std::snprintf(text, sizeof text, "%d h %02d min", int(seconds / 3600),
                  int(std::fmod(seconds, 3600) / 60));
  return text;
}

}  // namespace

void Progress::line_locked(const std::string& job, const std::string& step, double fraction) {
  const auto now = clock_();
  const int percent = int(fraction * 100);
  // A step never begun counts from its first update.
  StepLines& line = steps_.try_emplace(job + "/" + step, StepLines{now, now, 0}).first->second;
  if (percent <= line.percent || percent >= 100) return;
  const bool quarter = percent / 25 > line.percent / 25;
  if (!quarter && now - line.last < std::chrono::seconds(60)) return;
  line.percent = percent;
  line.last = now;
  const double elapsed = std::chrono::duration<double>(now - line.start).count();
  std::fprintf(out_, "hfbake: %s: %s %d%% (%s, about %s left)\n", job.c_str(), step.c_str(), percent,
               duration_text(elapsed).c_str(), duration_text(elapsed * (1 - fraction) / fraction).c_str());
}

void Progress::update(const std::string& job, const std::string& step, double fraction) {
  fraction = fraction < 0 ? 0 : (fraction > 1 ? 1 : fraction);
  if (observer_) observer_(job, step, fraction);
  if (!shows_steps()) return;
  std::lock_guard lock(mutex_);
  if (mode_ == Mode::lines) {
    line_locked(job, step, fraction);
    return;
  }
  const auto now = clock_();
  if (now - last_draw_ < std::chrono::milliseconds(100) && fraction < 1) return;
  last_draw_ = now;
  constexpr int width = 30;
  const int filled = int(fraction * width + 0.5);
  std::string bar(std::size_t(filled), '#');
  bar.append(std::size_t(width - filled), '-');
  std::fprintf(out_, "\r\033[2K%s: %s [%s] %3d%%", job.c_str(), step.c_str(), bar.c_str(),
               int(fraction * 100));
  std::fflush(out_);
  bar_visible_ = true;
}

void Progress::end(const std::string& job, const std::string& step, double seconds) {
  if (!shows_steps()) return;
  std::lock_guard lock(mutex_);
  clear_bar_locked();
  steps_.erase(job + "/" + step);
  std::fprintf(out_, "hfbake: %s: %s done in %.2f s\n", job.c_str(), step.c_str(), seconds);
}

void Progress::message(const std::string& text) {
  if (!shows_steps()) return;
  std::lock_guard lock(mutex_);
  clear_bar_locked();
  std::fprintf(out_, "hfbake: %s\n", printable(text).c_str());
}

void Progress::warning(const std::string& text) {
  if (mode_ == Mode::silent) return;
  std::lock_guard lock(mutex_);
  clear_bar_locked();
  std::fprintf(out_, "hfbake: %s\n", printable(text).c_str());
}

void Progress::error(const std::string& line) {
  if (mode_ == Mode::silent) return;
  std::lock_guard lock(mutex_);
  clear_bar_locked();
  std::fprintf(out_, "hfbake: error: %s\n", printable(line).c_str());
}

}  // namespace hfbake
