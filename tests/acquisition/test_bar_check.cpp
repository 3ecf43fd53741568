// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>

#include "ballbar/acquisition/bar_check.hpp"

using ballbar::acquisition::bar_length_mismatch;

TEST(BarCheck, AgreeingLengthsPass) {
    EXPECT_EQ(bar_length_mismatch(100, 100, 0.5), "");
    EXPECT_EQ(bar_length_mismatch(100, 100.4999, 0.5), "");
    EXPECT_EQ(bar_length_mismatch(150, 149.6, 0.5), "");
}

TEST(BarCheck, MismatchNamesBothLengthsAndTheFix) {
    const std::string m = bar_length_mismatch(100, 150, 0.5, "tests/data/plan.json");
    EXPECT_NE(m.find("100 mm bar"), std::string::npos) << m;
    EXPECT_NE(m.find("calibrated at 150 mm"), std::string::npos) << m;
    EXPECT_NE(m.find("mount and calibrate the 100 mm bar"), std::string::npos) << m;
    EXPECT_NE(m.find("\"bar_length_mm\": 150 in the plan file tests/data/plan.json"), std::string::npos) << m;
    const std::string d = bar_length_mismatch(100, 99.4, 0.5);
    EXPECT_NE(d.find("\"bar_length_mm\": 99.4 in a plan file (--plan FILE)"), std::string::npos) << d;
}

TEST(BarCheck, NonsenseLengthIsAMismatch) {
    EXPECT_NE(bar_length_mismatch(100, std::nan(""), 0.5), "");
    EXPECT_NE(bar_length_mismatch(100, 0, 0.5), "");
}
