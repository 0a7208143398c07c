// Progress lines in a log (lines mode): a line at every quarter and, once a minute has passed, at the next
// whole percent, with the elapsed and the remaining time; jobs reporting side by side keep their own counts.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "cli/progress.hpp"

namespace hfbake {
namespace {

using namespace std::chrono_literals;

std::chrono::steady_clock::time_point fake_now;  // the clock the Progress under test reads
std::chrono::steady_clock::time_point read_fake_clock() {
  return fake_now;
}

class ProgressLines : public ::testing::Test {
 protected:
  void SetUp() override {
    fake_now = std::chrono::steady_clock::time_point{};
    out_ = std::tmpfile();
    ASSERT_NE(out_, nullptr);
  }
  void TearDown() override { std::fclose(out_); }
  std::string written() {  // everything written since the last call
    std::fflush(out_);
    const long end = std::ftell(out_);
    std::string text(std::size_t(end - read_), '\0');
    std::fseek(out_, read_, SEEK_SET);
    text.resize(std::fread(text.data(), 1, text.size(), out_));
    std::fseek(out_, end, SEEK_SET);
    read_ = end;
    return text;
  }
  std::FILE* out_ = nullptr;
  long read_ = 0;
};

TEST_F(ProgressLines, QuartersAndAMinutelyLineWithElapsedAndRemainingTime) {
  Progress p(Progress::Mode::lines, out_, &read_fake_clock);
  p.begin("big", "farfield");
  EXPECT_EQ(written(), "hfbake: big: farfield ...\n");
  fake_now += 30s;
  p.update("big", "farfield", 0.10);
  EXPECT_EQ(written(), "");  // under a minute, no quarter
  fake_now += 31s;
  p.update("big", "farfield", 0.20);
  EXPECT_EQ(written(), "hfbake: big: farfield 20% (61 s, about 4 min left)\n");
  fake_now += 9s;
  p.update("big", "farfield", 0.21);
  EXPECT_EQ(written(), "");  // a minute has not passed since the last line
  fake_now += 10s;
  p.update("big", "farfield", 0.26);
  EXPECT_EQ(written(), "hfbake: big: farfield 26% (80 s, about 4 min left)\n");  // a quarter: at once
  fake_now += 2h;
  p.update("big", "farfield", 0.26);
  EXPECT_EQ(written(), "");  // the same percent again
  p.update("big", "farfield", 0.5);
  EXPECT_EQ(written(), "hfbake: big: farfield 50% (2 h 01 min, about 2 h 01 min left)\n");
  p.update("big", "farfield", 1.0);
  EXPECT_EQ(written(), "");  // 100 % is said by "done"
  p.end("big", "farfield", 7300);
  EXPECT_EQ(written(), "hfbake: big: farfield done in 7300.00 s\n");
}

TEST_F(ProgressLines, JobsSideBySideKeepTheirOwnCounts) {
  Progress p(Progress::Mode::lines, out_, &read_fake_clock);
  p.begin("a", "p1");
  fake_now += 100s;
  p.begin("b", "p1");
  EXPECT_EQ(written(), "hfbake: a: p1 ...\nhfbake: b: p1 ...\n");
  fake_now += 20s;
  p.update("a", "p1", 0.3);
  EXPECT_EQ(written(), "hfbake: a: p1 30% (2 min, about 5 min left)\n");
  p.update("b", "p1", 0.3);
  EXPECT_EQ(written(), "hfbake: b: p1 30% (20 s, about 47 s left)\n");
  fake_now += 61s;
  p.update("a", "p1", 0.31);
  EXPECT_EQ(written(), "hfbake: a: p1 31% (3 min, about 7 min left)\n");
}

TEST_F(ProgressLines, QuietWritesNothingButErrors) {
  Progress p(Progress::Mode::quiet, out_, &read_fake_clock);
  p.begin("a", "p1");
  p.update("a", "p1", 0.5);
  p.end("a", "p1", 1);
  p.message("wrote x");
  EXPECT_EQ(written(), "");
  p.error("x.json: /bake/0: bad");
  EXPECT_EQ(written(), "hfbake: error: x.json: /bake/0: bad\n");
}

}  // namespace
}  // namespace hfbake
