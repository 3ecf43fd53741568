// SPDX-License-Identifier: MIT
// Acceptance of the device layer: `ballbar emulate --pty` in one process and
// `ballbar monitor --device serial:<path> --seconds 2 --json` in another report ≈ 2000 samples and 0
// lost frames. Also over TCP, and the usage errors.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

extern char** environ;

namespace {

/// A child process whose stdout we read line by line.
class Child {
  public:
    explicit Child(std::vector<std::string> args) {
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
    ~Child() {
        if (pid_ > 0) {
            ::kill(pid_, SIGTERM);
            wait();
        }
        ::close(out_);
    }
    /// The next stdout line, or "" after `timeout_ms`.
    std::string line(int timeout_ms) {
        std::string s;
        while (true) {
            pollfd p{out_, POLLIN, 0};
            if (::poll(&p, 1, timeout_ms) <= 0) return {};
            char c;
            if (::read(out_, &c, 1) != 1) return s;
            if (c == '\n') return s;
            s.push_back(c);
        }
    }
    int wait() {
        int status = 0;
        ::waitpid(pid_, &status, 0);
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }

  private:
    pid_t pid_ = -1;
    int out_ = -1;
};

struct Run {
    int code;
    std::string out;
};

Run run_emulate_monitor(const std::string& cmd) {
    std::string out;
    FILE* f = ::popen(cmd.c_str(), "r");
    std::array<char, 4096> buf{};
    std::size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) out.append(buf.data(), n);
    const int status = ::pclose(f);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace

TEST(CliEmulateMonitor, PtyTwoSecondsGiveAbout2000SamplesAndNoLoss) {
    Child emu({BALLBAR_EXE, "emulate", "--pty", "--seed", "7"});
    const std::string path = emu.line(5000);
    ASSERT_EQ(path.rfind("/dev/pts/", 0), 0u) << "emulate printed '" << path << "'";
    const auto r =
        run_emulate_monitor(std::string(BALLBAR_EXE) + " monitor --device serial:" + path + " --seconds 2 --json");
    ASSERT_EQ(r.code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_NEAR(j.at("samples").get<double>(), 2000.0, 150.0) << r.out;
    EXPECT_EQ(j.at("lost_frames").get<int>(), 0) << r.out;
    EXPECT_NEAR(j.at("rate_hz").get<double>(), 1000.0, 1.0);
    EXPECT_NEAR(j.at("mean_mm").get<double>(), 150.0237, 0.001);  // unreferenced zero error 23.7 µm
    EXPECT_NEAR(j.at("sd_mm").get<double>(), 0.25e-3, 0.05e-3);
    // A second session on the same pty works too (the emulator outlives its hosts).
    const auto r2 =
        run_emulate_monitor(std::string(BALLBAR_EXE) + " monitor --device serial:" + path + " --seconds 0.5 --json");
    ASSERT_EQ(r2.code, 0) << r2.out;
    EXPECT_EQ(nlohmann::json::parse(r2.out).at("lost_frames").get<int>(), 0);
}

TEST(CliEmulateMonitor, TcpLoopback) {
    Child emu({BALLBAR_EXE, "emulate", "--tcp", "0"});
    const std::string uri = emu.line(5000);
    ASSERT_EQ(uri.rfind("tcp:127.0.0.1:", 0), 0u) << uri;
    const auto r = run_emulate_monitor(std::string(BALLBAR_EXE) + " monitor --device " + uri + " --seconds 0.5 --json");
    ASSERT_EQ(r.code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_NEAR(j.at("samples").get<double>(), 500.0, 100.0);
    EXPECT_EQ(j.at("lost_frames").get<int>(), 0);
}

TEST(CliEmulateMonitor, UsageAndDeviceErrors) {
    EXPECT_EQ(run_emulate_monitor(std::string(BALLBAR_EXE) + " monitor --device nonsense 2>&1").code, 2);
    EXPECT_EQ(
        run_emulate_monitor(std::string(BALLBAR_EXE) + " monitor --device serial:/dev/nonexistent-bb --seconds 1 2>&1")
            .code,
        1);
    EXPECT_EQ(run_emulate_monitor(std::string(BALLBAR_EXE) + " emulate 2>&1").code, 2);
    const auto r = run_emulate_monitor(std::string(BALLBAR_EXE) + " monitor --device emulator: --seconds 0.3 --json");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_GT(nlohmann::json::parse(r.out).at("samples").get<int>(), 200);
}

// Issue 24: an instrument that identifies but never streams (here every stream frame is lost) is a
// failure, exit 1, saying so; the JSON summary gives no statistics of nothing (null), not "std 0".
TEST(CliEmulateMonitor, AnInstrumentThatNeverStreamsIsAFailureNotZeroSamples) {
    char dir_template[] = "/tmp/ballbar-mute-XXXXXX";
    ASSERT_NE(::mkdtemp(dir_template), nullptr);
    const std::string cfg = std::string(dir_template) + "/mute.json";
    FILE* f = std::fopen(cfg.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("{\"faults\": {\"drop_frame_probability\": 1}}", f);
    std::fclose(f);
    const auto text =
        run_emulate_monitor(std::string(BALLBAR_EXE) + " monitor --device emulator:" + cfg + " --seconds 0.5 2>&1");
    EXPECT_EQ(text.code, 1) << text.out;
    EXPECT_NE(text.out.find("sent no samples"), std::string::npos) << text.out;
    EXPECT_EQ(text.out.find("std 0"), std::string::npos) << text.out;
    const auto json =
        run_emulate_monitor(std::string(BALLBAR_EXE) + " monitor --device emulator:" + cfg + " --seconds 0.5 --json");
    EXPECT_EQ(json.code, 1) << json.out;
    const auto j = nlohmann::json::parse(json.out, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << json.out;
    EXPECT_EQ(j.at("samples").get<int>(), 0);
    EXPECT_TRUE(j.at("sd_mm").is_null()) << json.out;
    EXPECT_NE(j.at("error").get<std::string>().find("sent no samples"), std::string::npos) << json.out;
    std::remove(cfg.c_str());
    ::rmdir(dir_template);
}

// `--link PATH` makes a new symlink to the pty and removes it when the emulator stops; whatever is
// already at PATH (a file, someone's link) is refused with exit 2 and left as it was.
TEST(CliEmulateMonitor, TheLinkIsMadeNewAndNeverOverSomethingElse) {
    char dir_template[] = "/tmp/ballbar-link-XXXXXX";
    ASSERT_NE(::mkdtemp(dir_template), nullptr);
    const std::string dir = dir_template;
    const std::string link = dir + "/bar";
    {
        Child emu({BALLBAR_EXE, "emulate", "--pty", "--seed", "7", "--link", link});
        const std::string path = emu.line(5000);
        ASSERT_EQ(path.rfind("/dev/pts/", 0), 0u) << path;
        std::array<char, 256> target{};
        const ssize_t n = ::readlink(link.c_str(), target.data(), target.size() - 1);
        ASSERT_GT(n, 0);
        EXPECT_EQ(std::string(target.data(), static_cast<std::size_t>(n)), path);
        const auto r = run_emulate_monitor(std::string(BALLBAR_EXE) + " monitor --device serial:" + link +
                                           " --seconds 0.3 --json");
        EXPECT_EQ(r.code, 0) << r.out;
    }  // SIGTERM: the emulator stops and takes its link with it
    EXPECT_NE(::access(link.c_str(), F_OK), 0);
    struct stat st {};
    EXPECT_NE(::lstat(link.c_str(), &st), 0) << "the link to a closed pty is left behind";

    // A file there: refused, named, and untouched.
    {
        FILE* f = std::fopen(link.c_str(), "w");
        ASSERT_NE(f, nullptr);
        std::fputs("not the emulator's\n", f);
        std::fclose(f);
    }
    const auto refused = run_emulate_monitor(std::string(BALLBAR_EXE) + " emulate --pty --link " + link + " 2>&1");
    EXPECT_EQ(refused.code, 2) << refused.out;
    EXPECT_NE(refused.out.find(link), std::string::npos) << refused.out;
    {
        FILE* f = std::fopen(link.c_str(), "r");
        ASSERT_NE(f, nullptr);
        std::array<char, 64> buf{};
        const std::size_t got = std::fread(buf.data(), 1, buf.size(), f);
        std::fclose(f);
        EXPECT_EQ(std::string(buf.data(), got), "not the emulator's\n");
    }
    // Someone's dangling link: refused too.
    ::unlink(link.c_str());
    ASSERT_EQ(::symlink("/dev/pts/someone-elses", link.c_str()), 0);
    EXPECT_EQ(run_emulate_monitor(std::string(BALLBAR_EXE) + " emulate --pty --link " + link + " 2>&1").code, 2);
    std::array<char, 256> target{};
    const ssize_t n = ::readlink(link.c_str(), target.data(), target.size() - 1);
    ASSERT_GT(n, 0);
    EXPECT_EQ(std::string(target.data(), static_cast<std::size_t>(n)), "/dev/pts/someone-elses");
    ::unlink(link.c_str());
    ::rmdir(dir.c_str());
}
