// SPDX-License-Identifier: MIT
// The reduced fault campaign (the full one is bench/acquisition/bench_fault_campaign): randomised
// sessions over the three types and the plan shapes under disconnects, lost and replayed frames, a late
// start, a feed override and slow answers. No point at a wrong pose, no sample stored twice, every
// session done or interrupted with exactly its missing points.
#include <gtest/gtest.h>

#include "fault_campaign.hpp"

namespace ballbar::acquisition::testing {
namespace {

TEST(FaultCampaign, ReducedCampaignStoresNothingAtAWrongPoseAndFinishesEverySession) {
    const CampaignFigures f = run_campaign(12, 1000);
    EXPECT_EQ(f.sessions, 12);
    EXPECT_GT(f.points_stored, 100u);
    EXPECT_EQ(f.wrong_pose, 0u) << f.first_problem;
    EXPECT_EQ(f.not_finished, 0) << f.first_problem;
    EXPECT_EQ(f.stored_twice, 0u);
    EXPECT_GT(f.faults, 0u);
    EXPECT_GT(f.replayed_samples, 0u);
    EXPECT_LT(f.max_position_error_um, 1.0);
    EXPECT_LT(f.max_angle_error_arcsec, 2.0);
}

/// Issue 24: on a link losing a fifth of its frames and repeating a fifth, a capture window could run
/// past the end of its dwell into the next move (its few samples of motion kept the window's scatter
/// under the limit) and be stored as the point. A window now counts only when the bar stood still at
/// the same level for confirm_s after it, and ends that long before the program's G4 does.
TEST(FaultCampaign, AHostileLinkStoresNoWindowThatRunsIntoTheNextMove) {
    const CampaignLink link{0.2, 0.2};
    const CampaignFigures f = run_campaign(12, 2000, &link);
    EXPECT_EQ(f.sessions, 12);
    EXPECT_GT(f.points_stored, 100u);
    EXPECT_EQ(f.wrong_pose, 0u) << f.first_problem;
    EXPECT_EQ(f.not_finished, 0) << f.first_problem;
    EXPECT_GE(f.done, 9) << f.interrupted_reasons;  // at least 3 of 4 complete
}

}  // namespace
}  // namespace ballbar::acquisition::testing
