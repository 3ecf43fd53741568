// SPDX-License-Identifier: MIT
// The terminal's prompts as an operator meets them (a pseudo-terminal, `ballbar measure` on the emulator):
// "no" at "Ready?" means not yet, keys typed while the machine runs answer nothing, an answer that could
// be two options is refused, and abort at "Press Enter…" is asked twice and leaves the session resumable,
// with a resume line that works as copied.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "../scratch_dir.hpp"
#include "pty_session.hpp"

namespace {

namespace fs = std::filesystem;
using ballbar::test::PtySession;
using namespace std::chrono_literals;

/// `measure`'s arguments on the emulated TTTRR with the one-test plan; `realtime`: the emulator on the
/// wall clock (the machine takes its seconds, so keys can be typed while it runs).
std::vector<std::string> prompts_measure_args(const ballbar::test::ScratchDir& dir, bool realtime) {
    const fs::path data = fs::path(BALLBAR_TEST_DATA_DIR) / "machines";
    std::ifstream in(data / "tttrr-emulator.json");
    std::stringstream cfg;
    cfg << in.rdbuf();
    std::string text = cfg.str();
    const std::string program = dir.file("session.nc");
    text.replace(text.find("PROGRAM"), 7, program);
    if (!realtime) text.replace(text.find('{'), 1, "{\"time\": \"simulated\",");
    std::ofstream(dir.file("emulator.json")) << text;
    return {"--db",
            dir.file("prompts.db"),
            "measure",
            "--device",
            "emulator:" + dir.file("emulator.json"),
            "--machine",
            (data / "tttrr.json").string(),
            "--plan",
            (data / "tttrr-quick.plan.json").string(),
            "--program",
            program};
}

constexpr const char* kReady = "[yes / not yet / abort] ";

TEST(CliPrompts, NoAtReadyIsNotYetTypedAheadKeysAnswerNothingAndAnAmbiguousAnswerIsRefused) {
    ballbar::test::ScratchDir dir("prompts");
    PtySession t(prompts_measure_args(dir, true));
    ASSERT_TRUE(t.wait_for("calibrator")) << t.screen;
    ASSERT_TRUE(t.wait_for(kReady)) << t.screen;
    t.type("no\n");  // "no" at Ready?: not yet, and asked again
    ASSERT_TRUE(t.wait_for("Not yet: take your time")) << t.screen;
    t.type("yes\n");
    ASSERT_TRUE(t.wait_for(kReady)) << t.screen;  // the set-up
    t.type("yes\n");
    ASSERT_TRUE(t.wait_for("start it on the machine")) << t.screen;
    // Keys pressed while the machine moves to the bar's mount: a `y` and an Enter for no question.
    t.type("y\n\n");
    ASSERT_TRUE(t.wait_for("Program stop (M0): mount the bar", 60s)) << t.screen;
    ASSERT_TRUE(t.wait_for("when you have pressed cycle start (or type abort). ")) << t.screen;
    t.settle(500);
    EXPECT_EQ(t.unmatched().find("Only Enter"), std::string::npos) << "the typed-ahead keys answered: " << t.screen;
    t.type("\n");
    // The points are measured; a stray `y` while they are is discarded at the review.
    ASSERT_TRUE(t.wait_for(", σ ", 60s)) << t.screen;
    t.type("y\n");
    ASSERT_TRUE(t.wait_for("Answer accept, measure-again or abort: ", 90s)) << t.screen;
    t.settle(500);
    EXPECT_EQ(t.unmatched().find("Please answer"), std::string::npos) << t.screen;
    EXPECT_EQ(t.unmatched().find("completed"), std::string::npos) << "accepted by a key typed before: " << t.screen;
    t.type("a\n");  // accept or abort?
    ASSERT_TRUE(t.wait_for("\"a\" could be accept or abort: type more of the word")) << t.screen;
    t.type("acc\n");
    EXPECT_EQ(t.exit_code(), 0) << t.screen;
    EXPECT_NE(t.screen.find("completed"), std::string::npos) << t.screen;
}

TEST(CliPrompts, AbortAtPressEnterIsAskedTwiceStopsResumableAndTheResumeLineWorksAsCopied) {
    ballbar::test::ScratchDir dir("prompts");
    PtySession t(prompts_measure_args(dir, false));
    ASSERT_TRUE(t.wait_for(kReady)) << t.screen;
    t.type("yes\n");
    ASSERT_TRUE(t.wait_for(kReady)) << t.screen;
    t.type("yes\n");
    ASSERT_TRUE(t.wait_for("when you have pressed cycle start (or type abort). ")) << t.screen;
    t.type("abort\n");  // not taken for Enter
    ASSERT_TRUE(t.wait_for("Abort the session? What it measured stays stored and it can be resumed. [yes/no] "))
        << t.screen;
    t.type("no\n");
    ASSERT_TRUE(t.wait_for("Not aborted.")) << t.screen;
    t.type("help\n");
    ASSERT_TRUE(t.wait_for("abort (or quit) stops the session")) << t.screen;
    t.type("quit\n");
    ASSERT_TRUE(t.wait_for("Abort the session?")) << t.screen;
    t.type("yes\n");
    EXPECT_EQ(t.exit_code(), 3) << t.screen;  // interrupted, as Ctrl-C
    // The resume line names the database and the program given, and works as copied (from elsewhere).
    std::smatch m;
    ASSERT_TRUE(std::regex_search(t.screen, m, std::regex("Continue it with: ballbar ([^\r\n]+)"))) << t.screen;
    const std::string line = m[1].str();
    EXPECT_NE(line.find("--db " + dir.file("prompts.db")), std::string::npos) << line;
    EXPECT_NE(line.find("--program " + dir.file("session.nc")), std::string::npos) << line;
    const std::string sessions = dir.file("sessions.json");
    const std::string again = "cd / && " + std::string(BALLBAR_EXE) + " " + line + " --non-interactive > " +
                              dir.file("resumed.txt") + " 2>&1";
    EXPECT_EQ(std::system(again.c_str()), 0) << line;
    const std::string cmd =
        std::string(BALLBAR_EXE) + " --db " + dir.file("prompts.db") + " sessions --json > " + sessions;
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    std::ifstream in(sessions);
    const auto list = nlohmann::json::parse(in);
    ASSERT_EQ(list.size(), 1u);
    EXPECT_EQ(list[0]["state"], "completed") << "resumed to its end: " << list.dump(1);
}

}  // namespace
