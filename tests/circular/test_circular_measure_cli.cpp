// SPDX-License-Identifier: MIT
// The circular test measured end to end by the real `ballbar` binary: `demo --test circular` on the three
// planes (full circle and partial arc) against the emulator's truth, under a disconnect (the run is
// repeated), and `circle measure` against `emulate --pty` in another process, interrupted and resumed;
// every stored session read back by `circle analyze SESSION` and `export --format trace`.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../app/cli_harness.hpp"
#include "diagnostic_json.hpp"

namespace {

using ballbar::test::run;
using ballbar::test::TempDir;
using json = nlohmann::json;

json demo(const TempDir& dir, const std::string& args, int expect_code = 0) {
    const auto r = run(dir, "demo --test circular --json " + args);
    EXPECT_EQ(r.code, expect_code) << r.err << r.out;
    const auto nl = r.out.find('{');
    if (nl == std::string::npos) return json::object();
    return json::parse(r.out.substr(nl), nullptr, false);
}

/// Every diagnostic of the demo within the accuracy rule, and the stored session analysed alike.
void expect_truth_met(const TempDir& dir, const json& j) {
    ASSERT_TRUE(j.is_object() && j.contains("diagnostics")) << j.dump();
    EXPECT_TRUE(j["pass"].get<bool>()) << j.dump(1);
    for (const auto& d : j["diagnostics"]) EXPECT_TRUE(d["pass"].get<bool>()) << d.dump() << " (" << j["plane"] << ")";
    ASSERT_EQ(j["runs"].size(), 2u);
    const std::string id = std::to_string(j["session"].get<int>());
    // The stored session reads like an imported trace: analyze it, export it, analyze the file.
    const auto an = run(dir, "circle analyze " + id + " --json");
    ASSERT_EQ(an.code, 0) << an.err;
    const auto a = json::parse(an.out);
    EXPECT_NEAR(a["runs"][0]["circularity_um"].get<double>(), j["runs"][0]["circularity_um"].get<double>(), 1e-9);
    const auto ex = run(dir, "export " + id + " --format trace --out '" + dir.file("back.csv") + "'");
    ASSERT_EQ(ex.code, 0) << ex.err;
    const auto back = run(dir, "circle analyze '" + dir.file("back.csv") + "' --json");
    ASSERT_EQ(back.code, 0) << back.err;
    EXPECT_NEAR(json::parse(back.out)["runs"][1]["circularity_um"].get<double>(),
                j["runs"][1]["circularity_um"].get<double>(), 0.01);
}

}  // namespace

TEST(CircularDemo, XyFullCircleMeetsTheEmulatorsTruth) {
    TempDir dir;
    const json j = demo(dir, "--plane XY");
    EXPECT_EQ(j["attempts"], 1);
    EXPECT_EQ(j["data_arc_deg"], 360.0);
    expect_truth_met(dir, j);
}

TEST(CircularDemo, XyPartialArcMeetsTheEmulatorsTruth) {
    TempDir dir;
    // --report writes the stored session's PDF (it was once taken and ignored); the report's polar plot
    // carries each run's model curve from the stored result, over the partial arc.
    const json j = demo(dir, "--plane XY --arc 180 --seed 3 --report '" + dir.file("circle.pdf") + "'");
    expect_truth_met(dir, j);
    EXPECT_EQ(j["report"], dir.file("circle.pdf"));
    std::ifstream pdf(dir.file("circle.pdf"), std::ios::binary);
    std::string head(5, '\0');
    pdf.read(head.data(), 5);
    EXPECT_EQ(head, "%PDF-");
    const auto rep = run(dir, "report " + std::to_string(j["session"].get<int>()) + " --json");
    ASSERT_EQ(rep.code, 0) << rep.err;
    const json r = json::parse(rep.out);
    for (const auto& run : r["circular"]["runs"]) {
        const auto& angles = run["polar"]["model_angle_deg"];
        ASSERT_GT(angles.size(), 300u) << "min and max per 0.5° of 180°";
        EXPECT_EQ(angles.size(), run["polar"]["model_deviation_um"].size());
    }
}

TEST(CircularDemo, YzPartialArcMeetsTheEmulatorsTruth) {
    TempDir dir;
    const json j = demo(dir, "--plane YZ");
    EXPECT_EQ(j["data_arc_deg"], 180.0);
    expect_truth_met(dir, j);
}

TEST(CircularDemo, ZxPartialArcMeetsTheEmulatorsTruth) {
    TempDir dir;
    expect_truth_met(dir, demo(dir, "--plane ZX --seed 2"));
}

TEST(CircularDemo, YzFullCircleMeetsTheEmulatorsTruth) {
    TempDir dir;
    expect_truth_met(dir, demo(dir, "--plane YZ --arc 360 --seed 4"));
}

TEST(CircularDemo, ADisconnectDuringARunRepeatsTheProgramAndTheResultIsStillRight) {
    TempDir dir;
    const json j = demo(dir, "--faults '{\"disconnect_at_s\": 20, \"disconnect_s\": 1.5}'");
    EXPECT_GE(j["attempts"].get<int>(), 2) << j.dump();
    EXPECT_GE(j["pauses"].get<int>(), 1);
    expect_truth_met(dir, j);
    const auto shown = run(dir, "export " + std::to_string(j["session"].get<int>()) + " --format json --out -");
    // Every run of the program is kept: the broken one marked, with why.
    const json ex = json::parse(shown.out, nullptr, false);
    ASSERT_TRUE(ex.is_object()) << shown.out.substr(0, 500);
    int bad = 0, good = 0;
    for (const auto& r : ex["results"]) {
        if (r["kind"] != "circular.attempt") continue;
        const json p = r["payload"].is_string() ? json::parse(r["payload"].get<std::string>()) : r["payload"];
        (p["good"].get<bool>() ? good : bad) += 1;
        if (!p["good"].get<bool>()) {
            EXPECT_NE(p["why"].get<std::string>().find("the instrument was lost"), std::string::npos);
        }
    }
    EXPECT_GE(bad, 1);
    EXPECT_EQ(good, 1);
}

TEST(CircularDemo, ReplayedFramesAreStoredOnce) {
    TempDir dir;
    const json j = demo(dir, "--plane XY --arc 180 --faults '{\"replay_frame_probability\": 0.02}'");
    EXPECT_GT(j["replayed_frames"].get<int>(), 0);
    EXPECT_EQ(j["gaps"].get<int>(), 0);  // the driver recognises a replay: no loss, no repeat
    EXPECT_EQ(j["attempts"], 1);
    expect_truth_met(dir, j);
}

TEST(CircularDemo, ALossyLinkLosesSamplesNotRuns) {
    // 1 % of the frames lost (13 samples each at 1 kHz) and a few corrupted bytes: the holes are short
    // and scattered, so the runs are used as they are and the diagnosis still meets its truth.
    TempDir dir;
    const json j = demo(dir,
                        "--plane XY --arc 360 --faults '{\"drop_frame_probability\": 0.01, "
                        "\"corrupt_byte_probability\": 2e-5}'");
    EXPECT_GT(j["gaps"].get<int>(), 0);
    EXPECT_GT(j["lost_samples"].get<int>(), 0);
    EXPECT_EQ(j["attempts"], 1);
    expect_truth_met(dir, j);
}

// ---- circle measure against `emulate --pty` in another process ----------------------------------------

namespace {

struct Emulate {
    pid_t pid = -1;
    int out = -1;
    std::string pty;
};

Emulate spawn(std::vector<std::string> args) {
    Emulate e;
    int fd[2];
    if (::pipe(fd) != 0) return e;
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    e.pid = ::fork();
    if (e.pid == 0) {
        ::dup2(fd[1], STDOUT_FILENO);
        ::close(fd[0]);
        ::execv(argv[0], argv.data());
        ::_exit(127);
    }
    ::close(fd[1]);
    e.out = fd[0];
    char c = 0;
    while (::read(e.out, &c, 1) == 1 && c != '\n') e.pty += c;
    return e;
}

/// The machine stands at 0° while the program starts at −20°: its rapid approach cuts inside the circle,
/// a fall the run finder must not take for the feed-in.
Emulate start_emulator(const TempDir& dir) {
    std::ofstream(dir.file("emu.json")) << R"({
      "instrument": {"calibrated_length_mm": 100, "noise_um": 0.15},
      "machine": {"start": {"X_mm": 100.8, "Y_mm": 0, "Z_mm": 0}},
      "program": {"file": "circle.nc"},
      "continuous": {"servo_lag_ms": {"X": 6, "Y": 4}, "backlash_um": {"X": 4, "Y": -2.5},
                     "squareness_um_per_m": {"XY": 40}}
    })";
    return spawn({BALLBAR_EXE, "emulate", "--pty", "--fast", "--config", dir.file("emu.json")});
}

void stop_emulator(Emulate& e) {
    if (e.pid > 0) {
        ::kill(e.pid, SIGINT);
        int st = 0;
        ::waitpid(e.pid, &st, 0);
    }
    if (e.out >= 0) ::close(e.out);
}

std::string plan(const TempDir& dir) {
    const auto p = run(dir, "circle plan --plane XY --radius 100 --feed 2000 --feed-in 0.8 --arc 180 --out '" +
                                dir.file("planned.nc") + "' --test-out '" + dir.file("test.json") + "'");
    EXPECT_EQ(p.code, 0) << p.err;
    return dir.file("test.json");
}

}  // namespace

TEST(CircleMeasure, TwoProcessesEmulatePtyAndMeasureStoreAnAnalysableSession) {
    TempDir dir;
    const std::string test = plan(dir);
    Emulate emu = start_emulator(dir);
    ASSERT_EQ(emu.pty.rfind("/dev/pts/", 0), 0u) << emu.pty;
    const auto m = run(dir, "circle measure --device serial:" + emu.pty + " --test '" + test + "' --program '" +
                                dir.file("circle.nc") + "' --machine '" + BALLBAR_TEST_DATA_DIR +
                                "/machines/tttrr.json' --non-interactive --json");
    stop_emulator(emu);
    ASSERT_EQ(m.code, 0) << m.err << m.out;
    // Stored under the machine tested (its file's name), not as "circular test".
    const auto listed = json::parse(run(dir, "sessions --json").out);
    ASSERT_EQ(listed.size(), 1u);
    EXPECT_EQ(listed[0]["machine"]["type"], "TTTRR") << listed.dump(1);
    EXPECT_NE(listed[0]["machine"]["name"], "circular test") << listed.dump(1);
    EXPECT_NE(m.out.find("\"event\":\"run_program\""), std::string::npos) << m.out;
    const auto done = json::parse(m.out.substr(m.out.rfind("{\"event\":\"done\"")));
    const auto diag = [&done](const char* key) {
        return ballbar::test::diagnostic(done["result"], key)["value"].get<double>();
    };
    EXPECT_NEAR(diag("backlash_x_um"), 4.0, 0.8) << done.dump();
    EXPECT_NEAR(diag("backlash_y_um"), -2.5, 0.5);
    EXPECT_NEAR(diag("squareness_um_per_m"), 40.0, 8.0);
    const std::string id = std::to_string(done["session"].get<int>());
    const auto an = run(dir, "circle analyze " + id + " --json");
    EXPECT_EQ(an.code, 0) << an.err;
}

// The defaults on a ±1 mm bar: the 1.5 mm feed-in would stand the bar outside its range. Not asked for,
// it is fitted (0.95 mm), said, written into the program and stored; asked for, it is refused.
TEST(CircleMeasure, TheDefaultFeedInIsFittedToTheBarsRangeAndAChosenOneIsRefused) {
    TempDir dir;
    Emulate emu = start_emulator(dir);
    ASSERT_EQ(emu.pty.rfind("/dev/pts/", 0), 0u) << emu.pty;
    const auto m = run(dir, "circle measure --device serial:" + emu.pty + " --feed 2000 --arc 180 --program '" +
                                dir.file("circle.nc") + "' --non-interactive --json");
    ASSERT_EQ(m.code, 0) << m.err << m.out;
    EXPECT_NE(m.out.find("Feed-in 0.95 mm instead of 1.50 mm"), std::string::npos) << m.out;
    std::stringstream program;
    program << std::ifstream(dir.file("circle.nc")).rdbuf();
    EXPECT_NE(program.str().find("feed-in 0.95 mm"), std::string::npos) << program.str();
    const auto done = json::parse(m.out.substr(m.out.rfind("{\"event\":\"done\"")));
    const std::string id = std::to_string(done["session"].get<int>());
    const auto header = run(dir, "export " + id + " --format trace --out -");
    EXPECT_NE(header.out.find("\"feed_in_mm\":0.95"), std::string::npos) << header.out.substr(0, 400);

    const auto chosen = run(
        dir, "circle measure --device serial:" + emu.pty + " --feed 2000 --arc 180 --feed-in 1.5 --non-interactive");
    stop_emulator(emu);
    EXPECT_EQ(chosen.code, 2) << chosen.err << chosen.out;
    EXPECT_NE(chosen.err.find("plan the test with --feed-in 0.95 or less"), std::string::npos) << chosen.err;
}

TEST(CircleMeasure, AFeedTooFastForTheInstrumentIsRefusedNamingTheHighestUsableFeed) {
    TempDir dir;
    const std::string test = plan(dir);
    Emulate emu = start_emulator(dir);
    // A 20 readings/s digital gauge is refused at 2000 mm/min; the bar at 1 kHz is not. The limit itself
    // comes from circular::sampling_limit (tested with the analysis); here: the procedure's refusal.
    std::ofstream(dir.file("long.json")) << R"({"kind": "circular", "plane": "XY", "radius_mm": 100.0,
      "centre_mm": [0, 0, 0], "feed_mm_min": 40000.0, "feed_in_mm": 0.8,
      "runs": [{"direction": "ccw", "start_deg": 0, "overshoot_deg": 45, "data_arc_deg": 360}]})";
    const auto m = run(
        dir, "circle measure --device serial:" + emu.pty + " --test '" + dir.file("long.json") + "' --non-interactive");
    stop_emulator(emu);
    EXPECT_EQ(m.code, 2) << m.err << m.out;
    EXPECT_NE(m.err.find("the highest usable feed is"), std::string::npos) << m.err;
}

TEST(CircleMeasure, ADigitalGaugeTooSlowForTheFeedIsRefusedNamingTheHighestUsableFeed) {
    TempDir dir;
    Emulate gauge = spawn({BALLBAR_EXE, "emulate", "--instrument", "sylvac", "--pty", "--rate", "20"});
    ASSERT_EQ(gauge.pty.rfind("/dev/pts/", 0), 0u) << gauge.pty;
    const auto m = run(dir, "circle measure --device sylvac:" + gauge.pty +
                                " --plane XY --radius 100 --feed 1000 --feed-in 0.8 --arc 180 --non-interactive");
    stop_emulator(gauge);
    EXPECT_EQ(m.code, 2) << m.err << m.out;
    std::smatch sm;
    ASSERT_TRUE(std::regex_search(m.err, sm, std::regex("the highest usable feed is ([0-9]+) mm/min"))) << m.err;
    // 20 readings/s and three samples on the 0.8 mm feed-in: about 60 · 20 · 0.8 / 3 = 320 mm/min.
    EXPECT_NEAR(std::stod(sm[1].str()), 320.0, 40.0) << m.err;
}

TEST(CircleMeasure, CtrlCDuringTheProgramStopsWithExit3AndTheSessionResumes) {
    TempDir dir;
    const std::string test = plan(dir);
    Emulate emu = start_emulator(dir);
    ASSERT_EQ(emu.pty.rfind("/dev/pts/", 0), 0u) << emu.pty;
    const std::string exe = BALLBAR_EXE;
    int fd[2];
    ASSERT_EQ(::pipe(fd), 0);
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::dup2(fd[1], STDOUT_FILENO);
        ::dup2(fd[1], STDERR_FILENO);
        ::close(fd[0]);
        const std::string db = dir.file("test.db"), dev = "serial:" + emu.pty, prog = dir.file("circle.nc");
        ::execl(exe.c_str(), exe.c_str(), "--db", db.c_str(), "circle", "measure", "--device", dev.c_str(), "--test",
                test.c_str(), "--program", prog.c_str(), "--non-interactive", static_cast<char*>(nullptr));
        ::_exit(127);
    }
    ::close(fd[1]);
    std::string out;
    std::array<char, 512> buf{};
    while (out.find("run 1 (ccw) captured") == std::string::npos) {
        const ssize_t n = ::read(fd[0], buf.data(), buf.size());
        if (n <= 0) break;
        out.append(buf.data(), static_cast<std::size_t>(n));
    }
    ::kill(pid, SIGINT);
    for (ssize_t n; (n = ::read(fd[0], buf.data(), buf.size())) > 0;)
        out.append(buf.data(), static_cast<std::size_t>(n));
    int st = 0;
    ::waitpid(pid, &st, 0);
    ::close(fd[0]);
    ASSERT_TRUE(WIFEXITED(st)) << out;
    EXPECT_EQ(WEXITSTATUS(st), 3) << out;
    std::smatch sm;
    ASSERT_TRUE(std::regex_search(out, sm, std::regex("Session ([0-9]+)"))) << out;
    const std::string id = sm[1].str();
    EXPECT_NE(out.find("circle measure --resume " + id), std::string::npos) << out;
    EXPECT_NE(out.find("--program " + dir.file("circle.nc")), std::string::npos) << out;
    const auto shown = run(dir, "sessions show " + id);
    EXPECT_NE(shown.out.find("circle measure --resume " + id + " --device URI"), std::string::npos) << shown.out;
    const auto r = run(dir, "circle measure --resume " + id + " --device serial:" + emu.pty + " --program '" +
                                dir.file("circle.nc") + "' --non-interactive");
    stop_emulator(emu);
    ASSERT_EQ(r.code, 0) << r.err << r.out;
    EXPECT_NE(r.out.find("completed"), std::string::npos) << r.out;
    const auto an = run(dir, "circle analyze " + id + " --json");
    ASSERT_EQ(an.code, 0) << an.err;
    EXPECT_NEAR(ballbar::test::diagnostic(json::parse(an.out), "backlash_x_um")["value"].get<double>(), 4.0, 0.8)
        << an.out;
}
