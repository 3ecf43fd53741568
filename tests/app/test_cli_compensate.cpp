// SPDX-License-Identifier: MIT
// Whole-process tests of issue 6's commands: `ballbar solve compensate`, `ballbar identify`,
// `ballbar compensate` and the proof `ballbar demo --compensate`.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_harness.hpp"

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

using namespace ballbar::test;

void expect_field_error(const CliRun& r, const std::string& field) {
    EXPECT_EQ(r.code, 2) << r.err;
    json e;
    ASSERT_NO_THROW(e = json::parse(r.err)) << r.err;
    EXPECT_TRUE(e.contains("error"));
    if (!field.empty()) {
        EXPECT_EQ(e.value("field", ""), field) << r.err;
    }
}

// ---- solve compensate -------------------------------------------------------------------------

TEST(CliSolveCompensate, AnswersWithFirstOrderAndExactCorrections) {
    TempDir d;
    const json req{{"kinematics", "lei-hsu"},
                   {"offsets_mm", {{"Xw0", 10}, {"Yw0", -5}, {"Zw0", 2}, {"Z3", 150}}},
                   {"u", {40, -25, 120, 0.5, 0.8}},
                   {"dv", {0.01, -0.02, 0.005, 2e-5, -1e-5, 1e-5}}};
    const CliRun r = run(d, "solve compensate", req.dump());
    ASSERT_EQ(r.code, 0) << r.err;
    const json a = json::parse(r.out);
    ASSERT_EQ(a["du_mm"].size(), 3u);
    ASSERT_EQ(a["du_rad"].size(), 2u);
    ASSERT_EQ(a["exact_du_mm"].size(), 3u);
    EXPECT_FALSE(a["singular"].get<bool>());
    EXPECT_TRUE(a["method"].is_string());
    // The closed-form orientation part (seed-math): dθa = C_a(S_c di + C_c dj) − S_a dk.
    const double sa = std::sin(0.5), ca = std::cos(0.5), sc = std::sin(0.8), cc = std::cos(0.8);
    EXPECT_NEAR(a["du_rad"][0].get<double>(), ca * (sc * 2e-5 + cc * -1e-5) - sa * 1e-5, 1e-15);
    EXPECT_NEAR(a["du_rad"][1].get<double>(), (cc * 2e-5 - sc * -1e-5) / sa, 1e-15);
    // First order and exact agree to second order (dv of 20 µm on ~150 mm: ~1e-6).
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(a["du_mm"][i].get<double>(), a["exact_du_mm"][i].get<double>(), 1e-5);
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(a["du_rad"][i].get<double>(), a["exact_du_rad"][i].get<double>(), 1e-5);
}

TEST(CliSolveCompensate, SingularPoseHasNoCCorrection) {
    TempDir d;
    const json req{{"kinematics", "lei-hsu"}, {"u", {40, -25, 120, 0.0, 0.8}}, {"dv", {0.01, 0, 0, 2e-5, 1e-5, 0}}};
    const CliRun r = run(d, "solve compensate", req.dump());
    ASSERT_EQ(r.code, 0) << r.err;
    const json a = json::parse(r.out);
    EXPECT_TRUE(a["singular"].get<bool>());
    EXPECT_EQ(a["du_rad"][1].get<double>(), 0.0);
    EXPECT_EQ(a["exact_du_rad"][1].get<double>(), 0.0);
}

TEST(CliSolveCompensate, MalformedRequestsNameTheField) {
    TempDir d;
    const json ok{{"kinematics", "lei-hsu"}, {"u", {0, 0, 0, 0.5, 0}}, {"dv", {0, 0, 0, 0, 0, 0}}};
    json r1 = ok;
    r1.erase("u");
    expect_field_error(run(d, "solve compensate", r1.dump()), "u");
    json r2 = ok;
    r2["u"] = {1, 2, 3};
    expect_field_error(run(d, "solve compensate", r2.dump()), "u");
    json r3 = ok;
    r3["dv"][3] = "x";
    expect_field_error(run(d, "solve compensate", r3.dump()), "dv[3]");
    json r4 = ok;
    r4["kinematics"] = "puma";
    expect_field_error(run(d, "solve compensate", r4.dump()), "kinematics");
    json r5 = ok;
    r5["offsets_mm"] = {{"Q", 1}};
    expect_field_error(run(d, "solve compensate", r5.dump()), "offsets_mm.Q");
    json r6 = ok;
    r6["extra"] = 1;
    expect_field_error(run(d, "solve compensate", r6.dump()), "extra");
    expect_field_error(run(d, "solve compensate", "{\"kinematics\": "), "");
}

// ---- identify and compensate ------------------------------------------------------------------

// A TTTRR machine whose C axis line is off by (dx, dy): readings of cube-corner SSM locations,
// computed here from the readings format's own definition so the test does not share code with
// the implementation.
struct Vec {
    double x, y, z;
};
Vec rx(double a, Vec v) {
    return {v.x, std::cos(a) * v.y - std::sin(a) * v.z, std::sin(a) * v.y + std::cos(a) * v.z};
}
Vec rz(double a, Vec v) {
    return {std::cos(a) * v.x - std::sin(a) * v.y, std::sin(a) * v.x + std::cos(a) * v.y, v.z};
}
Vec add(Vec a, Vec b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
Vec sub(Vec a, Vec b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
double norm(Vec a) {
    return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
}

std::string readings_file(double x0c_mm, double y0c_mm) {
    std::ostringstream f;
    f.precision(17);
    f << "# ballbar-readings/1\n"
      << "# machine: {\"type\":\"TTTRR\",\"name\":\"cli-test\",\"a_pivot_mm\":[0,0,0],\"c_offset_mm\":[0,0,-100],"
         "\"tool_ball_mm\":[0,0,0]}\n"
      << "location,point,X_mm,Y_mm,Z_mm,A_deg,C_deg,socket_x_mm,socket_y_mm,socket_z_mm,measured_mm\n";
    const Vec socket{100, 0, 20}, c_off{0, 0, -100}, d{x0c_mm, y0c_mm, 0};
    const double pi = 3.141592653589793, cone = 0.9553166181245093;
    int loc = 0;
    for (double a_deg : {-60.0, -30.0, 0.0, 30.0, 60.0})
        for (double c_deg : {0.0, 60.0, 120.0, 180.0, 240.0, 300.0}) {
            const double a = a_deg * pi / 180, c = c_deg * pi / 180;
            const Vec s_nom = rx(a, add(c_off, rz(c, socket)));
            const Vec s_act = rx(a, add(add(c_off, d), rz(c, sub(socket, d))));
            for (int k = 0; k < 3; ++k) {
                const double az = 2 * pi * k / 3;
                const Vec b = add(s_nom, Vec{100 * std::sin(cone) * std::cos(az), 100 * std::sin(cone) * std::sin(az),
                                             100 * std::cos(cone)});
                f << loc << ',' << k << ',' << b.x << ',' << b.y << ',' << b.z << ',' << a_deg << ',' << c_deg << ','
                  << socket.x << ',' << socket.y << ',' << socket.z << ',' << norm(sub(b, s_act)) << '\n';
            }
            ++loc;
        }
    return f.str();
}

TEST(CliIdentify, RecoversTheCAxisLocationAndStoresTheModel) {
    TempDir d;
    std::ofstream(d.path / "r.csv") << readings_file(0.03, -0.02);
    const CliRun r = run(d, "identify '" + (d.path / "r.csv").string() + "' --params X0C,Y0C,C_zero --json --out '" +
                                (d.path / "m.model.json").string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const json a = json::parse(r.out);
    // --out: the same model as a file, what LinuxCNC's ballbarkins and `compensate --model FILE` read.
    EXPECT_EQ(json::parse(slurp(d.path / "m.model.json")), a["model"]);
    EXPECT_TRUE(a["converged"].get<bool>());
    std::map<std::string, json> est;
    for (const auto& e : a["estimates"]) est[e["name"].get<std::string>()] = e;
    EXPECT_NEAR(est["X0C"]["value"].get<double>(), 0.03, 1e-7);
    EXPECT_NEAR(est["Y0C"]["value"].get<double>(), -0.02, 1e-7);
    EXPECT_FALSE(est["C_zero"]["observable"].get<bool>());  // a turn of the socket is a socket offset
    EXPECT_LT(a["residual_rms_um"].get<double>(), 1e-3);
    ASSERT_TRUE(a.contains("model_id"));
    EXPECT_EQ(a["model"]["format"], "ballbar-model/1");

    // The stored model compensates a program; the largest correction is the C-axis offset's size.
    std::ofstream(d.path / "in.nc") << "%\nO0001\nG90\nG1 X50 Y0 Z30 A30 C0 F1000\nG1 X0 Y50 A30 C90\n"
                                       "G1 X10 Y10 Z10 A0 C45\n%\n";
    const CliRun c = run(d, "compensate --model " + std::to_string(a["model_id"].get<long>()) + " --program '" +
                                (d.path / "in.nc").string() + "' --out '" + (d.path / "out.nc").string() + "' --json");
    ASSERT_EQ(c.code, 0) << c.err;
    const json cj = json::parse(c.out);
    EXPECT_EQ(cj["compensated"], 3);
    EXPECT_GT(cj["max_linear_correction_mm"].get<double>(), 0.01);
    EXPECT_LT(cj["max_linear_correction_mm"].get<double>(), 0.1);
    EXPECT_EQ(cj["singular_blocks"], 1);  // A = 0: C is parallel to the tool
    EXPECT_EQ(cj["singular_lines"][0], 6);
    const std::string out = slurp(d.path / "out.nc");
    EXPECT_NE(out.find("G1"), std::string::npos);
    // The model keeps where it was measured (the readings' span: A ±60°, C 0–300°); this program stays
    // inside it, so no warning says otherwise.
    EXPECT_EQ(a["model"]["measured_poses"]["A_deg"], json::array({-60.0, 60.0})) << a["model"].dump();
    EXPECT_EQ(a["model"]["measured_poses"]["C_deg"], json::array({0.0, 300.0}));
    for (const auto& w : cj["warnings"])
        EXPECT_EQ(w.get<std::string>().find("the program commands"), std::string::npos) << w;
    // One going beyond: A to 90° (line 4) and C to 330° (line 5), each said with its line.
    std::ofstream(d.path / "far.nc") << "%\nO0002\nG90\nG1 X50 Y0 Z30 A90 C0 F1000\nG1 X0 Y50 A30 C330\n%\n";
    const CliRun far =
        run(d, "compensate --model " + std::to_string(a["model_id"].get<long>()) + " --program '" +
                   (d.path / "far.nc").string() + "' --out '" + (d.path / "far-out.nc").string() + "' --json");
    ASSERT_EQ(far.code, 0) << far.err;
    std::string beyond;
    const json far_report = json::parse(far.out);  // outlives the loop over its list
    for (const auto& w : far_report["warnings"]) beyond += w.get<std::string>() + "\n";
    EXPECT_NE(beyond.find("the program commands A from 30° (line 5) to 90° (line 4); the model was measured from "
                          "-60° to 60°"),
              std::string::npos)
        << beyond;
    EXPECT_NE(beyond.find("the program commands C from 0° (line 4) to 330° (line 5); the model was measured from 0° "
                          "to 300°"),
              std::string::npos)
        << beyond;

    // The same with the model as a file, and a refused model.
    std::ofstream(d.path / "model.json") << a["model"].dump();
    EXPECT_EQ(run(d, "compensate --model '" + (d.path / "model.json").string() + "' --program '" +
                         (d.path / "in.nc").string() + "' --out '" + (d.path / "out2.nc").string() + "'")
                  .code,
              0);
    std::ofstream(d.path / "bad.json") << R"({"machine":{"type":"TTTRR","a_pivot_mm":[0,0,0],"c_offset_mm":[0,0,0],)"
                                       << R"("tool_ball_mm":[0,0,0]},"params":{"X9Q":1}})";
    const CliRun bad = run(d, "compensate --model '" + (d.path / "bad.json").string() + "' --program '" +
                                  (d.path / "in.nc").string() + "' --out '" + (d.path / "out3.nc").string() + "'");
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.err.find("X9Q"), std::string::npos) << bad.err;

    // A program with an error deep inside: refused with its line, and nothing half-written; an
    // existing output file is left as it was.
    {
        std::ofstream broken(d.path / "broken.nc");
        broken << "%\nO0001\nG90\n";
        for (int i = 0; i < 50000; ++i) broken << "G1 X" << i % 100 << " Y1 Z5 A30 C" << i % 360 << " F1000\n";
        broken << "G2 X1 Y1 I1\n%\n";
    }
    std::ofstream(d.path / "keep.nc") << "precious\n";
    const CliRun broken =
        run(d, "compensate --model '" + (d.path / "model.json").string() + "' --program '" +
                   (d.path / "broken.nc").string() + "' --out '" + (d.path / "keep.nc").string() + "'");
    EXPECT_EQ(broken.code, 2);
    EXPECT_NE(broken.err.find("line 50004"), std::string::npos) << broken.err;
    EXPECT_EQ(slurp(d.path / "keep.nc"), "precious\n");
    for (const auto& e : fs::directory_iterator(d.path))  // no temporary file (keep.nc.XXXXXXXX.part) left
        EXPECT_NE(e.path().extension(), ".part") << e.path();

    // --out: a directory is refused up front; so is a symlink (ballbar does not write through links,
    // docs/cli.md "Files"); a FIFO (or /dev/stdout on a pipe) is written straight through.
    const std::string compensate = "compensate --model '" + (d.path / "model.json").string() + "' --program '" +
                                   (d.path / "in.nc").string() + "' --out ";
    const CliRun dir_out = run(d, compensate + "'" + d.path.string() + "'");
    EXPECT_EQ(dir_out.code, 2);
    EXPECT_NE(dir_out.err.find("is a directory"), std::string::npos) << dir_out.err;
    std::ofstream(d.path / "real.nc") << "old\n";
    fs::create_symlink(d.path / "real.nc", d.path / "link.nc");
    const CliRun link_out = run(d, compensate + "'" + (d.path / "link.nc").string() + "'");
    EXPECT_EQ(link_out.code, 2) << link_out.err;
    EXPECT_NE(link_out.err.find("is a symbolic link"), std::string::npos) << link_out.err;
    EXPECT_TRUE(fs::is_symlink(d.path / "link.nc"));
    EXPECT_EQ(slurp(d.path / "real.nc"), "old\n");
    const std::string piped = std::string("'") + BALLBAR_EXE + "' --db '" + d.file("test.db") + "' " + compensate +
                              "/dev/stdout | cat > '" + (d.path / "piped.nc").string() + "'";
    ASSERT_EQ(std::system(piped.c_str()), 0);
    EXPECT_NE(slurp(d.path / "piped.nc").find("G1"), std::string::npos);
    EXPECT_TRUE(fs::is_symlink("/dev/stdout")) << "/dev/stdout is written through, never replaced";
    // Standard output ('-' or /dev/stdout, redirected to a file here) holds the program and nothing
    // else: the summary goes to stderr.
    for (const char* dest : {"-", "/dev/stdout"}) {
        const CliRun to_stdout = run(d, compensate + dest);
        EXPECT_EQ(to_stdout.code, 0) << to_stdout.err;
        EXPECT_EQ(to_stdout.out.rfind("%\nO0001", 0), 0u) << dest << ":\n" << to_stdout.out;
        EXPECT_EQ(to_stdout.out.find("compensated 3 of"), std::string::npos) << dest;
        EXPECT_NE(to_stdout.err.find("compensated 3 of"), std::string::npos) << dest << ": " << to_stdout.err;
    }
    // With --json too: the program alone on stdout, the JSON report alone on stderr (docs/cli.md).
    const CliRun json_out = run(d, compensate + "- --json");
    EXPECT_EQ(json_out.code, 0) << json_out.err;
    EXPECT_EQ(json_out.out.rfind("%\nO0001", 0), 0u) << json_out.out;
    EXPECT_EQ(json_out.out.find('{'), std::string::npos) << "no JSON in the program: " << json_out.out;
    const auto report = nlohmann::json::parse(json_out.err, nullptr, false);
    ASSERT_FALSE(report.is_discarded()) << "stderr is the JSON report and nothing else: " << json_out.err;
    EXPECT_EQ(report.value("compensated", -1), 3) << json_out.err;
    EXPECT_EQ(report.value("out", ""), "-");
    EXPECT_TRUE(fs::is_symlink("/dev/stdout"));
}

TEST(CliIdentify, RefusesUnknownInputs) {
    TempDir d;
    const CliRun r = run(d, "identify no-such-thing");
    EXPECT_EQ(r.code, 2) << r.err;
    std::ofstream(d.path / "r.csv") << readings_file(0, 0);
    const CliRun p = run(d, "identify '" + (d.path / "r.csv").string() + "' --params X0C,NOPE");
    EXPECT_EQ(p.code, 2);
    EXPECT_NE(p.err.find("NOPE"), std::string::npos) << p.err;
}

// ---- the proof ------------------------------------------------------------------------------

TEST(CliDemoCompensate, ImprovesEveryAxisAtLeastFiveTimes) {
    TempDir d;
    const CliRun r = run(d, "demo --machine TTTRR --compensate --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const json a = json::parse(r.out);
    for (const char* axis : {"X", "Y", "Z"}) {
        EXPECT_GE(a["improvement_ratio"][axis].get<double>(), 5.0) << axis;
        EXPECT_GT(a["rms_before_um"][axis].get<double>(), 1.0) << axis;  // there was something to fix
    }
    ASSERT_FALSE(a["identified"].empty());
    for (const auto& p : a["identified"]) {
        ASSERT_TRUE(p.contains("name") && p.contains("unit") && p.contains("value") && p.contains("true_value") &&
                    p.contains("value_std"));
    }
    EXPECT_TRUE(a["rms_after_um"].contains("X"));

    // The before/after is stored with the demo session: its report has the compensation section,
    // with the numbers the demo printed.
    ASSERT_TRUE(a.contains("session")) << r.out;
    const CliRun rep = run(d, "report " + std::to_string(a["session"].get<long>()) + " --json");
    ASSERT_EQ(rep.code, 0) << rep.err;
    const json j = json::parse(rep.out);
    ASSERT_EQ(j["compensation"]["axes"].size(), 3u) << rep.out;
    for (const auto& ax : j["compensation"]["axes"]) {
        const std::string axis = ax["axis"];
        EXPECT_NEAR(ax["before_um"].get<double>(), a["rms_before_um"][axis].get<double>(), 1e-9) << axis;
        EXPECT_NEAR(ax["after_um"].get<double>(), a["rms_after_um"][axis].get<double>(), 1e-9) << axis;
    }
    EXPECT_NE(j["compensation"]["metric"].get<std::string>().find("test path"), std::string::npos);
}

}  // namespace
