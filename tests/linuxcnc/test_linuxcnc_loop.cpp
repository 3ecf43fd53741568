// SPDX-License-Identifier: MIT
// The whole loop on LinuxCNC (`ballbar demo --controller linuxcnc`, docs/linuxcnc.md "The loop"), run as
// a user runs it: LinuxCNC's simulator runs the SSM programs, its joints drive the emulated machine, the
// session is measured through the pty, identified, the model loaded into ballbarkins, measured again.
// ctest label `linuxcnc`; skipped, saying why, where LinuxCNC or the module is absent or not root.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <nlohmann/json.hpp>

#include "../app/cli_harness.hpp"
#include "linuxcnc_sim.hpp"

namespace {

using nlohmann::json;
namespace lc = ballbar::test::lcnc;

TEST(LinuxcncLoop, MeasureIdentifyCompensateInTheServoLoopMeasureAgainTenTimesSmallerOnEveryAxis) {
    if (const std::string why = lc::unavailable(); !why.empty()) GTEST_SKIP() << "LinuxCNC tests skipped: " << why;
#ifdef BALLBAR_KINS_MODULE
    ballbar::test::TempDir dir;
    ::chmod(dir.path.c_str(), 0755);  // LinuxCNC's real-time process (uid 65534) reads the work directory
    const auto r =
        ballbar::test::run(dir, "demo --controller linuxcnc --json --module '" + std::string(BALLBAR_KINS_MODULE) +
                                    "' --work-dir '" + dir.file("loop") + "'");
    ASSERT_EQ(r.code, 0) << r.err << "\n" << r.out;
    const json j = json::parse(r.out);
    // LinuxCNC drove the machine: a servo cycle's joints per millisecond of both sessions.
    EXPECT_GT(j.at("servo_cycles").get<double>(), 60000) << r.out;
    // Where LinuxCNC put the machine with the nominal kinematics, the bar measured what the emulated
    // machine's errors give at the planned poses: the joints reached it as commanded.
    ASSERT_EQ(j.at("locations").size(), 8u);
    for (const auto& l : j.at("locations")) {
        for (std::size_t k = 0; k < 3; ++k)
            EXPECT_NEAR(l.at("before_e_mm")[k].get<double>(), l.at("true_before_e_mm")[k].get<double>(), 1e-3)
                << l.dump();
    }
    for (const auto& a : j.at("axes")) {
        EXPECT_GT(a.at("before_um").get<double>(), 5.0) << a.dump();  // tens of µm before
        EXPECT_GE(a.at("gain").get<double>(), 10.0) << a.dump();
        RecordProperty("gain_" + a.at("axis").get<std::string>(), std::to_string(a.at("gain").get<double>()));
    }
    EXPECT_TRUE(j.at("goal_met").get<bool>());
    // Both sessions stored complete; the second carries the before/after its report shows.
    for (const char* key : {"before_session", "after_session"}) {
        const auto s = ballbar::test::run(dir, "sessions show " + std::to_string(j.at(key).get<int>()) + " --json");
        ASSERT_EQ(s.code, 0) << s.err;
        EXPECT_EQ(json::parse(s.out).at("session").at("state"), "completed") << s.out;
    }
    const auto after =
        ballbar::test::run(dir, "sessions show " + std::to_string(j.at("after_session").get<int>()) + " --json");
    int compensation = 0;
    const json shown = json::parse(after.out);
    for (const auto& res : shown.at("results")) compensation += res.at("kind") == "compensation";
    EXPECT_EQ(compensation, 1) << after.out;
    EXPECT_TRUE(std::filesystem::exists(j.at("model").get<std::string>()));
#endif
}

}  // namespace
