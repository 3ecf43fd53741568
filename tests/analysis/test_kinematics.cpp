// SPDX-License-Identifier: MIT
// Kinematics against the seed's Table 1 (RRTTT) and Table 2 (TTTRR), and round trips.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "ballbar/analysis/kinematics.hpp"

namespace ba = ballbar::analysis;
using ba::Vec3;

namespace {

constexpr double kTableTol_mm = 1e-3;  // the seed prints three decimals

nlohmann::json load_table1() {
    std::ifstream in(std::string(BALLBAR_TEST_DATA_DIR) + "/table1.json");
    EXPECT_TRUE(in.good()) << "tests/data/table1.json missing";
    return nlohmann::json::parse(in);
}

// Table 1: spindle pivot (−50, −15, 500), tool ball [0, 0, −250] from the pivot.
ba::MachineGeometry table1_machine() {
    ba::MachineGeometry g;
    g.type = ba::MachineType::RRTTT;
    g.tool_ball_mm = {0, 0, -250};
    return g;
}

// Table 2 (DL-5X): both rotary axes through the origin, C frame 100 mm below the A axis.
ba::MachineGeometry table2_machine() {
    ba::MachineGeometry g;
    g.type = ba::MachineType::TTTRR;
    g.c_offset_mm = {0, 0, -100};
    return g;
}

}  // namespace

TEST(Kinematics, Table1NominalAfterRotationAllFifteenValues) {
    const auto table = load_table1();
    ASSERT_EQ(table.size(), 5u);
    const auto g = table1_machine();
    // The printed table at three decimals, every one of the 15 after-rotation coordinates.
    const double printed[5][3] = {{-50.000, 110.000, 283.494},
                                  {-210.697, -15.000, 308.489},
                                  {-266.506, 73.388, 411.612},
                                  {-241.511, 124.168, 419.652},
                                  {-266.506, 47.500, 391.747}};
    for (std::size_t i = 0; i < 5; ++i) {
        const auto& c = table[i];
        ba::Pose pose{c["x1"], c["y1"], c["z1"], c["alpha_rad"], c["beta_rad"], 0};
        const Vec3 b = ba::nominal_tool_ball(g, pose);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(b[k], printed[i][k], kTableTol_mm) << "case " << i + 1 << " axis " << k;
        EXPECT_NEAR(b.x(), c["x2"].get<double>(), 1e-9);
        EXPECT_NEAR(b.y(), c["y2"].get<double>(), 1e-9);
        EXPECT_NEAR(b.z(), c["z2"].get<double>(), 1e-9);
    }
}

TEST(Kinematics, Table1PositionErrorsAreTheZeroOffsetsOfTheHead) {
    // The seed's Δα, Δβ are angle errors of the head axes: our A_zero and B_zero.
    const auto table = load_table1();
    const auto g = table1_machine();
    for (const auto& c : table) {
        ba::ErrorParams e;
        e[ba::Param::A_zero] = c["dalpha_rad"];
        e[ba::Param::B_zero] = c["dbeta_rad"];
        ba::Pose pose{c["x1"], c["y1"], c["z1"], c["alpha_rad"], c["beta_rad"], 0};
        const Vec3 err = ba::total_position_error(g, e, pose, Vec3::Zero());
        EXPECT_NEAR(err.x(), c["dxV2"].get<double>(), 1e-12);
        EXPECT_NEAR(err.y(), c["dyV2"].get<double>(), 1e-12);
        EXPECT_NEAR(err.z(), c["dzV2"].get<double>(), 1e-12);
    }
}

TEST(Kinematics, Table2AfterRotationPointsWithCase4Corrected) {
    const auto g = table2_machine();
    const Vec3 socket{-49.275, -14.312, -77.777};
    // Before rotation the reference point is at p0 = (−49.275, −14.312, −177.777).
    const Vec3 before = ba::nominal_table_ball(g, ba::Pose{}, socket);
    EXPECT_NEAR(before.x(), -49.275, kTableTol_mm);
    EXPECT_NEAR(before.y(), -14.312, kTableTol_mm);
    EXPECT_NEAR(before.z(), -177.777, kTableTol_mm);
    struct Case {
        double a_deg, c_deg, x, y, z;
    };
    const Case cases[] = {{0, 30, -35.517, -37.032, -177.777},
                          {15, 0, -49.275, 32.188, -175.424},
                          {10, 30, -35.517, -5.599, -181.507},
                          {10, 45, -24.723, -13.409, -182.884}};  // x printed as 24.723: a misprint
    for (const auto& c : cases) {
        ba::Pose pose;
        pose.A_rad = ba::deg_to_rad(c.a_deg);
        pose.C_rad = ba::deg_to_rad(c.c_deg);
        const Vec3 s = ba::nominal_table_ball(g, pose, socket);
        EXPECT_NEAR(s.x(), c.x, kTableTol_mm) << "A=" << c.a_deg << " C=" << c.c_deg;
        EXPECT_NEAR(s.y(), c.y, kTableTol_mm) << "A=" << c.a_deg << " C=" << c.c_deg;
        EXPECT_NEAR(s.z(), c.z, kTableTol_mm) << "A=" << c.a_deg << " C=" << c.c_deg;
    }
}

TEST(Kinematics, ZeroErrorsGiveTheNominalMachine) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> lin(-300, 300), ang(-1.5, 1.5);
    for (auto type : {ba::MachineType::RRTTT, ba::MachineType::TTTRR, ba::MachineType::RTTTR}) {
        ba::MachineGeometry g;
        g.type = type;
        g.tool_ball_mm = {1.5, -2.0, -180};
        g.a_pivot_mm = {10, 20, -150};
        g.c_offset_mm = {0, 0, -80};
        for (int i = 0; i < 200; ++i) {
            ba::Pose pose{lin(rng), lin(rng), lin(rng), ang(rng), ang(rng), ang(rng)};
            const Vec3 socket{lin(rng) / 3, lin(rng) / 3, lin(rng) / 10};
            const auto nom = ba::nominal_balls(g, pose, socket);
            const auto act = ba::actual_balls(g, ba::ErrorParams{}, pose, socket);
            EXPECT_LT((nom.tool - act.tool).norm(), 1e-10);
            EXPECT_LT((nom.table - act.table).norm(), 1e-10);
            EXPECT_NEAR(ba::predicted_reading(g, ba::ErrorParams{}, pose, socket), ba::nominal_length(g, pose, socket),
                        1e-10);
        }
    }
}

TEST(Kinematics, CommandForToolBallRoundTrips) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> lin(-300, 300), ang(-3, 3);
    for (auto type : {ba::MachineType::RRTTT, ba::MachineType::TTTRR, ba::MachineType::RTTTR}) {
        ba::MachineGeometry g;
        g.type = type;
        g.tool_ball_mm = {0.5, 1.0, -200};
        for (int i = 0; i < 500; ++i) {
            ba::Pose pose{lin(rng), lin(rng), lin(rng), ang(rng), ang(rng), ang(rng)};
            const Vec3 b = ba::nominal_tool_ball(g, pose);
            const ba::Pose back = ba::command_for_tool_ball(g, pose, b);
            EXPECT_NEAR(back.X_mm, pose.X_mm, 1e-9);
            EXPECT_NEAR(back.Y_mm, pose.Y_mm, 1e-9);
            EXPECT_NEAR(back.Z_mm, pose.Z_mm, 1e-9);
        }
    }
}

TEST(Kinematics, LocationErrorsVanishAtZeroAngles) {
    // By our convention an axis's location errors move nothing while the axis is at zero: the set-up
    // at the start angles is the datum (docs/kinematics.md).
    ba::MachineGeometry g;
    g.type = ba::MachineType::TTTRR;
    g.c_offset_mm = {0, 0, -100};
    ba::ErrorParams e;
    for (auto p : ba::rotary_params_for(g.type))
        if (p != ba::Param::A_zero && p != ba::Param::C_zero) e[p] = 0.01;
    const Vec3 socket{30, 40, -50};
    EXPECT_LT(ba::total_position_error(g, e, ba::Pose{}, socket).norm(), 1e-12);
    ba::Pose rotated;
    rotated.A_rad = 0.3;
    EXPECT_GT(ba::total_position_error(g, e, rotated, socket).norm(), 1e-3);
}
