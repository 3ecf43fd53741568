// SPDX-License-Identifier: MIT
// The whole loop on LinuxCNC (`ballbar demo --controller linuxcnc`, docs/linuxcnc.md "The loop"), run as
// a user runs it: LinuxCNC's simulator runs the SSM programs, its joints drive the emulated machine, the
// session is measured through the pty, identified, the model loaded into ballbarkins, measured again.
// ctest label `linuxcnc`; skipped, saying why, where LinuxCNC or the module is absent or not root.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/shm.h>
#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../app/cli_harness.hpp"
#include "linuxcnc_sim.hpp"

namespace {

using nlohmann::json;
namespace lc = ballbar::test::lcnc;

// The emulated machine has, besides the rotary axes' location errors the model holds, a squareness of X
// and Y (C0Y, 40 µrad) it does not: the second measurement shows what remains, `discover` names it, the
// extended model goes into ballbarkins and the third measurement closes the gap. After each SSM the
// circular test in XY with the table tilted (A = 30°) gives G: the squareness's ellipse, untouched by the
// rotary model, gone with the extended one.
TEST(LinuxcncLoop, MeasureIdentifyCompensateDiscoverTheHiddenSquarenessMeasureAgainTenTimesSmaller) {
    if (const std::string why = lc::unavailable(); !why.empty()) GTEST_SKIP() << "LinuxCNC tests skipped: " << why;
    lc::free_orphaned_shm();
#ifdef BALLBAR_KINS_MODULE
    ballbar::test::TempDir dir;
    ::chmod(dir.path.c_str(), 0755);  // LinuxCNC's real-time process (uid 65534) reads the work directory
    const auto r = ballbar::test::run(dir, "demo --controller linuxcnc --json --hidden squareness_XY --module '" +
                                               std::string(BALLBAR_KINS_MODULE) + "' --work-dir '" + dir.file("loop") +
                                               "' --report '" + dir.file("loop.pdf") + "'");
    ASSERT_EQ(r.code, 0) << r.err << "\n" << r.out;
    const json j = json::parse(r.out);
    // LinuxCNC drove the machine: a servo cycle's joints per millisecond of the three runs.
    EXPECT_GT(j.at("servo_cycles").get<double>(), 150000) << r.out;
    // Where LinuxCNC put the machine with the nominal kinematics, the bar measured what the emulated
    // machine's errors give at the planned poses: the joints reached it as commanded. In Y, the SSM's e
    // holds one more term the pointwise truth has not: e is a translation fitted to the bar's three
    // directions, and the squareness is a field over them (C0Y·L·u_x·u_y, 1.6 µm here) — the same at
    // every location, as the same directions are measured at each.
    ASSERT_EQ(j.at("locations").size(), 8u);
    const double bias_y = j.at("locations")[0].at("before_e_mm")[1].get<double>() -
                          j.at("locations")[0].at("true_before_e_mm")[1].get<double>();
    EXPECT_LT(std::abs(bias_y), 2.5e-3);
    for (const auto& l : j.at("locations")) {
        for (std::size_t k = 0; k < 3; ++k)
            EXPECT_NEAR(l.at("before_e_mm")[k].get<double>() - (k == 1 ? bias_y : 0.0),
                        l.at("true_before_e_mm")[k].get<double>(), k == 1 ? 2e-4 : 1e-3)
                << l.dump();
    }
    // The discovery named the hidden effect, and nothing else.
    const json& d = j.at("discovery");
    ASSERT_EQ(d.at("discovered").size(), 1u) << d.dump();
    EXPECT_EQ(d.at("discovered")[0].get<std::string>().rfind("squareness_XY (C0Y) = ", 0), 0u) << d.dump();
    ASSERT_TRUE(d.at("third_session").is_number()) << d.dump();
    for (const auto& a : j.at("axes")) {
        SCOPED_TRACE(a.dump());
        EXPECT_GT(a.at("before_um").get<double>(), 5.0);  // tens of µm before
        // The rotary model alone leaves the squareness; the extended model takes it out too.
        EXPECT_GT(a.at("after_um").get<double>(), 3.0 * a.at("third_um").get<double>());
        EXPECT_GE(a.at("third_gain").get<double>(), 10.0);
        RecordProperty("gain_" + a.at("axis").get<std::string>(), std::to_string(a.at("gain").get<double>()));
        RecordProperty("third_gain_" + a.at("axis").get<std::string>(),
                       std::to_string(a.at("third_gain").get<double>()));
    }
    EXPECT_TRUE(j.at("goal_met").get<bool>());
    // G: the squareness's ellipse (40 µrad over R 100 mm: about 4 µm), the same after the rotary model,
    // a fraction of it with the extended one.
    ASSERT_EQ(j.at("circles").size(), 3u) << j.at("circles").dump();
    const double g_before = j.at("circles")[0].at("g_um"), g_after = j.at("circles")[1].at("g_um"),
                 g_third = j.at("circles")[2].at("g_um");
    EXPECT_GT(g_before, 3.0);
    EXPECT_NEAR(g_after, g_before, 1.0);
    EXPECT_LT(g_third, g_before / 3.0);
    // Every session stored complete; the second and third carry the before/after their reports show.
    std::vector<int> sessions{j.at("before_session").get<int>(), j.at("after_session").get<int>(),
                              d.at("third_session").get<int>()};
    for (const auto& c : j.at("circles")) sessions.push_back(c.at("session").get<int>());
    for (const int id : sessions) {
        const auto s = ballbar::test::run(dir, "sessions show " + std::to_string(id) + " --json");
        ASSERT_EQ(s.code, 0) << s.err;
        const json shown = json::parse(s.out);
        EXPECT_EQ(shown.at("session").at("state"), "completed") << s.out;
        int compensation = 0;
        for (const auto& res : shown.at("results")) compensation += res.at("kind") == "compensation";
        EXPECT_EQ(compensation, id == sessions[1] || id == sessions[2] ? 1 : 0) << s.out;
    }
    EXPECT_TRUE(std::filesystem::exists(j.at("model").get<std::string>()));
    EXPECT_TRUE(std::filesystem::exists(d.at("extended_model").get<std::string>()));
    EXPECT_EQ(ballbar::test::slurp(dir.file("loop.pdf")).rfind("%PDF", 0), 0u);
#endif
}

// (Used by the tests below where the module was built: clang's unused-function check sees the rest.)
[[maybe_unused]] int linuxcnc_processes() {
    return std::system(
               "pgrep -x rtapi_app > /dev/null || pgrep -x milltask > /dev/null || "
               "pgrep -x linuxcncsvr > /dev/null") == 0;
}

/// LinuxCNC's shared-memory segments (HAL's, motion's) still in the kernel's table.
[[maybe_unused]] int linuxcnc_segments() {
    std::ifstream shm("/proc/sysvipc/shm");
    std::string line;
    std::getline(shm, line);
    int n = 0;
    while (std::getline(shm, line)) {
        long key = 0;
        if (std::sscanf(line.c_str(), "%ld", &key) == 1 && (key == 0x48414c32 || key == 100 || key == 0x48534130)) ++n;
    }
    return n;
}

// An operator's Ctrl-\, a kill -9, a crash: the demo dies with LinuxCNC running a program. LinuxCNC
// must go down with it (its display reads the end of its input, its script shuts it down) and free its
// shared memory: a LinuxCNC left running, or its leftovers, stop the next run.
TEST(LinuxcncLoop, AKilledDemoTakesLinuxcncDownAndTheNextRunIsNotBlocked) {
    if (const std::string why = lc::unavailable(); !why.empty()) GTEST_SKIP() << "LinuxCNC tests skipped: " << why;
    lc::free_orphaned_shm();
#ifdef BALLBAR_KINS_MODULE
    ballbar::test::TempDir dir;
    ::chmod(dir.path.c_str(), 0755);
    const std::string cmd = std::string("'") + BALLBAR_EXE + "' --db '" + dir.file("test.db") +
                            "' demo --controller linuxcnc --json --module '" + BALLBAR_KINS_MODULE + "' --work-dir '" +
                            dir.file("loop") + "' </dev/null >'" + dir.file("out") + "' 2>'" + dir.file("err") +
                            "' & echo $! >'" + dir.file("pid") + "'";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    const int pid = std::stoi(ballbar::test::slurp(dir.file("pid")));
    // Until LinuxCNC runs the first measurement's program (its display said "started").
    bool started = false;
    for (int i = 0; i < 600 && !started; ++i) {
        started = ballbar::test::slurp(dir.file("loop/linuxcnc-before.log")).find("ballbar-display: started") !=
                  std::string::npos;
        if (!started) ::usleep(100'000);
    }
    ASSERT_TRUE(started) << ballbar::test::slurp(dir.file("err"));
    ::usleep(2'000'000);
    ASSERT_EQ(::kill(pid, SIGKILL), 0);
    bool down = false;
    for (int i = 0; i < 300 && !down; ++i) {
        down = !linuxcnc_processes() && linuxcnc_segments() == 0;
        if (!down) ::usleep(100'000);
    }
    EXPECT_TRUE(down) << "LinuxCNC still runs, or its shared memory is left, 30 s after the demo was killed:\n"
                      << ballbar::test::slurp(dir.file("loop/linuxcnc-before.log"));
    // What was stored survives: the session the kill cut short is listed.
    const auto listed = ballbar::test::run(dir, "sessions --json");
    EXPECT_EQ(listed.code, 0) << listed.err;
    EXPECT_EQ(json::parse(listed.out).size(), 1u) << listed.out;
#endif
}

// A LinuxCNC that did not shut down left its shared memory: the demo says so, naming the keys and how
// to free them, starts nothing and frees nothing (the memory is not its own).
TEST(LinuxcncLoop, LeftoverSharedMemoryIsNamedAndLeftAlone) {
    if (const std::string why = lc::unavailable(); !why.empty()) GTEST_SKIP() << "LinuxCNC tests skipped: " << why;
    lc::free_orphaned_shm();
#ifdef BALLBAR_KINS_MODULE
    const int id = ::shmget(0x48534137, 4096, IPC_CREAT | IPC_EXCL | 0600);  // the eighth sampler's key
    ASSERT_GE(id, 0) << std::strerror(errno);
    ballbar::test::TempDir dir;
    ::chmod(dir.path.c_str(), 0755);
    const auto r = ballbar::test::run(dir, "demo --controller linuxcnc --module '" + std::string(BALLBAR_KINS_MODULE) +
                                               "' --work-dir '" + dir.file("loop") + "'");
    shmid_ds st{};
    const bool still_there = ::shmctl(id, IPC_STAT, &st) == 0;
    ::shmctl(id, IPC_RMID, nullptr);
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.err.find("0x48534137"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("halrun -U"), std::string::npos) << r.err;
    EXPECT_TRUE(still_there);
    EXPECT_FALSE(std::filesystem::exists(dir.file("loop")));
    EXPECT_EQ(linuxcnc_processes(), 0);
#endif
}

}  // namespace
