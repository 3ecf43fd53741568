// SPDX-License-Identifier: MIT
// `ballbar machines add|list|show|edit` and `--asset` (docs/fleet.md): a machine registered under its
// asset id is measured, listed and trended under it; what the registry refuses leaves the database as
// it was.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_harness.hpp"
#include "json_vocabulary.hpp"

namespace {

namespace fs = std::filesystem;
using ballbar::test::run;
using ballbar::test::slurp;
using ballbar::test::TempDir;
using nlohmann::json;

const fs::path kMachineDir = fs::path(BALLBAR_TEST_DATA_DIR) / "machines";

std::string machine_arg(const char* file) {
    return " --machine '" + (kMachineDir / file).string() + "'";
}

TEST(CliMachines, ARegisteredMachineIsMeasuredListedAndTrendedUnderItsAssetId) {
    TempDir d;
    const auto none = run(d, "machines --json");
    EXPECT_EQ(none.code, 0) << none.err;
    EXPECT_EQ(json::parse(none.out), json::array());
    EXPECT_FALSE(fs::exists(d.file("test.db"))) << "listing creates no database";

    const auto add = run(d, "machines add M-0042" + machine_arg("tttrr.json") +
                                " --name 'DMU 50' --location 'hall 2' --location-tolerance 30 --json");
    ASSERT_EQ(add.code, 0) << add.err;
    const json m = json::parse(add.out);
    EXPECT_EQ(m.at("asset_id"), "M-0042");
    EXPECT_EQ(m.at("name"), "DMU 50");
    EXPECT_EQ(m.at("type"), "TTTRR");
    EXPECT_EQ(m.at("location"), "hall 2");
    EXPECT_EQ(m.at("sessions"), 0);
    EXPECT_EQ(m.at("tolerances").at("location_um"), 30.0);
    EXPECT_TRUE(m.at("tolerances").at("circularity_um").is_null());
    EXPECT_EQ(m.at("uuid").get<std::string>().size(), 36u);
    EXPECT_TRUE(ballbar::test::vocabulary_violations(m).empty());

    // An SSM on the emulator (simulated time) of the registered machine: its geometry, its tolerance.
    std::string cfg = slurp(kMachineDir / "tttrr-emulator.json");
    cfg.replace(cfg.find("PROGRAM"), 7, d.file("m.nc"));
    cfg.replace(cfg.find('{'), 1, "{\"time\": \"simulated\",");
    std::ofstream(d.file("emu.json")) << cfg;
    const auto measured =
        run(d, "measure --non-interactive --asset M-0042 --device emulator:" + d.file("emu.json") + " --plan '" +
                   (kMachineDir / "tttrr-quick.plan.json").string() + "' --program " + d.file("m.nc"));
    ASSERT_EQ(measured.code, 0) << measured.err << measured.out;
    EXPECT_NE(measured.out.find("FAIL"), std::string::npos) << "the registered 30 µm judges: " << measured.out;

    const json sessions = json::parse(run(d, "sessions --json").out);
    ASSERT_EQ(sessions.size(), 1u);
    EXPECT_EQ(sessions[0].at("machine_asset_id"), "M-0042");
    EXPECT_EQ(sessions[0].at("machine").at("name"), "DMU 50");
    const auto trend = run(d, "sessions trend M-0042 --json");
    ASSERT_EQ(trend.code, 0) << trend.err;
    EXPECT_EQ(json::parse(trend.out).at("points").size(), 1u);
    const json listed = json::parse(run(d, "machines list --json").out);
    ASSERT_EQ(listed.size(), 1u);
    EXPECT_EQ(listed[0].at("sessions"), 1);
    const auto shown = run(d, "machines show M-0042");
    EXPECT_EQ(shown.code, 0) << shown.err;
    EXPECT_NE(shown.out.find("hall 2"), std::string::npos) << shown.out;

    // The demo on a registered machine of another type.
    ASSERT_EQ(run(d, "machines add R-7" + machine_arg("rrttt.json")).code, 0);
    const auto demo = run(d, "demo --asset R-7 --json");
    ASSERT_EQ(demo.code, 0) << demo.err;
    EXPECT_EQ(json::parse(demo.out).at("machine"), "RRTTT");
    EXPECT_EQ(json::parse(run(d, "machines show R-7 --json").out).at("sessions"), 1);
}

TEST(CliMachines, WhatTheRegistryRefusesNamesTheReasonExitsTwoAndChangesNothing) {
    TempDir d;
    ASSERT_EQ(run(d, "machines add M-1" + machine_arg("tttrr.json")).code, 0);
    const std::string before = slurp(d.file("test.db"));

    const auto twice = run(d, "machines add M-1" + machine_arg("tttrr.json"));
    EXPECT_EQ(twice.code, 2);
    EXPECT_NE(twice.err.find("M-1 is registered already"), std::string::npos) << twice.err;

    const auto unknown = run(d, "machines show M-2");
    EXPECT_EQ(unknown.code, 2);
    EXPECT_NE(unknown.err.find("there are M-1"), std::string::npos) << unknown.err;

    const auto no_file = run(d, "machines add M-3");
    EXPECT_EQ(no_file.code, 2);

    std::ofstream(d.file("bad.json")) << R"({"format": "ballbar-machine/1", "type": "XYZ"})";
    const auto bad = run(d, "machines add M-3 --machine '" + d.file("bad.json") + "'");
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.err.find("bad.json"), std::string::npos) << bad.err;

    const auto both =
        run(d, "measure --asset M-1" + machine_arg("tttrr.json") + " --device emulator: --non-interactive");
    EXPECT_EQ(both.code, 2);
    EXPECT_NE(both.err.find("--machine and --asset"), std::string::npos) << both.err;
    const auto unknown_asset = run(d, "demo --asset M-9");
    EXPECT_EQ(unknown_asset.code, 2);
    EXPECT_NE(unknown_asset.err.find("no machine \"M-9\""), std::string::npos) << unknown_asset.err;
    EXPECT_EQ(slurp(d.file("test.db")), before) << "a refusal writes nothing";

    // The geometry of a machine with sessions stays: its sessions' analysis rests on it.
    ASSERT_EQ(run(d, "demo --asset M-1").code, 0);
    const auto regeometry = run(d, "machines edit M-1" + machine_arg("rrttt.json"));
    EXPECT_EQ(regeometry.code, 2);
    EXPECT_NE(regeometry.err.find("register"), std::string::npos) << regeometry.err;
    EXPECT_EQ(json::parse(run(d, "machines show M-1 --json").out).at("type"), "TTTRR");
    const auto located = run(d, "machines edit M-1 --location 'hall 5' --circularity-tolerance 8 --json");
    ASSERT_EQ(located.code, 0) << located.err;
    EXPECT_EQ(json::parse(located.out).at("location"), "hall 5");
    EXPECT_EQ(json::parse(located.out).at("tolerances").at("circularity_um"), 8.0);
    EXPECT_FALSE(json::parse(located.out).at("updated_at").is_null());
}

}  // namespace
