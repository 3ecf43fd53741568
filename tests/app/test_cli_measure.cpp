// SPDX-License-Identifier: MIT
// `ballbar measure` driven like an operator would: through a pseudo-terminal (forkpty), answering the
// prompts as they appear, against the emulator in real time (a one-test plan, about ten seconds).
// Also the dry run (plan check and NC program) and the refusal of a plan outside the travel.
#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
const fs::path kDataMeasure = fs::path(BALLBAR_TEST_DATA_DIR) / "machines";

fs::path temp_dir() {
    const auto dir = fs::temp_directory_path() / ("ballbar-measure-test-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir;
}

std::string slurp(const fs::path& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

int run_measure(const std::string& args, std::string* out = nullptr) {
    const std::string cmd = std::string(BALLBAR_EXE) + " " + args + " 2>&1";
    FILE* p = ::popen(cmd.c_str(), "r");
    std::array<char, 4096> buf{};
    std::size_t n;
    std::string text;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) text.append(buf.data(), n);
    const int st = ::pclose(p);
    if (out) *out = text;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/// The emulator's configuration running the NC program `measure` writes to `program` (the emulated
/// operator loads it and presses cycle start when `measure` starts the stream). On simulated time unless
/// a test needs the wall clock (to stop a process half-way): a session then takes the CPU's time, not
/// the machine's 19 s, and what these tests check (prompts, answers, exit codes) is the same.
fs::path emulator_config(const fs::path& dir, const fs::path& program, bool simulated = true) {
    std::string cfg = slurp(kDataMeasure / "tttrr-emulator.json");
    cfg.replace(cfg.find("PROGRAM"), 7, program.string());
    if (simulated) cfg.replace(cfg.find('{'), 1, "{\"time\": \"simulated\",");
    const fs::path path = dir / ("emulator-" + program.stem().string() + ".json");
    std::ofstream(path) << cfg;
    return path;
}

TEST(CliMeasure, DryRunChecksThePlanAndWritesTheProgram) {
    std::string out;
    ASSERT_EQ(run_measure("measure --dry-run --machine " + (kDataMeasure / "rrttt.json").string(), &out), 0) << out;
    EXPECT_NE(out.find("G90"), std::string::npos);
    EXPECT_NE(out.find("G4 P"), std::string::npos);
    EXPECT_NE(out.find(" B"), std::string::npos);  // RRTTT turns A and B
    const fs::path bad = temp_dir() / "narrow.json";
    std::string m = slurp(kDataMeasure / "tttrr.json");
    m.replace(m.find("\"A_deg\": [-30, 120]"), 19, "\"A_deg\": [-5, 5]");
    std::ofstream(bad) << m;
    EXPECT_EQ(run_measure("measure --dry-run --machine " + bad.string() + " --plan " +
                              (kDataMeasure / "tttrr-table2.plan.json").string(),
                          &out),
              2);
    EXPECT_NE(out.find("A = 15"), std::string::npos) << out;
    EXPECT_NE(out.find("travel"), std::string::npos) << out;
}

TEST(CliMeasure, InteractiveSessionThroughAPseudoTerminal) {
    const fs::path dir = temp_dir();
    const std::string prog = (dir / "session.nc").string();
    fs::remove(prog);
    const fs::path cfg = emulator_config(dir, prog);
    const fs::path db = dir / "interactive.db";
    fs::remove(db);
    const std::string exe = BALLBAR_EXE;
    const std::string machine = (kDataMeasure / "tttrr.json").string();
    const std::string plan = (kDataMeasure / "tttrr-quick.plan.json").string();
    const std::string device = "emulator:" + cfg.string();

    int master = -1;
    const pid_t pid = ::forkpty(&master, nullptr, nullptr, nullptr);
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        ::unsetenv("NO_COLOR");
        ::execl(exe.c_str(), exe.c_str(), "--db", db.c_str(), "measure", "--device", device.c_str(), "--machine",
                machine.c_str(), "--plan", plan.c_str(), "--operator", "tester", "--program", prog.c_str(),
                static_cast<char*>(nullptr));
        ::_exit(127);
    }
    std::string screen;
    std::size_t answered = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(90);
    for (;;) {
        pollfd pfd{master, POLLIN, 0};
        if (::poll(&pfd, 1, 200) > 0) {
            std::array<char, 4096> buf{};
            const ssize_t n = ::read(master, buf.data(), buf.size());
            if (n <= 0) break;  // the child closed the terminal
            screen.append(buf.data(), static_cast<std::size_t>(n));
        }
        // Answer each new question as it appears: yes, Enter after cycle start, accept the results
        // (the first time with a typo, which is asked again).
        struct Prompt {
            const char* text;
            std::string answer;
        };
        const Prompt prompts[] = {{"[yes / not yet / abort]", "yes\n"},
                                  {"pressed cycle start (or type abort).", "\n"},
                                  {"measure-again or abort:", "acept\n"},
                                  {"Please answer", "ac\n"}};
        std::vector<std::pair<std::size_t, std::string>> due;
        for (const Prompt& p : prompts)
            for (std::size_t at = screen.find(p.text); at != std::string::npos; at = screen.find(p.text, at + 1))
                due.emplace_back(at, p.answer);
        std::sort(due.begin(), due.end());
        while (answered < due.size()) {
            const std::string& a = due[answered].second;
            ASSERT_EQ(::write(master, a.data(), a.size()), static_cast<ssize_t>(a.size()));
            ++answered;
        }
        if (std::chrono::steady_clock::now() > deadline) {
            ::kill(pid, SIGKILL);
            break;
        }
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ::close(master);
    ASSERT_TRUE(WIFEXITED(status)) << screen;
    EXPECT_EQ(WEXITSTATUS(status), 0) << screen;
    EXPECT_GE(answered, 5u) << screen;  // reference, set-up, mount the bar, accept (with a typo)
    EXPECT_NE(screen.find("calibrator"), std::string::npos) << screen;
    EXPECT_NE(screen.find("start it on the machine"), std::string::npos) << screen;
    EXPECT_NE(screen.find("Program stop (M0): mount the bar"), std::string::npos) << screen;
    EXPECT_NE(screen.find("Please answer accept, measure-again or abort"), std::string::npos)
        << "a typo is asked again: " << screen;
    EXPECT_NE(screen.find("ΔV1 ("), std::string::npos) << "results shown before they are accepted: " << screen;
    EXPECT_NE(screen.find(", σ "), std::string::npos) << "each point with its standard deviation: " << screen;
    EXPECT_NE(screen.find(" left"), std::string::npos) << "time left: " << screen;
    EXPECT_EQ(screen.find("Δβ"), std::string::npos) << "a TTTRR has no Δβ: " << screen;
    EXPECT_NE(screen.find("] 3/6"), std::string::npos) << "progress bar: " << screen;
    EXPECT_NE(screen.find("bar "), std::string::npos) << "live bar reading: " << screen;
    EXPECT_NE(screen.find(" µm)"), std::string::npos) << "live bar reading: " << screen;
    EXPECT_NE(screen.find("\033["), std::string::npos) << "colour on a terminal";
    EXPECT_NE(screen.find("completed"), std::string::npos) << screen;
    EXPECT_NE(screen.find("orientation (exact)"), std::string::npos) << screen;
    EXPECT_TRUE(fs::exists(prog));
}

/// docs/procedure.md's two commands, in two processes: `ballbar emulate --pty --config …` and
/// `ballbar measure --device serial:PTY …` (with --non-interactive), with the given plan; the exit
/// code, and measure's output in `out`.
/// `emulate --pty` and `measure` on its pty, as docs/procedure.md shows them; `fast`: the emulator as fast
/// as measure reads (`emulate --fast`).
int run_two_processes(const fs::path& db, const fs::path& plan, std::string& out, bool fast = false) {
    fs::remove(db);
    fs::remove("/tmp/ballbar-session.nc");
    const std::string exe = BALLBAR_EXE;
    const std::string cfg = (kDataMeasure / "tttrr-emulator-measure.json").string();
    int outfd[2];
    if (::pipe(outfd) != 0) return -1;
    const pid_t emu = ::fork();
    if (emu < 0) return -1;
    if (emu == 0) {
        ::dup2(outfd[1], STDOUT_FILENO);
        ::close(outfd[0]);
        if (fast)
            ::execl(exe.c_str(), exe.c_str(), "emulate", "--pty", "--fast", "--config", cfg.c_str(),
                    static_cast<char*>(nullptr));
        else
            ::execl(exe.c_str(), exe.c_str(), "emulate", "--pty", "--config", cfg.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
    }
    ::close(outfd[1]);
    std::string line;
    char c = 0;
    while (::read(outfd[0], &c, 1) == 1 && c != '\n') line += c;
    int code = -1;
    if (line.rfind("/dev/pts/", 0) == 0)
        code = run_measure("--db " + db.string() + " measure --non-interactive --device serial:" + line +
                               " --machine " + (kDataMeasure / "tttrr.json").string() + " --plan " + plan.string() +
                               " --program /tmp/ballbar-session.nc",
                           &out);
    else
        out = "the emulator printed no pty: " + line;
    ::kill(emu, SIGINT);
    int st = 0;
    ::waitpid(emu, &st, 0);
    ::close(outfd[0]);
    return code;
}

TEST(CliMeasure, TheDocumentedTwoProcessCommandsCompleteASession) {
    std::string out;
    const int code = run_two_processes(temp_dir() / "two-process.db", kDataMeasure / "tttrr-quick.plan.json", out);
    EXPECT_EQ(code, 0) << out;
    EXPECT_NE(out.find("Program stop (M0): mount the bar"), std::string::npos) << out;
    EXPECT_NE(out.find("completed"), std::string::npos) << out;
    EXPECT_NE(out.find("1 program)"), std::string::npos) << "no retry needed: " << out;
}

/// A plan with a second socket position, through `emulate --pty`: the program stops for the remount,
/// the emulated machine's socket goes where the stop says (as an operator would move it), and the
/// session completes with both tests measured. Had a point of the second test been taken at the first
/// socket, its reading would be millimetres off and the capture would refuse it.
TEST(CliMeasure, ATwoSocketPlanCompletesThroughTheEmulatorOnAPty) {
    const fs::path db = temp_dir() / "two-sockets.db";
    std::string out;
    const int code = run_two_processes(db, kDataMeasure / "tttrr-two-sockets.plan.json", out, /*fast=*/true);
    EXPECT_EQ(code, 0) << out;
    EXPECT_NE(out.find("move the socket to [-29.275, -24.312, -77.777]"), std::string::npos) << out;
    EXPECT_NE(out.find("completed"), std::string::npos) << out;
    std::string shown;
    ASSERT_EQ(run_measure("--db " + db.string() + " sessions show 1 --json", &shown), 0) << shown;
    const auto j = nlohmann::json::parse(shown);
    EXPECT_EQ(j.at("session").at("state"), "completed") << shown;
    EXPECT_EQ(j.at("session").at("point_count"), 12) << "two tests, two steps, three points each";
}

TEST(CliMeasure, ADefaultPlanWithTheEmulatorsDefaultBarIsRefusedBeforeAnyQuestion) {
    const fs::path dir = temp_dir();
    std::string out;
    const int code = run_measure("--db " + (dir / "mismatch.db").string() +
                                     " measure --non-interactive --device emulator: --machine " +
                                     (kDataMeasure / "tttrr.json").string(),
                                 &out);
    EXPECT_EQ(code, 1) << out;
    EXPECT_NE(out.find("\"bar_length_mm\": 150 in a plan file"), std::string::npos) << "names the fix: " << out;
    EXPECT_EQ(out.find("calibrator"), std::string::npos) << "nothing asked first: " << out;
}

TEST(CliMeasure, JsonGivesTheOperatorsEventsAsJsonLines) {
    const fs::path dir = temp_dir();
    fs::remove(dir / "j.nc");
    const fs::path cfg = emulator_config(dir, dir / "j.nc");
    const fs::path db = dir / "json.db";
    fs::remove(db);
    std::string out;
    const int code =
        run_measure("--db " + db.string() + " measure --json --non-interactive --device emulator:" + cfg.string() +
                        " --machine " + (kDataMeasure / "tttrr.json").string() + " --plan " +
                        (kDataMeasure / "tttrr-quick.plan.json").string() + " --program " + (dir / "j.nc").string(),
                    &out);
    EXPECT_EQ(code, 0) << out;
    int points = 0, stops = 0, programs = 0, done = 0;
    std::istringstream lines(out);
    for (std::string line; std::getline(lines, line);) {
        if (line.empty() || line[0] != '{') continue;  // the session line
        const auto j = nlohmann::json::parse(line);
        const std::string ev = j.at("event");
        if (ev == "point") {
            ++points;
            EXPECT_GT(j.at("sd_um").get<double>(), 0.0) << line;
            EXPECT_NE(j.at("evidence").get<std::string>().find("code "), std::string::npos) << line;
        }
        stops += ev == "program_stop";
        programs += ev == "run_program";
        done += ev == "done";
    }
    EXPECT_EQ(points, 6) << out;
    EXPECT_EQ(stops, 1) << out;
    EXPECT_EQ(programs, 1) << out;
    EXPECT_EQ(done, 1) << out;
}

TEST(CliMeasure, NonInteractiveTakesThePlansAnswers) {
    const fs::path dir = temp_dir();
    fs::remove(dir / "b.nc");
    const fs::path cfg = emulator_config(dir, dir / "b.nc");
    const fs::path db = dir / "batch.db";
    fs::remove(db);
    std::string out;
    const int code =
        run_measure("--db " + db.string() + " measure --non-interactive --device emulator:" + cfg.string() +
                        " --machine " + (kDataMeasure / "tttrr.json").string() + " --plan " +
                        (kDataMeasure / "tttrr-quick.plan.json").string() + " --program " + (dir / "b.nc").string(),
                    &out);
    EXPECT_EQ(code, 0) << out;
    EXPECT_NE(out.find("[plan: yes]"), std::string::npos) << out;
    EXPECT_NE(out.find("captured 5/6"), std::string::npos) << out;
    EXPECT_NE(out.find("completed"), std::string::npos) << out;
    EXPECT_EQ(out.find("\033["), std::string::npos) << "no colour in a pipe";
    // Nothing left to resume: a completed session is refused as a bad command line (exit 2).
    std::regex id_re("Session ([0-9]+)");
    std::smatch m;
    ASSERT_TRUE(std::regex_search(out, m, id_re)) << out;
    std::string refused;
    EXPECT_EQ(run_measure("--db " + db.string() + " measure --non-interactive --device emulator:" + cfg.string() +
                              " --resume " + m[1].str(),
                          &refused),
              2)
        << refused;
}

TEST(CliMeasure, AQualityAbortInCiIsAFailureExit1NotAnInterruption) {
    // The plan's capture asks for a 0.05 µm standard deviation of a 0.1 µm-noise bar: every point fails
    // its checks, and the plan's answer to a failed point is "abort" (as in CI).
    const fs::path dir = temp_dir();
    fs::remove(dir / "q.nc");
    const fs::path cfg = emulator_config(dir, dir / "q.nc");
    std::string plan = slurp(kDataMeasure / "tttrr-quick.plan.json");
    const std::string loose = "\"max_std_um\": 2";
    ASSERT_NE(plan.find(loose), std::string::npos);
    plan.replace(plan.find(loose), loose.size(), "\"max_std_um\": 0.05, \"retries\": 0");
    const fs::path plan_file = dir / "strict.plan.json";
    std::ofstream(plan_file) << plan;
    const fs::path db = dir / "quality.db";
    fs::remove(db);
    std::string out;
    const int code =
        run_measure("--db " + db.string() + " measure --non-interactive --device emulator:" + cfg.string() +
                        " --machine " + (kDataMeasure / "tttrr.json").string() + " --plan " + plan_file.string() +
                        " --program " + (dir / "q.nc").string(),
                    &out);
    EXPECT_EQ(code, 1) << "3 is only an interruption:\n" << out;
    EXPECT_NE(out.find("ballbar: error: session 1 aborted: "), std::string::npos) << out;
    EXPECT_NE(out.find("failed"), std::string::npos) << out;
    std::string shown;
    ASSERT_EQ(run_measure("--db " + db.string() + " sessions show 1 --json", &shown), 0) << shown;
    EXPECT_EQ(nlohmann::json::parse(shown).at("session").at("state"), "aborted") << shown;
}

/// Starts `measure --non-interactive` on the emulator and reads its output until three of the six
/// points are captured (the fourth is a second away); then sends `sig` and waits. Returns the output,
/// the session id and the exit status.
struct StoppedMeasure {
    std::string out;
    std::string session;
    int status = 0;
};

StoppedMeasure measure_then_signal(const fs::path& dir, const fs::path& db, int sig) {
    const std::string exe = BALLBAR_EXE;
    const std::string machine = (kDataMeasure / "tttrr.json").string();
    const std::string plan = (kDataMeasure / "tttrr-quick.plan.json").string();
    const std::string prog = (dir / "k.nc").string();
    fs::remove(prog);
    const std::string device = "emulator:" + emulator_config(dir, prog, /*simulated=*/false).string();
    StoppedMeasure r;
    int outfd[2];
    if (::pipe(outfd) != 0) return r;
    const pid_t pid = ::fork();
    if (pid < 0) return r;
    if (pid == 0) {
        ::dup2(outfd[1], STDOUT_FILENO);
        ::dup2(outfd[1], STDERR_FILENO);
        ::close(outfd[0]);
        ::execl(exe.c_str(), exe.c_str(), "--db", db.c_str(), "measure", "--non-interactive", "--device",
                device.c_str(), "--machine", machine.c_str(), "--plan", plan.c_str(), "--program", prog.c_str(),
                static_cast<char*>(nullptr));
        ::_exit(127);
    }
    ::close(outfd[1]);
    std::array<char, 1024> buf{};
    while (r.out.find("captured 3/6") == std::string::npos) {
        const ssize_t n = ::read(outfd[0], buf.data(), buf.size());
        if (n <= 0) break;
        r.out.append(buf.data(), static_cast<std::size_t>(n));
    }
    ::kill(pid, sig);
    for (ssize_t n; (n = ::read(outfd[0], buf.data(), buf.size())) > 0;)
        r.out.append(buf.data(), static_cast<std::size_t>(n));
    ::waitpid(pid, &r.status, 0);
    ::close(outfd[0]);
    std::smatch m;
    if (std::regex_search(r.out, m, std::regex("Session ([0-9]+)"))) r.session = m[1].str();
    return r;
}

/// A new emulator (the machine runs whatever program `measure` writes); the session continues with a
/// retry program for the three points still missing.
void expect_resumes_after_three_points(const fs::path& dir, const fs::path& db, const std::string& session) {
    fs::remove(dir / "k2.nc");
    const std::string resumed_device = "emulator:" + emulator_config(dir, dir / "k2.nc").string();
    std::string out2;
    const int code = run_measure("--db " + db.string() + " measure --non-interactive --device " + resumed_device +
                                     " --resume " + session + " --program " + (dir / "k2.nc").string(),
                                 &out2);
    EXPECT_EQ(code, 0) << out2;
    EXPECT_NE(out2.find("resumed after 3 points"), std::string::npos) << out2;
    EXPECT_NE(out2.find("Retry program (3 points)"), std::string::npos) << out2;
    EXPECT_NE(out2.find("completed"), std::string::npos) << out2;
    EXPECT_NE(out2.find("orientation (exact)"), std::string::npos) << out2;
}

TEST(CliMeasure, KilledSessionResumesAfterItsLastPoint) {
    const fs::path dir = temp_dir();
    const fs::path db = dir / "killed.db";
    fs::remove(db);
    const StoppedMeasure s = measure_then_signal(dir, db, SIGKILL);
    ASSERT_TRUE(WIFSIGNALED(s.status)) << s.out;
    ASSERT_NE(s.out.find("captured 3/6"), std::string::npos) << s.out;
    ASSERT_FALSE(s.session.empty()) << s.out;
    expect_resumes_after_three_points(dir, db, s.session);
}

TEST(CliMeasure, CtrlCStoresStopsWithExit3AndResumes) {
    const fs::path dir = temp_dir();
    const fs::path db = dir / "ctrlc.db";
    fs::remove(db);
    const StoppedMeasure s = measure_then_signal(dir, db, SIGINT);
    ASSERT_TRUE(WIFEXITED(s.status)) << "Ctrl-C must not kill the process\n" << s.out;
    EXPECT_EQ(WEXITSTATUS(s.status), 3) << s.out;
    EXPECT_NE(s.out.find("interrupted after"), std::string::npos) << s.out;
    EXPECT_NE(s.out.find("--resume " + s.session), std::string::npos) << "says how to continue:\n" << s.out;
    ASSERT_FALSE(s.session.empty()) << s.out;
    // Stored as interrupted by the operator, not failed or aborted: resumable.
    std::string shown;
    ASSERT_EQ(run_measure("--db " + db.string() + " sessions show " + s.session + " --json", &shown), 0) << shown;
    EXPECT_NE(shown.find("\"state\": \"interrupted\""), std::string::npos) << shown;
    EXPECT_NE(shown.find("interrupted: interrupted by the operator"), std::string::npos) << shown;  // the stored reason
    expect_resumes_after_three_points(dir, db, s.session);
}

/// Issue 24: kill -9 of `measure` leaves a standalone instrument streaming (this one has no watchdog,
/// the worst case); an immediate `measure --resume` on the same instrument stops the stream, takes
/// over and completes, where it used to fail with "the instrument refused Configure: busy" and mark
/// the session failed.
TEST(CliMeasure, AResumeRightAfterAKillTakesOverTheStreamingInstrument) {
    const fs::path dir = temp_dir() / "takeover";
    fs::create_directories(dir);
    const fs::path db = dir / "takeover.db", prog = dir / "t.nc";
    fs::remove(db);
    fs::remove(prog);
    std::string cfg = slurp(kDataMeasure / "tttrr-emulator-measure.json");
    cfg.replace(cfg.find("/tmp/ballbar-session.nc"), 23, prog.string());
    const fs::path cfg_path = dir / "emulator.json";
    std::ofstream(cfg_path) << cfg;
    const std::string exe = BALLBAR_EXE;
    int emu_out[2];
    ASSERT_EQ(::pipe(emu_out), 0);
    const pid_t emu = ::fork();
    ASSERT_GE(emu, 0);
    if (emu == 0) {
        ::dup2(emu_out[1], STDOUT_FILENO);
        ::close(emu_out[0]);
        ::execl(exe.c_str(), exe.c_str(), "emulate", "--tcp", "0", "--watchdog", "0", "--config", cfg_path.c_str(),
                static_cast<char*>(nullptr));
        ::_exit(127);
    }
    ::close(emu_out[1]);
    std::string device;
    for (char c = 0; ::read(emu_out[0], &c, 1) == 1 && c != '\n';) device += c;
    ASSERT_EQ(device.rfind("tcp:127.0.0.1:", 0), 0u) << device;

    // 1. measure, killed while the instrument streams (after three points).
    int out[2];
    ASSERT_EQ(::pipe(out), 0);
    const std::string machine = (kDataMeasure / "tttrr.json").string(),
                      plan = (kDataMeasure / "tttrr-quick.plan.json").string();
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        ::dup2(out[1], STDOUT_FILENO);
        ::dup2(out[1], STDERR_FILENO);
        ::close(out[0]);
        ::execl(exe.c_str(), exe.c_str(), "--db", db.c_str(), "measure", "--non-interactive", "--device",
                device.c_str(), "--machine", machine.c_str(), "--plan", plan.c_str(), "--program", prog.c_str(),
                static_cast<char*>(nullptr));
        ::_exit(127);
    }
    ::close(out[1]);
    std::string first;
    std::array<char, 1024> buf{};
    while (first.find("captured 3/6") == std::string::npos) {
        const ssize_t n = ::read(out[0], buf.data(), buf.size());
        if (n <= 0) break;
        first.append(buf.data(), static_cast<std::size_t>(n));
    }
    ::kill(pid, SIGKILL);
    int st = 0;
    ::waitpid(pid, &st, 0);
    ::close(out[0]);
    ASSERT_NE(first.find("captured 3/6"), std::string::npos) << first;

    // 2. at once, on the same (still streaming) instrument.
    std::string second;
    const int code = run_measure("--db " + db.string() + " measure --non-interactive --device " + device +
                                     " --resume 1 --program " + prog.string(),
                                 &second);
    ::kill(emu, SIGINT);
    ::waitpid(emu, &st, 0);
    ::close(emu_out[0]);
    EXPECT_EQ(code, 0) << second;
    EXPECT_EQ(second.find("busy"), std::string::npos) << second;
    EXPECT_NE(second.find("resumed after 3 points"), std::string::npos) << second;
    EXPECT_NE(second.find("completed"), std::string::npos) << second;
}

}  // namespace
