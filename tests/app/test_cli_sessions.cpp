// SPDX-License-Identifier: MIT
// The unfinished session as a user meets it, through the real `ballbar`: a measure killed with SIGKILL
// is listed `interrupted` (not `running`) by `sessions`, which writes nothing; a failed one shows why and
// resumes (`measure --resume` says why first) to completion; the instrument's identity is stored and
// shown; a bar whose length does not match the plan stops the session before any question, naming the fix.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "cli_harness.hpp"

namespace {

namespace fs = std::filesystem;
using ballbar::test::CliRun;
using ballbar::test::run;
using ballbar::test::slurp;
using ballbar::test::TempDir;
const fs::path kDataSessions = fs::path(BALLBAR_TEST_DATA_DIR) / "machines";

/// A loopback TCP port that takes connections (the kernel's backlog) and never answers: an instrument
/// that does not speak.
struct SilentPort {
    int fd = -1;
    int port = 0;
    SilentPort() {
        fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
        ::listen(fd, 8);
        socklen_t len = sizeof a;
        ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
        port = ntohs(a.sin_port);
    }
    ~SilentPort() { ::close(fd); }
};

/// The emulator with the plan's NC program from power-on, and the bar's length.
fs::path emulator_config_sessions(const TempDir& dir, double bar_mm) {
    const std::string prog = dir.file("plan.nc");
    const CliRun dry = run(dir, "measure --dry-run --machine " + (kDataSessions / "tttrr.json").string() + " --plan " +
                                    (kDataSessions / "tttrr-quick.plan.json").string() + " --program " + prog);
    EXPECT_EQ(dry.code, 0) << dry.out << dry.err;
    std::string cfg = slurp(kDataSessions / "tttrr-emulator.json");
    cfg.replace(cfg.find("PROGRAM"), 7, prog);
    const std::string len = "\"calibrated_length_mm\": 100";
    cfg.replace(cfg.find(len), len.size(), "\"calibrated_length_mm\": " + std::to_string(bar_mm));
    const fs::path path = dir.path / ("emulator-" + std::to_string(static_cast<int>(bar_mm)) + ".json");
    std::ofstream(path) << cfg;
    return path;
}

std::string measure_args(const std::string& device, const TempDir& dir) {
    return "measure --non-interactive --device " + device + " --machine " + (kDataSessions / "tttrr.json").string() +
           " --plan " + (kDataSessions / "tttrr-quick.plan.json").string() + " --program " + dir.file("m.nc");
}

nlohmann::json show_json(const TempDir& dir, const std::string& id) {
    const CliRun r = run(dir, "sessions show " + id + " --json");
    EXPECT_EQ(r.code, 0) << r.err;
    return nlohmann::json::parse(r.out, nullptr, false);
}

}  // namespace

TEST(CliSessions, KilledIsInterruptedAFailedOpenKeepsItSoAndItResumes) {
    TempDir dir;
    SilentPort silent;
    const std::string mute = "tcp:127.0.0.1:" + std::to_string(silent.port);
    // 1. kill -9 while it waits for the instrument's first answer.
    const pid_t pid = ::fork();
    if (pid == 0) {
        const std::string cmd = std::string("exec '") + BALLBAR_EXE + "' --db '" + dir.file("test.db") + "' " +
                                measure_args(mute, dir) + " >/dev/null 2>&1";
        ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
    }
    bool seen = false;
    for (int i = 0; i < 100 && !seen; ++i) {  // until the session exists (it waits 1.5 s for an answer)
        std::this_thread::sleep_for(std::chrono::milliseconds(30));
        const auto list = nlohmann::json::parse(run(dir, "sessions --json").out, nullptr, false);
        seen = list.is_array() && !list.empty();
    }
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(seen);
    ASSERT_TRUE(WIFSIGNALED(status));
    const CliRun listed = run(dir, "sessions");
    EXPECT_NE(listed.out.find("interrupted"), std::string::npos) << listed.out;
    EXPECT_EQ(listed.out.find("running"), std::string::npos) << "a killed session is not running:\n" << listed.out;
    auto j = show_json(dir, "1");
    EXPECT_EQ(j["session"]["state"], "interrupted");
    EXPECT_EQ(j["session"]["resumable"], true);
    EXPECT_NE(j["session"]["state_reason"].get<std::string>().find("writer is gone"), std::string::npos);

    // 2. resumed on the same silent instrument, it cannot open it: the reason is shown, and the session
    //    stays interrupted and resumable (a failed open never makes it failed: issue 24).
    CliRun r = run(dir, "measure --non-interactive --resume 1 --device " + mute + " --program " + dir.file("r.nc"));
    EXPECT_EQ(r.code, 3) << r.out << r.err;
    EXPECT_NE(r.out.find("Session 1 is interrupted: "), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("interrupted: interrupted"), std::string::npos) << "said once: " << r.out;
    const CliRun shown = run(dir, "sessions show 1");
    EXPECT_NE(shown.out.find("state       interrupted  (cannot open the instrument"), std::string::npos) << shown.out;
    // The line to copy names the database the command was given.
    EXPECT_NE(shown.out.find("resume      ballbar --db " + dir.file("test.db") + " measure --resume 1 --device URI"),
              std::string::npos)
        << shown.out;

    // 3. it resumes on a working instrument and completes; the reason comes first.
    const fs::path cfg = emulator_config_sessions(dir, 100);
    r = run(dir, "measure --non-interactive --resume 1 --device emulator:" + cfg.string() + " --program " +
                     dir.file("r2.nc"));
    EXPECT_EQ(r.code, 0) << r.out << r.err;
    EXPECT_EQ(r.out.rfind("Session 1 is interrupted: cannot open the instrument", 0), 0u) << r.out;
    EXPECT_NE(r.out.find("completed"), std::string::npos) << r.out;
    j = show_json(dir, "1");
    EXPECT_EQ(j["session"]["state"], "completed");
    EXPECT_EQ(j["session"]["resumable"], false);
    EXPECT_EQ(j["session"]["instrument"]["model"], "BB-1E");
    EXPECT_EQ(j["session"]["instrument"]["serial"], "EMU00001");
    EXPECT_EQ(j["session"]["instrument"]["firmware"], "1.0.0");
    EXPECT_EQ(j["session"]["instrument"]["calibrated_length_mm"], 100.0);
    EXPECT_EQ(j["session"]["instrument"]["calibration_date"], "2026-01-15");
    const CliRun text = run(dir, "sessions show 1");
    EXPECT_NE(text.out.find("instrument  BB-1E, serial EMU00001, firmware 1.0.0, calibrated length 100.0000 mm, "
                            "calibrated on 2026-01-15"),
              std::string::npos)
        << text.out;
    EXPECT_NE(text.out.find("test 1 step 1 point 1"), std::string::npos) << "points numbered as measure does\n"
                                                                         << text.out;
}

TEST(CliSessions, BarLengthMismatchStopsBeforeAnyQuestionAndNamesTheFix) {
    TempDir dir;
    const fs::path cfg = emulator_config_sessions(dir, 150);
    const CliRun r = run(dir, measure_args("emulator:" + cfg.string(), dir));
    EXPECT_EQ(r.code, 1) << r.out << r.err;
    const std::string all = r.out + r.err;
    EXPECT_NE(all.find("bar length mismatch: the plan is for a 100 mm bar, the instrument's bar is calibrated at "
                       "150 mm"),
              std::string::npos)
        << all;
    EXPECT_NE(all.find("\"bar_length_mm\": 150 in the plan file"), std::string::npos) << all;
    EXPECT_EQ(all.find("[plan:"), std::string::npos) << "nothing was asked of the operator:\n" << all;
    const auto j = show_json(dir, "1");
    EXPECT_EQ(j["session"]["instrument"]["calibrated_length_mm"], 150.0) << "the identity is stored all the same";
}

TEST(CliSessions, TheListFiltersByMachineProcedureStateAndDateAndKeepsDemosApartWithTheirResult) {
    TempDir dir;
    ASSERT_EQ(run(dir, "demo --test circular --plane XY").code, 0);
    ASSERT_EQ(run(dir, "demo --json").code, 0);
    const CliRun all = run(dir, "sessions");
    ASSERT_EQ(all.code, 0) << all.err;
    EXPECT_NE(all.out.find("Demo sessions (the emulator):"), std::string::npos) << all.out;
    EXPECT_NE(all.out.find("G "), std::string::npos) << "the circular test's G: " << all.out;
    EXPECT_NE(all.out.find("|ΔV| max "), std::string::npos) << "the SSM's largest |ΔV|: " << all.out;
    EXPECT_NE(all.out.find(" µm"), std::string::npos) << all.out;

    const auto count = [&dir](const std::string& filters) {
        const CliRun r = run(dir, "sessions --json " + filters);
        EXPECT_EQ(r.code, 0) << r.err;
        return nlohmann::json::parse(r.out).size();
    };
    EXPECT_EQ(count(""), 2u);
    EXPECT_EQ(count("--procedure circular"), 1u);
    EXPECT_EQ(count("--procedure ssm"), 1u);
    EXPECT_EQ(count("--state completed"), 2u);
    EXPECT_EQ(count("--state interrupted"), 0u);
    EXPECT_EQ(count("--since 2000-01-01"), 2u);
    EXPECT_EQ(count("--since 2999-01-01"), 0u);
    const auto listed = nlohmann::json::parse(run(dir, "sessions --json").out);
    const std::string machine =
        listed[0]["machine"]["type"].get<std::string>() + " " + listed[0]["machine"]["name"].get<std::string>();
    EXPECT_EQ(count("--machine '" + machine + "'"), 1u) << machine;
    EXPECT_NE(run(dir, "sessions --since 2999-01-01").out.find("no sessions match the filters"), std::string::npos);
    EXPECT_EQ(run(dir, "sessions --since yesterday").code, 2);
    EXPECT_EQ(run(dir, "sessions --procedure milling").code, 2);
}
