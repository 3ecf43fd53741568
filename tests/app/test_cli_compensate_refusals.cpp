// SPDX-License-Identifier: MIT
// `ballbar compensate` never exits 0 with nonsense (issue 17): refusals exit 2 with the line and the
// reason and leave --out as it was; singular poses give no NaN and no added turns.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_harness.hpp"

using nlohmann::json;
using namespace ballbar::test;
namespace fs = std::filesystem;

namespace {

std::string model(const std::string& type, const json& params) {
    json m{{"format", "ballbar-model/1"},
           {"machine",
            {{"type", type},
             {"name", "refusals"},
             {"a_pivot_mm", {0, 0, 0}},
             {"c_offset_mm", {0, 0, -100}},
             {"tool_ball_mm", type == "TTTRR" ? json{0, 0, 0} : json{0, 0, -150}}}},
           {"params", params}};
    return m.dump();
}
const json kSeedLike{{"Y0A", 0.025}, {"Z0A", -0.018}, {"X0C", 0.035}, {"Y0C", -0.022}, {"A0C", 5e-5}, {"B0C", -3e-5}};

struct Fixture {
    TempDir d;
    Fixture() {
        std::ofstream(d.path / "model.json") << model("TTTRR", kSeedLike);
        std::ofstream(d.path / "keep.nc") << "precious\n";
    }
    CliRun compensate(const std::string& program, const std::string& flags = "", const std::string& name = "in.nc") {
        std::ofstream(d.path / name) << program;
        return run(d, "compensate --model '" + d.file("model.json") + "' --program '" + d.file(name) + "' --out '" +
                          d.file("keep.nc") + "' " + flags);
    }
    /// Exit 2, the message names `what` (and the line when given), --out untouched.
    void expect_refused(const CliRun& r, const std::string& what, int line = 0) {
        EXPECT_EQ(r.code, 2) << r.err;
        EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
        if (line > 0) {
            EXPECT_NE(r.err.find("line " + std::to_string(line) + ":"), std::string::npos) << r.err;
        }
        EXPECT_EQ(slurp(d.path / "keep.nc"), "precious\n");
        for (const auto& e : fs::directory_iterator(d.path))  // no temporary file (keep.nc.XXXXXXXX.part) left
            EXPECT_NE(e.path().extension(), ".part") << e.path();
    }
};

const std::string kOk = "%\nG90\nG1 X50 Y0 Z30 A30 C0 F1000\nG1 X0 Y50 A30 C90\nM30\n%\n";

TEST(CliCompensateRefuses, MalformedProgramsWithTheLineAndTheReason) {
    Fixture f;
    f.expect_refused(f.compensate("%\nG1 X28.5 X1000 Y0 Z0 A30 C0 F100\nM30\n%\n"), "word X twice", 2);
    f.expect_refused(f.compensate("%\nG1 X" + std::string(400, '9') + " Y0 Z0 A30 C0 F100\nM30\n%\n"), "out-of-range",
                     2);
    f.expect_refused(f.compensate("%\nG1 X1e5 Y0 Z0 A30 C0 F100\nM30\n%\n"), "malformed or out-of-range number '1e5'",
                     2);
    f.expect_refused(f.compensate("%\nG1 Xnan Y0 Z0 A30 C0 F100\nM30\n%\n"), "unknown word", 2);
    f.expect_refused(f.compensate("%\n#1=5\nG1 X#1 Y0 Z0 A30 C0 F100\nM30\n%\n"), "controller's interpreter", 2);
    f.expect_refused(f.compensate("G1 X[1+2] Y0 Z0 A30 C0 F100\nM2\n", "--dialect linuxcnc"), "expand", 1);
    f.expect_refused(f.compensate("o100 sub\nG1 X1 Y0 Z0 A30 C0 F100\no100 endsub\nM2\n", "--dialect linuxcnc"),
                     "O-word", 1);
    f.expect_refused(f.compensate("%\nG54 G1 X1 Y0 Z0 A30 C0 F100\nM30\n%\n"), "--offsets", 2);
    f.expect_refused(f.compensate("%\nG41 D1 G1 X1 Y0 Z0 A30 C0 F100\nM30\n%\n"), "G40", 2);
    f.expect_refused(f.compensate("%\nG1 X1 F100\nM30\n%\n"), "name every axis", 2);
}

TEST(CliCompensateRefuses, ProgramsWithoutAnEndUnlessAllowed) {
    Fixture f;
    const std::string truncated = "%\nG90\nG1 X50 Y0 Z30 A30 C0 F1000\nG1 X0 Y50 A30 C90\n";
    f.expect_refused(f.compensate(truncated), "no end");
    const CliRun ok = f.compensate(truncated, "--allow-truncated");
    ASSERT_EQ(ok.code, 0) << ok.err;
    const std::string out = slurp(f.d.path / "keep.nc");
    EXPECT_EQ(out.find("M30"), std::string::npos) << "nothing is added to a truncated program:\n" << out;
    EXPECT_NE(ok.out.find("no end"), std::string::npos) << ok.out;
}

TEST(CliCompensateRefuses, EmptyProgramsDirectoriesAndOutputOverAnInput) {
    Fixture f;
    f.expect_refused(f.compensate(""), "empty program");
    f.expect_refused(f.compensate("%\n(only a comment)\n%\n"), "empty program");
    const CliRun dir = run(f.d, "compensate --model '" + f.d.file("model.json") + "' --program '" + f.d.path.string() +
                                    "' --out '" + f.d.file("keep.nc") + "'");
    f.expect_refused(dir, "is a directory");
    std::ofstream(f.d.path / "in.nc") << kOk;
    for (const std::string& victim : {f.d.file("in.nc"), f.d.file("model.json"), f.d.file("test.db")}) {
        if (!fs::exists(victim)) std::ofstream(victim) << "x";
        const std::string before = slurp(victim);
        const CliRun r = run(f.d, "compensate --model '" + f.d.file("model.json") + "' --program '" +
                                      f.d.file("in.nc") + "' --out '" + victim + "'");
        EXPECT_EQ(r.code, 2) << victim << ": " << r.err;
        EXPECT_NE(r.err.find("would be overwritten"), std::string::npos) << r.err;
        EXPECT_EQ(slurp(victim), before) << victim;
    }
}

TEST(CliCompensateRefuses, ModelsBeyondTheBoundOrOfAnotherMachine) {
    Fixture f;
    // Beyond any machine: refused as the model file is read (docs/formats/model.md, the ranges).
    for (const json& params : {json{{"X0C", 1e308}}, json{{"B0A", 1e10}}}) {
        std::ofstream(f.d.path / "model.json") << model("TTTRR", params);
        f.expect_refused(f.compensate(kOk), "is outside");
    }
    std::ofstream(f.d.path / "model.json") << model("TTTRR", json{{"Y0A", 50.0}});
    f.expect_refused(f.compensate(kOk), "bound", 3);
    std::ofstream(f.d.path / "model.json") << model("TTTRR", json{{"Y0A", 50.0}});
    EXPECT_EQ(f.compensate(kOk, "--force").code, 0);
    std::ofstream(f.d.path / "keep.nc") << "precious\n";
    std::ofstream(f.d.path / "model.json") << model("RRTTT", json{{"X0B", 0.01}});
    f.expect_refused(f.compensate(kOk), "another machine type", 3);
}

TEST(CliCompensateSingular, NoNanForAnyToleranceAndNoAddedTurns) {
    Fixture f;
    // A = 0 exactly and just off it; C runs continuously over two turns.
    std::ostringstream p;
    p << "%\nG90\n";
    for (int i = 0; i <= 720; i += 15)
        p << "G1 X" << 50 + i / 100.0 << " Y10 Z20 A" << (i % 45 == 0 ? 0.0 : (i % 2 ? 1e-4 : -0.01)) << " C" << i
          << " F1000\n";
    p << "M30\n%\n";
    for (const char* deg : {"0", "0.06", "45"}) {
        for (const char* method : {"", "--exact"}) {
            const CliRun r = f.compensate(p.str(), std::string("--json --singular-deg ") + deg + " " + method);
            ASSERT_EQ(r.code, 0) << deg << method << r.err;
            const std::string out = slurp(f.d.path / "keep.nc");
            EXPECT_EQ(out.find("nan"), std::string::npos) << out;
            EXPECT_EQ(out.find("inf"), std::string::npos) << out;
            // Every compensated C within the bound (0.1 deg) of the programmed one.
            std::istringstream in(out);
            std::string line;
            int k = 0;
            while (std::getline(in, line)) {
                const auto c = line.find(" C");
                if (line.rfind("G1", 0) != 0 || c == std::string::npos) continue;
                const double got = std::stod(line.substr(c + 2));
                EXPECT_NEAR(got, 15.0 * k, 0.1) << deg << method << ": " << line;
                ++k;
            }
            EXPECT_EQ(k, 49);
            std::ofstream(f.d.path / "keep.nc") << "precious\n";
        }
    }
}

TEST(CliCompensateSingular, ExactNonConvergenceIsCountedAndNothingIsWritten) {
    Fixture f;
    const CliRun r = f.compensate(kOk, "--exact --max-iterations 1 --json");
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.err.find("did not converge for 2 point(s), lines 3 4"), std::string::npos) << r.err;
    EXPECT_EQ(json::parse(r.out)["not_converged"], 2);
    EXPECT_EQ(slurp(f.d.path / "keep.nc"), "precious\n");
}

TEST(CliSolveCompensate, NearASingularityUsesTheCompensateDefault) {
    TempDir d;
    // θa = 2e-7 rad: with the old 1e-9 tolerance dθc was ~1e-5/2e-7 = 50 rad (seven turns of C).
    const json req{{"kinematics", "lei-hsu"}, {"u", {40, -25, 120, 2e-7, 0.8}}, {"dv", {0.01, 0, 0, 2e-5, 1e-5, 0}}};
    const CliRun r = run(d, "solve compensate", req.dump());
    ASSERT_EQ(r.code, 0) << r.err;
    const json a = json::parse(r.out);
    EXPECT_TRUE(a["singular"].get<bool>());
    EXPECT_EQ(a["du_rad"][1].get<double>(), 0.0);
    EXPECT_EQ(a["exact_du_rad"][1].get<double>(), 0.0);
}

}  // namespace
