// SPDX-License-Identifier: MIT
// docs/cli.md's "JSON output: one vocabulary", checked on what every command with --json prints: the
// checker (json_vocabulary.hpp) is written from the documented rules, and first shown to catch each kind
// of violation, then run on each command's output.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_harness.hpp"
#include "json_vocabulary.hpp"

namespace fs = std::filesystem;
using ballbar::test::run;
using ballbar::test::TempDir;
using ballbar::test::vocabulary_violations;
using ballbar::test::vocabulary_violations_of_lines;
using nlohmann::json;

namespace {

const fs::path kMachines = fs::path(BALLBAR_TEST_DATA_DIR) / "machines";

std::string joined(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& e : v) s += "  " + e + "\n";
    return s;
}

/// The violations of one document printed by `what`, or of each line of a JSON-lines output.
void expect_vocabulary(const std::string& what, const std::string& out, bool lines = false) {
    std::vector<std::string> v;
    if (lines) {
        v = vocabulary_violations_of_lines(out);
    } else {
        const auto j = json::parse(out, nullptr, false);
        ASSERT_FALSE(j.is_discarded()) << what << " printed no JSON document:\n" << out.substr(0, 400);
        v = vocabulary_violations(j);
    }
    EXPECT_TRUE(v.empty()) << what << " breaks the vocabulary:\n" << joined(v);
}

}  // namespace

TEST(JsonVocabulary, TheCheckerFindsEachKindOfViolation) {
    const auto count = [](const char* text) { return vocabulary_violations(json::parse(text)).size(); };
    EXPECT_EQ(count(R"({"e_mm":[1,2,3],"e_mm_std":[0.1,0.1,0.1],"samples":3,"started_at":"2026-12-04T14:00:00.000Z",
                       "note":null,"diagnostics":[{"key":"backlash_x","unit":"um","value":3.0,"value_std":0.1}]})"),
              0u);
    EXPECT_EQ(count(R"({"note":""})"), 1u) << "a missing value is null, not \"\"";
    EXPECT_EQ(count(R"({"e_mm":1,"std":0.1})"), 1u) << "bare std";
    EXPECT_EQ(count(R"({"e_mm":1,"std_mm":0.1})"), 1u) << "std_ prefix";
    EXPECT_EQ(count(R"({"e_mm":1,"uncertainty_mm":0.1})"), 1u);
    EXPECT_EQ(count(R"({"e_mm":1,"stderr":0.1})"), 1u);
    EXPECT_EQ(count(R"({"f_mm_std":0.1})"), 1u) << "an uncertainty of nothing";
    EXPECT_EQ(count(R"({"unit":"µm"})"), 1u) << "non-ASCII unit";
    EXPECT_EQ(count(R"({"unit":"furlong"})"), 1u) << "a unit not in the list";
    EXPECT_EQ(count(R"({"samples":3.0})"), 1u) << "a count is an integer";
    EXPECT_EQ(count(R"({"started_at":"2026-12-04 14:00:00"})"), 1u) << "no T, no offset";
    EXPECT_EQ(count(R"({"tool-centre-point":1})"), 1u) << "a key with a hyphen";
    EXPECT_EQ(count(R"({"diagnostics":{"backlash_x_um":3}})"), 1u) << "diagnostics as a map";
    EXPECT_EQ(count(R"({"diagnostics":[{"key":"b","unit":"um","value":3}]})"), 1u) << "no value_std";
    EXPECT_EQ(count(R"({"a":[{"b":{"c":""}}]})"), 1u) << "found at any depth";
    EXPECT_EQ(vocabulary_violations_of_lines("{\"a\":1}\nSession 1: text\n").size(), 1u) << "a text line";
}

// Every command with --json, on one database the demos made: each output follows the vocabulary.
TEST(JsonVocabulary, EveryCommandsJsonFollowsIt) {
    TempDir dir;
    const auto ok = [&](const std::string& args, const std::string& input = "") {
        const auto r = run(dir, args, input);
        EXPECT_EQ(r.code, 0) << args << "\n" << r.err;
        return r.out;
    };
    expect_vocabulary("demo", ok("demo --json"));                                      // session 1
    expect_vocabulary("demo --instrument", ok("demo --instrument digimatic --json"));  // session 2
    expect_vocabulary("demo --compensate", ok("demo --compensate --json"));            // session 3
    expect_vocabulary("demo --test circular", ok("demo --test circular --json"));      // session 4
    expect_vocabulary("sessions", ok("sessions --json"));
    expect_vocabulary("sessions show (SSM)", ok("sessions show 1 --json"));
    expect_vocabulary("sessions show (circular)", ok("sessions show 4 --json"));
    expect_vocabulary("report (SSM)", ok("report 1 --json"));
    expect_vocabulary("report (circular)", ok("report 4 --json"));
    expect_vocabulary("circle analyze", ok("circle analyze 4 --json"));
    expect_vocabulary("identify", ok("identify 1 --json"));
    expect_vocabulary("discover", ok("discover 1 --json"));
    expect_vocabulary("report (identified)", ok("report 1 --json"));
    ok("export 1 --format readings --out '" + dir.file("r.csv") + "'");
    expect_vocabulary("import", ok("import '" + dir.file("r.csv") + "' --allow-duplicate --json"));

    std::ofstream(dir.file("part.nc")) << "G90 G21\nG1 X10 Y20 Z30 A5 C10 F1000\nG1 X20 A10 C20\nM2\n";
    expect_vocabulary("compensate", ok("compensate --model 1 --program '" + dir.file("part.nc") + "' --out '" +
                                       dir.file("c.nc") + "' --json"));
    expect_vocabulary("solve ssm", ok("solve ssm", R"({"socket_mm":[0,0,0],
        "points_mm":[[100,0,0],[0,100,0],[0,0,100],[70.7,70.7,0]], "delta_l_mm":[0.001,-0.002,0.0005,0.0001],
        "std_mm":0.0005})"));
    expect_vocabulary("solve orientation", ok("solve orientation", R"({"machine":"TTTRR", "a_pivot_mm":[0,0,0],
        "c_offset_mm":[0,0,-100], "socket_mm":[-49.275,-14.312,-77.777], "alpha_rad":0.2617993877991494,
        "gamma_rad":0.5235987755982988, "dV1_mm":[-0.0075,-0.0207,0.0117], "dV2_mm":[-0.0239,-0.0462,0.0174]})"));
    expect_vocabulary("solve compensate", ok("solve compensate", R"({"kinematics":"lei-hsu",
        "offsets_mm":{"Xw0":0,"Yw0":0,"Zw0":0,"Z3":100}, "u":[10,20,30,0.1,0.2],
        "dv":[0.001,0.002,0.003,0.0001,0.0,0.0]})"));
    expect_vocabulary("monitor", ok("monitor --device emulator: --seconds 0.3 --json"));
    expect_vocabulary("devices", ok("devices --json"));
    ok("machines add M-1 --machine '" + (kMachines / "tttrr.json").string() + "' --circularity-tolerance 12");
    expect_vocabulary("machines", ok("machines --json"));
    expect_vocabulary("machines show", ok("machines show M-1 --json"));
    ok("demo --asset M-1 --seed 3");
    expect_vocabulary("trend", ok("trend M-1 --json"));

    // The procedures' events, one document a line.
    std::string cfg = ballbar::test::slurp(kMachines / "tttrr-emulator.json");
    cfg.replace(cfg.find("PROGRAM"), 7, dir.file("m.nc"));
    cfg.replace(cfg.find('{'), 1, "{\"time\": \"simulated\",");
    std::ofstream(dir.file("emu.json")) << cfg;
    expect_vocabulary("measure",
                      ok("measure --json --non-interactive --device emulator:" + dir.file("emu.json") + " --machine " +
                         (kMachines / "tttrr.json").string() + " --plan " +
                         (kMachines / "tttrr-quick.plan.json").string() + " --program " + dir.file("m.nc")),
                      /*lines=*/true);
    ok("circle plan --feed-in 0.8 --test-out '" + dir.file("circle.json") + "' --out '" + dir.file("plan.nc") + "'");
    std::ofstream(dir.file("cemu.json"))
        << R"({"time": "simulated", "instrument": {"calibrated_length_mm": 100, "noise_um": 0.15},
              "machine": {"start": {"X_mm": 100.8, "Y_mm": 0, "Z_mm": 0}},
              "program": {"file": ")"
        << dir.file("circle.nc") << R"(", "start": "cycle_start"},
              "continuous": {"servo_lag_ms": {"X": 8, "Y": 5, "Z": 6.5}, "backlash_um": {"X": 3, "Y": -2},
                             "squareness_um_per_m": {"XY": 25}}})";
    expect_vocabulary(
        "circle measure",
        ok("circle measure --device emulator:" + dir.file("cemu.json") + " --test '" + dir.file("circle.json") +
           "' --program '" + dir.file("circle.nc") + "' --non-interactive --json"),
        /*lines=*/true);
}
