// SPDX-License-Identifier: MIT
// The parts of the LinuxCNC loop (workflow/linuxcnc_loop.hpp) that need no LinuxCNC: the circular test's
// place on the tilted table, the emulated machine's error sets, the size a hidden effect is given. The
// loop itself runs on LinuxCNC in tests/linuxcnc/test_linuxcnc_loop.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "ballbar/acquisition/compute.hpp"
#include "ballbar/analysis/effects.hpp"
#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/workflow/linuxcnc_loop.hpp"

namespace ballbar::workflow {
namespace {

namespace ba = ballbar::analysis;
namespace circ = ballbar::analysis::circular;

// The bar the nominal machine commands from the circle's points to the socket on the table tilted to
// A = 30°: the radius on the circle, radius + feed-in at the stand — by the nominal kinematics of the
// readings format, not by the function that placed the circle.
TEST(LinuxcncLoopParts, TheCircleLiesAboutTheSocketOnTheTiltedTableInTheMachinesXyPlane) {
    const acquisition::MachineFile m = loop_machine();
    const acquisition::PlanSpec plan = loop_plan();
    const circ::TestSpec t = loop_circle(m, plan, 30.0);
    EXPECT_TRUE(t.validate().empty()) << t.validate();
    EXPECT_EQ(t.plane, circ::Plane::XY);
    EXPECT_DOUBLE_EQ(t.radius_mm, plan.bar_length_mm);
    ASSERT_EQ(t.runs.size(), 2u);
    EXPECT_NE(t.runs[0].direction, t.runs[1].direction);  // G(b) needs both
    const ba::Vec3 socket = plan.tests.front().socket_mm;
    for (const double deg : {0.0, 37.0, 90.0, 200.0, 315.0}) {
        for (const double r : {t.radius_mm, t.radius_mm + t.feed_in_mm}) {
            ba::Pose p;
            p.X_mm = t.centre_mm[0] + r * std::cos(deg * M_PI / 180.0);
            p.Y_mm = t.centre_mm[1] + r * std::sin(deg * M_PI / 180.0);
            p.Z_mm = t.centre_mm[2];
            p.A_rad = 30.0 * M_PI / 180.0;
            EXPECT_NEAR(ba::nominal_length(m.geometry, p, socket), r, 1e-9) << deg << "° r " << r;
        }
    }
    // Tilted, the socket is not where it stands at A = 0: the circle moved with it.
    const circ::TestSpec flat = loop_circle(m, plan, 0.0);
    EXPECT_GT(std::hypot(flat.centre_mm[1] - t.centre_mm[1], flat.centre_mm[2] - t.centre_mm[2]), 10.0);
}

TEST(LinuxcncLoopParts, ErrorSetZeroIsTheDemoMachinesRotaryErrorsAndOthersAreRandomOfTheirSize) {
    const ba::ErrorParams demo = acquisition::demo_errors(ba::MachineType::TTTRR);
    const ba::ErrorParams zero = loop_errors(0);
    for (std::size_t i = 0; i < ba::kParamCount; ++i) {
        const auto p = static_cast<ba::Param>(i);
        EXPECT_EQ(zero[p], p == ba::Param::tool_length ? 0.0 : demo[p]) << ba::param_info(p).name;
    }
    const ba::ErrorParams a = loop_errors(3), b = loop_errors(3), c = loop_errors(4);
    int differ = 0;
    for (const ba::Param p : ba::rotary_params_for(ba::MachineType::TTTRR)) {
        EXPECT_EQ(a[p], b[p]);  // deterministic in the set
        differ += a[p] != c[p];
        const bool angle = ba::param_info(p).unit == ba::ParamUnit::rad;
        EXPECT_LE(std::abs(a[p]), 1.5 * (angle ? 30e-6 : 0.02)) << ba::param_info(p).name;
    }
    EXPECT_GT(differ, 5);
}

TEST(LinuxcncLoopParts, AHiddenEffectIsOneOfTheMachinesGeometryVisibleAndOfARealMachinesOrder) {
    int hideable = 0;
    for (const ba::Effect& e : ba::effect_library()) {
        const std::string why = hidden_effect_refusal(e.id);
        const auto base = ba::rotary_params_for(ba::MachineType::TTTRR);
        const bool in_model = std::find(base.begin(), base.end(), e.param) != base.end();
        const bool geometric =
            e.unit() == ba::ParamUnit::mm || e.unit() == ba::ParamUnit::rad || e.unit() == ba::ParamUnit::mm_per_mm;
        const bool of_bar = e.param == ba::Param::bar_length || e.param == ba::Param::bar_kappa;
        EXPECT_EQ(why.empty(), !in_model && geometric && !of_bar) << e.id << ": " << why;
        if (!why.empty()) continue;
        ++hideable;
        // At the loop's lever (about 100 mm), a few µm: far above the bar's 0.1 µm noise, below the
        // rotary axes' tens of µm.
        const double v = hidden_effect_size(e.param);
        const double um = (e.unit() == ba::ParamUnit::mm ? v : v * 100.0) * 1e3;
        EXPECT_GE(um, 2.0) << e.id;
        EXPECT_LE(um, 20.0) << e.id;
    }
    EXPECT_GE(hideable, 7);  // scale X/Y/Z, squareness XY/YZ/ZX, tool length
    EXPECT_NE(hidden_effect_refusal("no_such_effect").find("no such effect"), std::string::npos);
    EXPECT_NE(hidden_effect_refusal("location_Y0A").find("in the loop's model"), std::string::npos);
}

}  // namespace
}  // namespace ballbar::workflow
