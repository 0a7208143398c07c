// Progress on stderr: a live bar when stderr is a terminal, plain lines otherwise, nothing when quiet.
// Thread-safe: several jobs and the methods' worker threads report concurrently.
#pragma once

#include <time.h>

#include <chrono>
#include <mutex>
#include <string>

namespace hfbake {

// Wall seconds since t0.
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// CPU seconds of the whole process (all worker threads): the cost of a method on a shared, loaded machine,
// where wall time measures the other users too.
inline double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

class Progress {
 public:
  enum class Mode { quiet, lines, bar };
  explicit Progress(Mode mode) : mode_(mode) {}
  static Mode detect(bool quiet);  // quiet, else bar on a terminal, else lines

  // A step of a job begins ("demo", "p1"); fraction updates follow; end() prints its time.
  void begin(const std::string& job, const std::string& step);
  void update(const std::string& job, const std::string& step, double fraction);
  void end(const std::string& job, const std::string& step, double seconds);
  // A one-off message (e.g. "wrote out/demo/demo.p1.exr"), printed above the bar.
  void message(const std::string& text);
  // An error line "hfbake: error: <line>": printed even when quiet.
  void error(const std::string& line);

 private:
  void clear_bar_locked();
  Mode mode_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point last_draw_{};
  int last_line_percent_ = -1;
  std::string last_line_key_;
  bool bar_visible_ = false;
};

}  // namespace hfbake
