// SPDX-License-Identifier: MIT
// The real `ballbar` binary on a circular test from the independent generator: import, analyze (text,
// JSON keys, stored result, tolerance, controller), export --format trace, plan, refusals.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <random>

#include "../app/cli_harness.hpp"
#include "diagnostic_json.hpp"
#include "trace_generator.hpp"

namespace {

using ballbar::test::run;
using ballbar::test::TempDir;
using namespace ballbar::testgen;

std::string write_trace(const TempDir& dir) {
    std::mt19937_64 rng(99);
    GenSpec s;
    s.radius_mm = 100.0, s.feed_mm_min = 2000.0, s.sample_hz = 400.0, s.noise_um = 0.2;
    s.runs = {{true, 0, 45, 360}, {false, 90, 45, 360}};
    GenEffects fx;
    fx.backlash_um = {8.0, 5.0};
    fx.squareness_um_per_m = 30.0;
    const std::string path = dir.file("t.csv");
    std::ofstream(path) << to_file(s, generate(s, fx, rng));
    return path;
}

TEST(CircularCli, ImportAnalyzeStoreExport) {
    TempDir dir;
    const std::string trace = write_trace(dir);
    const auto imp = run(dir, "import '" + trace + "' --json");
    ASSERT_EQ(imp.code, 0) << imp.err;
    const auto id = nlohmann::json::parse(imp.out)["session"].get<int>();
    const auto an = run(dir, "circle analyze " + std::to_string(id) + " --json --tolerance 50");
    ASSERT_EQ(an.code, 0) << an.err;
    const auto j = nlohmann::json::parse(an.out);
    ASSERT_EQ(j["runs"].size(), 2u);
    EXPECT_EQ(j["runs"][0]["direction"], "ccw");
    EXPECT_GT(j["runs"][0]["circularity_um"].get<double>(), 0.0);
    EXPECT_TRUE(j["bidirectional_circularity_um"].is_number());
    EXPECT_TRUE(j["radial_deviation_um"]["max"].is_number());
    EXPECT_NEAR(ballbar::test::diagnostic(j, "backlash_x_um")["value"].get<double>(), 8.0, 1.6);
    EXPECT_NEAR(ballbar::test::diagnostic(j, "backlash_y_um")["value"].get<double>(), 5.0, 1.0);
    EXPECT_NEAR(ballbar::test::diagnostic(j, "squareness_um_per_m")["value"].get<double>(), 30.0, 6.0);
    EXPECT_TRUE(ballbar::test::diagnostic(j, "backlash_x_um")["value_std"].is_number());
    EXPECT_TRUE(ballbar::test::diagnostic(j, "backlash_x_um")["share_percent"].is_number());
    EXPECT_TRUE(j["tolerance"]["pass"].get<bool>());
    const auto show = run(dir, "sessions show " + std::to_string(id) + " --json");
    EXPECT_NE(show.out.find("circular"), std::string::npos);

    const auto fail = run(dir, "circle analyze '" + trace + "' --tolerance 1");
    EXPECT_EQ(fail.code, 1);
    EXPECT_NE(fail.out.find("FAIL"), std::string::npos);

    const auto ctl = run(dir, "circle analyze '" + trace + "' --controller linuxcnc");
    EXPECT_NE(ctl.out.find("[JOINT_0] BACKLASH = 0.00"), std::string::npos) << ctl.out;
    const auto m425 = run(dir, "circle analyze '" + trace + "' --controller marlin --json");
    EXPECT_NE(m425.out.find("M425 X0.00"), std::string::npos);

    const auto ex = run(dir, "export " + std::to_string(id) + " --format trace --out '" + dir.file("back.csv") + "'");
    ASSERT_EQ(ex.code, 0) << ex.err;
    const auto again = run(dir, "circle analyze '" + dir.file("back.csv") + "' --json");
    ASSERT_EQ(again.code, 0) << again.err;
    EXPECT_NEAR(nlohmann::json::parse(again.out)["runs"][0]["circularity_um"].get<double>(),
                j["runs"][0]["circularity_um"].get<double>(), 0.01);
}

TEST(CircularCli, RefusesAnInvalidTraceWithLineAndProblem) {
    TempDir dir;
    const std::string bad = std::string(BALLBAR_TEST_DATA_DIR) + "/traces/invalid/non_numeric.csv";
    const auto imp = run(dir, "import '" + bad + "'");
    EXPECT_EQ(imp.code, 2);
    EXPECT_NE(imp.err.find("line 5"), std::string::npos) << imp.err;
    const auto an = run(dir, "circle analyze '" + bad + "'");
    EXPECT_EQ(an.code, 2);
    const auto list = run(dir, "sessions --json");
    EXPECT_EQ(list.out.find("circular"), std::string::npos);
}

TEST(CircularCli, PlanWritesBothDialectsAndChecksTravel) {
    TempDir dir;
    const auto fanuc = run(dir, "circle plan --plane XY --radius 100 --feed 1000");
    ASSERT_EQ(fanuc.code, 0) << fanuc.err;
    EXPECT_NE(fanuc.out.find("G17"), std::string::npos);
    EXPECT_NE(fanuc.out.find("G3 X"), std::string::npos);
    EXPECT_NE(fanuc.out.find("G2 X"), std::string::npos);
    EXPECT_NE(fanuc.out.find("G4 P1000"), std::string::npos);
    const auto lcnc =
        run(dir, "circle plan --plane YZ --arc 180 --dialect linuxcnc --test-out '" + dir.file("t.json") + "'");
    ASSERT_EQ(lcnc.code, 0) << lcnc.err;
    EXPECT_NE(lcnc.out.find("G19"), std::string::npos);
    EXPECT_NE(lcnc.out.find("G4 P1\n"), std::string::npos);
    const auto stored = run(dir, "circle plan --plane XY --store --out '" + dir.file("p.nc") + "'");
    ASSERT_EQ(stored.code, 0) << stored.err;
    EXPECT_NE(stored.err.find("planned session 1"), std::string::npos) << stored.err;
    const auto show = run(dir, "sessions show 1 --json");
    EXPECT_NE(show.out.find("radius_mm"), std::string::npos) << show.out;
    const auto header = nlohmann::json::parse(ballbar::test::slurp(dir.file("t.json")));
    EXPECT_EQ(header["runs"][1]["start_deg"].get<double>(), 200.0);
    const std::string machine = std::string(BALLBAR_TEST_DATA_DIR) + "/machines/tttrr.json";  // X ±400 mm
    EXPECT_EQ(run(dir, "circle plan --radius 300 --machine '" + machine + "'").code, 0);
    const auto out = run(dir, "circle plan --radius 450 --machine '" + machine + "'");
    EXPECT_EQ(out.code, 2);
    EXPECT_NE(out.err.find("travel of X"), std::string::npos) << out.err;
}

// A slow gauge (issue 14): `--rate` refuses a feed whose samples lie too far apart along the path,
// naming the highest usable feed; the feed-in (three samples on 1.5 mm: 0.5 mm) binds by default, the
// cyclic-error pitch (two samples per 2 mm: 1 mm) with a long feed-in.
TEST(CircularCli, PlanRefusesAFeedTooFastForTheReadingRate) {
    TempDir dir;
    const auto fast = run(dir, "circle plan --radius 100 --feed 1000 --rate 20");
    EXPECT_EQ(fast.code, 2);
    EXPECT_TRUE(fast.out.empty()) << "no program for a refused feed";
    EXPECT_NE(fast.err.find("ballbar: error: --feed 1000 mm/min is too fast for 20 readings/s"), std::string::npos)
        << fast.err;
    EXPECT_NE(fast.err.find("0.8333 mm apart"), std::string::npos) << fast.err;
    EXPECT_NE(fast.err.find("1.5 mm feed-in"), std::string::npos) << fast.err;
    EXPECT_NE(fast.err.find("the highest usable feed is 600 mm/min"), std::string::npos) << fast.err;

    const auto limit = run(dir, "circle plan --radius 100 --feed 600 --rate 20");
    EXPECT_EQ(limit.code, 0) << limit.err;
    EXPECT_NE(limit.out.find("G3 X"), std::string::npos);
    EXPECT_NE(limit.err.find("the highest usable feed is 600 mm/min"), std::string::npos) << limit.err;
    EXPECT_EQ(run(dir, "circle plan --feed 601 --rate 20").code, 2);
    EXPECT_EQ(run(dir, "circle plan --feed 1000 --rate 33").code, 2);  // 990 mm/min at most
    EXPECT_EQ(run(dir, "circle plan --feed 1000 --rate 34").code, 0);  // 1020 mm/min at most
    EXPECT_EQ(run(dir, "circle plan --feed 1000").code, 0) << "no rate given: no check";

    const auto pitch = run(dir, "circle plan --feed 1300 --feed-in 6 --rate 20");
    EXPECT_EQ(pitch.code, 2);
    EXPECT_NE(pitch.err.find("2 mm cyclic-error pitch"), std::string::npos) << pitch.err;
    EXPECT_NE(pitch.err.find("the highest usable feed is 1200 mm/min"), std::string::npos) << pitch.err;

    for (const char* bad : {"0", "-5", "abc"}) {
        const auto r = run(dir, std::string("circle plan --rate ") + bad);
        EXPECT_EQ(r.code, 2) << bad;
        EXPECT_NE(r.err.find("--rate"), std::string::npos) << bad << ": " << r.err;
    }
}

// The highest usable feed really is usable: a 20 readings/s trace at 600 mm/min is analysed, both runs
// found, the injected backlash recovered.
TEST(CircularCli, TheHighestUsableFeedOfASlowGaugeIsAnalysed) {
    TempDir dir;
    std::mt19937_64 rng(7);
    GenSpec s;
    s.radius_mm = 100.0, s.feed_mm_min = 600.0, s.sample_hz = 20.0, s.noise_um = 0.2;
    s.runs = {{true, 0, 45, 360}, {false, 90, 45, 360}};
    GenEffects fx;
    fx.backlash_um = {8.0, 5.0};
    const std::string path = dir.file("slow.csv");
    std::ofstream(path) << to_file(s, generate(s, fx, rng));
    const auto an = run(dir, "circle analyze '" + path + "' --json");
    ASSERT_EQ(an.code, 0) << an.err;
    const auto j = nlohmann::json::parse(an.out);
    ASSERT_EQ(j["runs"].size(), 2u);
    EXPECT_NEAR(ballbar::test::diagnostic(j, "backlash_x_um")["value"].get<double>(), 8.0, 1.6);
    EXPECT_NEAR(ballbar::test::diagnostic(j, "backlash_y_um")["value"].get<double>(), 5.0, 1.0);
}

}  // namespace
