// Progress on stderr: a live bar when stderr is a terminal, plain lines otherwise, nothing when quiet.
// Thread-safe: several jobs and the methods' worker threads report concurrently.
#pragma once

#include <time.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
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
  // quiet: warnings and errors only; silent: nothing (the caller reports the warnings from JobOutcome, as the
  // Python module does).
  enum class Mode { quiet, lines, bar, silent };
  using Clock = std::chrono::steady_clock::time_point (*)();
  // Everything goes to `out`; `clock` is what the bar's redraw interval and the lines' elapsed and remaining
  // times are read from (both for tests; the program uses stderr and the steady clock).
  explicit Progress(Mode mode, std::FILE* out = stderr, Clock clock = &std::chrono::steady_clock::now)
      : mode_(mode), out_(out), clock_(clock) {}
  static Mode detect(bool quiet);  // quiet, else bar on a terminal, else lines

  // A step of a job begins ("demo", "p1"); fraction updates follow; end() prints its time. In lines mode
  // (a log, a farm's output file) a line "<job>: <step> P% (<elapsed>, about <left> left)" comes at every
  // quarter, and at the next whole percent once a minute has passed since the step's last line, so an
  // hour-long step shows it is alive and when it will end.
  void begin(const std::string& job, const std::string& step);
  void update(const std::string& job, const std::string& step, double fraction);
  void end(const std::string& job, const std::string& step, double seconds);
  // Called by every update() with the step's fraction, in any mode, from the thread that reports (the
  // Python module's progress callback); it must be thread-safe.
  using Observer = std::function<void(const std::string& job, const std::string& step, double fraction)>;
  void set_observer(Observer observer) { observer_ = std::move(observer); }
  // A one-off message (e.g. "wrote out/demo/demo.p1.exr"), printed above the bar.
  void message(const std::string& text);
  // A message that warns ("warning: ..."): printed above the bar as message() does, and even when quiet.
  void warning(const std::string& text);
  // An error line "hfbake: error: <line>": printed even when quiet (not when silent).
  void error(const std::string& line);

 private:
  bool shows_steps() const { return mode_ == Mode::lines || mode_ == Mode::bar; }
  void clear_bar_locked();
  void line_locked(const std::string& job, const std::string& step, double fraction);
  Mode mode_;
  Observer observer_;
  std::FILE* out_;
  Clock clock_;
  struct StepLines {  // lines mode: one step's start, its last line and that line's percent
    std::chrono::steady_clock::time_point start, last;
    int percent = 0;
  };
  std::map<std::string, StepLines> steps_;  // by "<job>/<step>": jobs may bake side by side
  std::mutex mutex_;
  std::chrono::steady_clock::time_point last_draw_{};
  bool bar_visible_ = false;
};

}  // namespace hfbake
