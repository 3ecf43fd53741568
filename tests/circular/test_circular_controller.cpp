// SPDX-License-Identifier: MIT
// `circle analyze --controller`: the measured backlash (and scale) in each controller's own terms, on
// traces from the independent generator. The numbers and names are the controllers' (checked against
// their sources, docs/circular.md): LinuxCNC [JOINT_n] BACKLASH; Marlin M425 with F1 (its default
// correction fraction is 0); SmoothieV2 M425 … P1 and config.ini; grblHAL $160-$162 (mm) and $100-$102.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "../app/cli_harness.hpp"
#include "trace_generator.hpp"

namespace {

using ballbar::test::run;
using ballbar::test::TempDir;
using namespace ballbar::testgen;

/// A ZX full circle (p = Z, q = X) with Z backlash 12 µm and X backlash 4 µm.
std::string zx_trace(const TempDir& dir) {
    std::mt19937_64 rng(5);
    GenSpec s;
    s.plane = 2;
    s.radius_mm = 100.0, s.feed_mm_min = 1500.0, s.sample_hz = 500.0, s.noise_um = 0.15;
    s.runs = {{true, 0, 45, 360}, {false, 90, 45, 360}};
    GenEffects fx;
    fx.backlash_um = {12.0, 4.0};
    fx.scale_ppm = {30.0, -10.0};
    const std::string path = dir.file("zx.csv");
    std::ofstream(path) << to_file(s, generate(s, fx, rng));
    return path;
}

nlohmann::json controller(const TempDir& dir, const std::string& trace, const std::string& name) {
    const auto r = run(dir, "circle analyze '" + trace + "' --json --controller " + name);
    EXPECT_EQ(r.code, 0) << r.err;
    return nlohmann::json::parse(r.out)["controller"];
}

TEST(CircularController, EachControllerGetsItsOwnSettingForTheRightAxis) {
    TempDir dir;
    const std::string trace = zx_trace(dir);
    const auto grbl = controller(dir, trace, "grblhal");
    EXPECT_EQ(grbl["axes"]["Z"]["setting"], "$162=0.012");
    EXPECT_EQ(grbl["axes"]["X"]["setting"], "$160=0.004");
    EXPECT_EQ(grbl["axes"]["Z"]["scale_setting"].get<std::string>().rfind("$102 = current × 0.9999", 0), 0u)
        << grbl["axes"]["Z"]["scale_setting"];
    const auto lcnc = controller(dir, trace, "linuxcnc");
    EXPECT_EQ(lcnc["axes"]["Z"]["setting"].get<std::string>().rfind("[JOINT_2] BACKLASH = 0.01", 0), 0u);
    EXPECT_EQ(lcnc["axes"]["X"]["setting"].get<std::string>().rfind("[JOINT_0] BACKLASH = 0.00", 0), 0u);
    const auto marlin = controller(dir, trace, "marlin");
    const std::string mz = marlin["axes"]["Z"]["setting"];
    EXPECT_EQ(mz.rfind("M425 Z0.01", 0), 0u) << mz;
    EXPECT_NE(mz.find(" F1"), std::string::npos) << mz;  // Marlin's default correction fraction is 0
    const auto smoothie = controller(dir, trace, "smoothieware");
    const std::string sz = smoothie["axes"]["Z"]["setting"];
    EXPECT_EQ(sz.rfind("M425 Z0.01", 0), 0u) << sz;
    EXPECT_NE(sz.find(" P1"), std::string::npos) << sz;
    EXPECT_EQ(smoothie["axes"]["Z"]["config"].get<std::string>().rfind("[actuator] gamma.backlash_mm = 0.01", 0), 0u);
    EXPECT_EQ(smoothie["axes"]["X"]["config"].get<std::string>().rfind("[actuator] alpha.backlash_mm", 0), 0u);
    EXPECT_EQ(smoothie["config"], "[motion control] backlash_enable = true");
    // The values: the lost motion, in mm.
    EXPECT_NEAR(grbl["axes"]["Z"]["backlash_mm"].get<double>(), 0.012, 0.0015);
    EXPECT_NEAR(grbl["axes"]["X"]["backlash_mm"].get<double>(), 0.004, 0.0008);
}

TEST(CircularController, TextOutputNamesTheBuildOptionsAndHowToKeepThem) {
    TempDir dir;
    const std::string trace = zx_trace(dir);
    const auto grbl = run(dir, "circle analyze '" + trace + "' --controller grblhal");
    EXPECT_NE(grbl.out.find("ENABLE_BACKLASH_COMPENSATION"), std::string::npos) << grbl.out;
    const auto marlin = run(dir, "circle analyze '" + trace + "' --controller marlin");
    EXPECT_NE(marlin.out.find("M500"), std::string::npos);
    EXPECT_NE(marlin.out.find("BACKLASH_GCODE"), std::string::npos);
    const auto smoothie = run(dir, "circle analyze '" + trace + "' --controller smoothieware");
    EXPECT_NE(smoothie.out.find("backlash_enable = true"), std::string::npos) << smoothie.out;
    EXPECT_EQ(smoothie.out.find("M500"), std::string::npos);
}

}  // namespace
