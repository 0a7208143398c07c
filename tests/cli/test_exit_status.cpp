// run_bake's exit status (docs/contract.md "Exit status"): the worst of the jobs' outcomes, or 128 + the
// signal when a stop signal stopped some job. A signal that came after every job had ended, its outputs
// moved into place, interrupted nothing.
#include <gtest/gtest.h>
#include <signal.h>

#include <vector>

#include "cli/bake_command.hpp"

namespace {

using hfbake::JobOutcome;
using hfbake::JobStatus;

std::vector<JobOutcome> outcomes(std::initializer_list<JobStatus> statuses) {
  std::vector<JobOutcome> r;
  for (JobStatus s : statuses) r.emplace_back().status = s;
  return r;
}

TEST(ExitStatus, TheWorstOutcomeWithoutASignal) {
  EXPECT_EQ(hfbake::bake_exit_status(outcomes({JobStatus::ok, JobStatus::ok}), false, 0), 0);
  EXPECT_EQ(hfbake::bake_exit_status(outcomes({JobStatus::ok, JobStatus::threshold_failed}), false, 0), 1);
  EXPECT_EQ(hfbake::bake_exit_status(outcomes({JobStatus::threshold_failed, JobStatus::invalid}), false, 0),
            2);
  EXPECT_EQ(hfbake::bake_exit_status(outcomes({JobStatus::failed, JobStatus::ok}), false, 0), 2);
}

TEST(ExitStatus, ASignalThatStoppedAJobGivesItsStatus) {
  const auto stopped = outcomes({JobStatus::ok, JobStatus::cancelled});
  ASSERT_TRUE(hfbake::bake_interrupted(stopped, true));
  EXPECT_EQ(hfbake::bake_exit_status(stopped, true, SIGTERM), 128 + SIGTERM);
  EXPECT_EQ(hfbake::bake_exit_status(stopped, true, 0), 128 + SIGINT);  // no signal recorded: Ctrl-C
}

TEST(ExitStatus, ASignalAfterEveryJobEndedInterruptsNothing) {
  // The signal set the flag while the last job's outputs were moving into place: every job ended as baked.
  const auto done = outcomes({JobStatus::ok, JobStatus::threshold_failed});
  EXPECT_FALSE(hfbake::bake_interrupted(done, true));
  EXPECT_EQ(hfbake::bake_exit_status(done, hfbake::bake_interrupted(done, true), SIGINT), 1);
  EXPECT_FALSE(hfbake::bake_interrupted(outcomes({JobStatus::ok}), true));
  EXPECT_FALSE(hfbake::bake_interrupted(outcomes({JobStatus::cancelled}), false));
}

}  // namespace
