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

}  // namespace
}  // namespace ballbar::acquisition::testing
