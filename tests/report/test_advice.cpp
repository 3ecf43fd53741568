// SPDX-License-Identifier: MIT
// A diagnostic's action in the machine's terms: the axis, the direction of the correction and its size
// as the format defines the sign (docs/formats/trace.md), nothing for what the data does not show.
#include <gtest/gtest.h>

#include "ballbar/report/advice.hpp"

namespace {

using ballbar::report::diagnostic_action;

TEST(DiagnosticAction, NamesTheAxisTheDirectionAndTheSizeOfTheCorrection) {
    EXPECT_EQ(diagnostic_action("backlash_x_um", 3.04, 0.01, "XY"),
              "raise X's backlash compensation by 3.0 µm (lost motion at each reversal of X)");
    EXPECT_EQ(diagnostic_action("backlash_z_um", -2.0, 0.01, "YZ"),
              "lower Z's backlash compensation by 2.0 µm: it over-compensates");
    const std::string sq = diagnostic_action("squareness_um_per_m", -25.0, 0.1, "ZX");
    EXPECT_NE(sq.find("Z and X are out of square by 25.0 µm/m (5.2″, the angle between +Z and +X over 90°)"),
              std::string::npos)
        << sq;
    EXPECT_EQ(diagnostic_action("servo_mismatch_ms", -1.5, 0.01, "XY").rfind("Y lags X by 1.50 ms", 0), 0u);
    EXPECT_NE(diagnostic_action("scale_mismatch_ppm", 20, 0.1, "XY").find("X travels 20.0 ppm further than Y"),
              std::string::npos);
}

TEST(DiagnosticAction, NothingForWhatTheDataDoesNotShowOrAPitchOrAnUnknownKey) {
    EXPECT_EQ(diagnostic_action("straightness_y_um", -0.001, 0.003, "XY"), "");
    EXPECT_EQ(diagnostic_action("backlash_x_um", 0.05, 0.03, "XY"), "");
    EXPECT_EQ(diagnostic_action("cyclic_pitch_x_mm", 6.0, 0.0, "XY"), "");
    EXPECT_EQ(diagnostic_action("vibration_hz", 31.0, 0.0, "XY"), "");
    EXPECT_EQ(diagnostic_action("something_else", 5.0, 0.0, "XY"), "");
}

}  // namespace
