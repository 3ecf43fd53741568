// SPDX-License-Identifier: MIT
// Whole-process tests of `ballbar discover` on readings files written by another program
// (tests/data/readings/discovery_make.py: its own kinematics, other column order, extra columns,
// quoted fields, CRLF), and on a stored session: the JSON shape, the effect named, exit codes, and the
// result and the versioned model stored with the session.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "../analysis/independent_readings.hpp"
#include "cli_harness.hpp"

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

using namespace ballbar::test;

std::string data(const std::string& name) {
    return std::string(BALLBAR_TEST_DATA_DIR) + "/readings/" + name;
}

TEST(CliDiscover, NamesTheHiddenEffectInAThirdPartyFile) {
    TempDir dir;
    const CliRun r = run(dir, "discover --json '" + data("discovery_spindle_growth.csv") + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    json j;
    ASSERT_NO_THROW(j = json::parse(r.out)) << r.out;
    for (const char* key : {"base_model", "rms_initial_um", "steps", "rms_final_um", "confounded", "unidentifiable"})
        EXPECT_TRUE(j.contains(key)) << key;
    for (const char* key : {"noise_floor_um", "noise_source", "verdict", "verdict_before_search"})
        EXPECT_TRUE(j.contains(key)) << key;
    EXPECT_EQ(j["base_model"].front(), "Y0A");
    ASSERT_EQ(j["steps"].size(), 1u) << r.out;
    const json& st = j["steps"][0];
    EXPECT_EQ(st["effect"], "spindle_thermal_growth");
    EXPECT_EQ(st["unit"], "mm_per_h");
    EXPECT_EQ(st["criterion"], "F");
    EXPECT_EQ(st["explained_by"], "time");
    // The file's generator hid 0.025 mm/h of growth under 0.4 µm of noise.
    const double est = st["value"], sd = st["value_std"];
    EXPECT_LE(std::abs(est - 0.025), std::max(3 * sd, 0.0025)) << est << " ± " << sd;
    for (const char* key : {"effect", "iso", "value", "unit", "value_std", "rms_before_um", "rms_after_um", "criterion",
                            "statistic", "explained_by"})
        EXPECT_TRUE(st.contains(key)) << key;
    EXPECT_GT(j["rms_initial_um"].get<double>(), 2.0);
    EXPECT_LT(j["rms_final_um"].get<double>(), 0.5);
    EXPECT_LT(st["rms_after_um"].get<double>(), st["rms_before_um"].get<double>());
}

TEST(CliDiscover, NothingNamedWithoutAnEffectAndTheTableIsReadable) {
    TempDir dir;
    const CliRun j = run(dir, "discover --json '" + data("discovery_none.csv") + "'");
    ASSERT_EQ(j.code, 0) << j.err;
    EXPECT_TRUE(json::parse(j.out)["steps"].empty()) << j.out;
    const CliRun t = run(dir, "discover '" + data("discovery_spindle_growth.csv") + "'");
    ASSERT_EQ(t.code, 0) << t.err;
    EXPECT_NE(t.out.find("spindle_thermal_growth"), std::string::npos) << t.out;
    EXPECT_NE(t.out.find("final residual RMS"), std::string::npos) << t.out;
    EXPECT_NE(t.out.find("criterion:"), std::string::npos) << t.out;
}

TEST(CliDiscover, ModelOptionAndErrors) {
    TempDir dir;
    // A model without X0C: the location error is found among the candidates.
    const CliRun m =
        run(dir, "discover --json --model Y0A,Z0A,B0A,C0A,Y0C,A0C,B0C '" + data("discovery_none.csv") + "'");
    ASSERT_EQ(m.code, 0) << m.err;
    const json j = json::parse(m.out);
    ASSERT_FALSE(j["steps"].empty()) << m.out;
    EXPECT_EQ(j["steps"][0]["effect"], "location_X0C");
    EXPECT_EQ(j["steps"][0]["iso"], "X0C");

    const CliRun bad = run(dir, "discover --model X0C,nonsense '" + data("discovery_none.csv") + "'");
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.err.find("nonsense"), std::string::npos) << bad.err;

    const CliRun missing = run(dir, "discover /no/such/file.csv");
    EXPECT_EQ(missing.code, 2);
    EXPECT_NE(missing.err.find("/no/such/file.csv"), std::string::npos) << missing.err;

    std::ofstream(dir.path / "broken.csv") << "# ballbar-readings/1\n# machine: {\"type\":\"TTTRR\"}\nX_mm,Y_mm\n1,2\n";
    const CliRun broken = run(dir, "discover '" + (dir.path / "broken.csv").string() + "'");
    EXPECT_EQ(broken.code, 2);
    EXPECT_NE(broken.err.find("broken.csv"), std::string::npos) << broken.err;
}

TEST(CliDiscover, StoresResultAndModelHistoryWithTheSession) {
    TempDir dir;
    const CliRun imp = run(dir, "import '" + data("discovery_spindle_growth.csv") + "'");
    if (imp.code != 0) GTEST_SKIP() << "no `ballbar import` in this build: " << imp.err;
    const CliRun r = run(dir, "discover --json --save-model growth-test 1");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(json::parse(r.out)["steps"][0]["effect"], "spindle_thermal_growth");
    // The database holds the result and two model versions (base, + spindle growth).
    const std::string q = "sqlite3 '" + dir.file("test.db") + "' ";
    const std::string cmd =
        q + "\"select count(*) from results where kind='discovery';\" > '" + (dir.path / "q").string() + "' 2>&1";
    if (std::system(cmd.c_str()) != 0) GTEST_SKIP() << "no sqlite3 shell";
    EXPECT_EQ(slurp(dir.path / "q"), "1\n");
    const std::string cmd2 =
        q + "\"select count(*) from models where name='growth-test';\" > '" + (dir.path / "q").string() + "' 2>&1";
    ASSERT_EQ(std::system(cmd2.c_str()), 0);
    EXPECT_EQ(slurp(dir.path / "q"), "2\n");

    // The session's report draws the step from its own before/after residual trend.
    const CliRun rep = run(dir, "report 1 --json");
    ASSERT_EQ(rep.code, 0) << rep.err;
    const json disc = json::parse(rep.out)["discovery"];
    ASSERT_EQ(disc.size(), 1u) << rep.out;
    EXPECT_TRUE(disc[0]["own_step"].get<bool>());
    EXPECT_EQ(disc[0]["x"].size(), 8u);
    double before = 0, after = 0;
    for (const auto& v : disc[0]["before_um"]) before = std::max(before, std::abs(v.get<double>()));
    for (const auto& v : disc[0]["after_um"]) after = std::max(after, std::abs(v.get<double>()));
    EXPECT_GT(before, 3 * after) << "the growth's trend is gone after the step";
}

TEST(CliDiscover, StructureOutsideTheLibraryIsFoundNeverCalledNoise) {
    // The case: a TTTRR whose C axis has a once-per-revolution angular error of 80 µrad,
    // 0.3 µm of noise given as n/std_mm, written by the independent generator.
    TempDir dir;
    indep::Scenario sc = indep::make_scenario("TTTRR", "angular", false, 5);
    sc.m.angular_amp_rad = 80e-6;
    sc.m.angular_phase_rad = 40 * indep::kDeg;
    std::mt19937_64 rng(5);
    const std::string file = dir.file("c_axis.csv");
    std::ofstream(file) << indep::generate(sc.m, rng).text();
    const CliRun r = run(dir, "discover --json '" + file + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const json j = json::parse(r.out);
    EXPECT_NEAR(j["noise_floor_um"].get<double>(), 0.3, 0.03);
    EXPECT_EQ(j["noise_source"], "within-point spread");
    EXPECT_EQ(j["verdict_before_search"]["result"], "unexplained structure");
    EXPECT_EQ(j["verdict_before_search"]["statistic"], "chi-square");
    EXPECT_EQ(j["verdict"]["result"], "consistent with noise");
    ASSERT_FALSE(j["steps"].empty()) << r.out;
    const json& st = j["steps"].back();
    EXPECT_EQ(st["kind"], "empirical");
    EXPECT_EQ(st["effect"], "C_angular");
    EXPECT_EQ(st["explained_by"], "C");
    EXPECT_NE(st["where"].get<std::string>().find("once per revolution"), std::string::npos) << st["where"];
    bool h1_cos = false;  // the learned terms: a list of {name, unit, value, value_std}
    for (const auto& t : st["terms"]) h1_cos = h1_cos || (t["name"] == "C_angular_h1_cos" && t.contains("value_std"));
    EXPECT_TRUE(h1_cos) << st["terms"].dump();
    EXPECT_LE(j["rms_final_um"].get<double>(), 1.5 * j["noise_floor_um"].get<double>());

    // A floor the residual cannot reach: the verdict stays structure, and the table never says noise.
    const CliRun low = run(dir, "discover --noise-um 0.1 '" + file + "'");
    ASSERT_EQ(low.code, 0) << low.err;
    EXPECT_NE(low.out.find("UNEXPLAINED STRUCTURE"), std::string::npos) << low.out;
    EXPECT_EQ(low.out.find("final: residual RMS 0.2"), low.out.find("final: residual RMS 0.2")) << low.out;
    EXPECT_EQ(low.out.find("is noise"), std::string::npos) << low.out;
    const CliRun bad = run(dir, "discover --noise-um -1 '" + file + "'");
    EXPECT_EQ(bad.code, 2) << bad.out;
}

}  // namespace
