// SPDX-License-Identifier: MIT
// The digital gauges from the command line (issue 14): `ballbar emulate --instrument KIND --pty` in one
// process, `ballbar monitor --device KIND:PATH` in another; and `ballbar demo --instrument KIND`, the
// guided SSM procedure on each emulated gauge at 20 readings/s, which must recover the injected errors
// within 1 µm and 2 arc-seconds.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_harness.hpp"

extern char** environ;

namespace {

class GaugeChild {
  public:
    explicit GaugeChild(std::vector<std::string> args) {
        int fds[2];
        if (::pipe(fds) != 0) throw std::runtime_error("pipe");
        posix_spawn_file_actions_t fa;
        posix_spawn_file_actions_init(&fa);
        posix_spawn_file_actions_adddup2(&fa, fds[1], STDOUT_FILENO);
        posix_spawn_file_actions_addclose(&fa, fds[0]);
        std::vector<char*> argv;
        for (auto& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        if (posix_spawn(&pid_, argv[0], &fa, nullptr, argv.data(), environ) != 0) throw std::runtime_error("spawn");
        posix_spawn_file_actions_destroy(&fa);
        ::close(fds[1]);
        out_ = fds[0];
    }
    ~GaugeChild() {
        ::kill(pid_, SIGTERM);
        int status = 0;
        ::waitpid(pid_, &status, 0);
        ::close(out_);
    }
    std::string line(int timeout_ms) {
        std::string s;
        for (;;) {
            pollfd p{out_, POLLIN, 0};
            if (::poll(&p, 1, timeout_ms) <= 0) return {};
            char c;
            if (::read(out_, &c, 1) != 1 || c == '\n') return s;
            s.push_back(c);
        }
    }

  private:
    pid_t pid_ = -1;
    int out_ = -1;
};

class GaugeCli : public ::testing::TestWithParam<std::string> {};

TEST_P(GaugeCli, EmulateThenMonitor) {
    GaugeChild emu({BALLBAR_EXE, "emulate", "--instrument", GetParam(), "--pty", "--rate", "40"});
    const std::string path = emu.line(5000);
    ASSERT_EQ(path.rfind("/dev/pts/", 0), 0u) << "emulate printed '" << path << "'";
    ballbar::test::TempDir dir;
    const std::string uri = GetParam() + ":" + path + (GetParam() == "modbus" ? "?slave=1" : "");
    const auto r = ballbar::test::run(dir, "monitor --device '" + uri + "' --seconds 1.5 --rate 1000 --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_NEAR(j.at("rate_hz").get<double>(), 40, 8) << r.out;  // the gauge's own pace
    EXPECT_GE(j.at("samples").get<int>(), 40);
    EXPECT_GT(j.at("resolution_mm").get<double>(), 0);
    EXPECT_EQ(j.at("timeouts").get<int>(), 0);
}

TEST_P(GaugeCli, DemoRecoversTheInjectedErrors) {
    ballbar::test::TempDir dir;
    const auto r = ballbar::test::run(dir, "demo --instrument " + GetParam() + " --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_LT(j.at("max_location_error_um").get<double>(), 1.0) << r.out;
    EXPECT_LT(j.at("max_orientation_error_arcsec").get<double>(), 2.0) << r.out;
    EXPECT_GE(j.at("locations").size(), 2u);
    const auto& inst = j.at("instrument");
    EXPECT_NEAR(inst.at("reading_rate_hz").get<double>(), 20, 0.5);  // measured, on the gauge's clock
    EXPECT_NEAR(inst.at("resolution_mm").get<double>(), 1e-4, 1e-12);

    // Resolution and measured rate are stored with every sample (through its segment), shown by sessions show.
    const std::string id = std::to_string(j.at("session").get<int>());
    const auto show = ballbar::test::run(dir, "sessions show " + id);
    ASSERT_EQ(show.code, 0) << show.err;
    EXPECT_NE(show.out.find(": resolution 0.1 µm, 20.0 readings/s measured"), std::string::npos) << show.out;
    const auto js = ballbar::test::run(dir, "sessions show " + id + " --json");
    ASSERT_EQ(js.code, 0) << js.err;
    const auto segs = nlohmann::json::parse(js.out).at("sample_segments");
    ASSERT_GE(segs.size(), 1u) << js.out;
    for (const auto& g : segs) {
        EXPECT_NEAR(g.at("resolution_mm").get<double>(), 1e-4, 1e-12) << js.out;
        EXPECT_NEAR(g.at("reading_rate_hz").get<double>(), 20, 0.5) << js.out;
    }
}

INSTANTIATE_TEST_SUITE_P(Serial, GaugeCli, ::testing::Values("sylvac", "digimatic", "modbus"),
                         [](const auto& p) { return std::string(p.param); });

TEST(GaugeCliItn, DemoOnTheUsbItn) {
    ballbar::test::TempDir dir;
    const auto r = ballbar::test::run(dir, "demo --instrument mitutoyo-itn --json --rate 10");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_LT(j.at("max_location_error_um").get<double>(), 1.0) << r.out;
    EXPECT_LT(j.at("max_orientation_error_arcsec").get<double>(), 2.0) << r.out;
    EXPECT_EQ(j.at("instrument").at("serial"), "EMU-G1");
    EXPECT_NEAR(j.at("instrument").at("reading_rate_hz").get<double>(), 10, 0.5);
}

TEST(GaugeCliItn, UsageErrors) {
    ballbar::test::TempDir dir;
    EXPECT_EQ(ballbar::test::run(dir, "emulate --instrument mitutoyo-itn --pty").code, 2);
    EXPECT_EQ(ballbar::test::run(dir, "emulate --instrument sylvac --tcp 0").code, 2);
    EXPECT_EQ(ballbar::test::run(dir, "emulate --instrument sylvac --pty --faults bogus=1").code, 2);
    EXPECT_EQ(ballbar::test::run(dir, "monitor --device 'modbus:/dev/null?slave=999' --seconds 1").code, 2);
    const auto r = ballbar::test::run(dir, "monitor --device sylvac:/nonexistent/tty --seconds 1");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("/nonexistent/tty"), std::string::npos) << r.err;
}

}  // namespace
