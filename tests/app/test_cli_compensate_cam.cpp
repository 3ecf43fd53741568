// SPDX-License-Identifier: MIT
// `ballbar compensate` on CAM-style programs, checked independently of the compensator: this file has
// its own forward kinematics of the erroneous TTTRR machine (written from docs/kinematics.md), its own
// reading of the NC subset in the programs, and its own tool-centre-point kinematics. It runs the
// compensated program on the actual machine and checks that the tool is where the input program meant
// it relative to the workpiece at every block end.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../independent_tttrr.hpp"
#include "cli_harness.hpp"

using nlohmann::json;
using namespace ballbar::test;

namespace {

using namespace ballbar::test::tttrr;

// The machine: TTTRR, A pivot at the origin, C frame 100 mm below it (docs/kinematics.md).
const Geometry kMachine{{0, 0, 0}, {0, 0, -100}};
const V kPivot = kMachine.a_pivot, kCOffset = kMachine.c_offset;

json params_json(const Errors& e) {
    return {{"Y0A", e.Y0A}, {"Z0A", e.Z0A}, {"B0A", e.B0A}, {"C0A", e.C0A},       {"X0C", e.X0C},
            {"Y0C", e.Y0C}, {"A0C", e.A0C}, {"B0C", e.B0C}, {"A_zero", e.A_zero}, {"C_zero", e.C_zero},
            {"EXX", e.EXX}, {"EYY", e.EYY}, {"C0Y", e.C0Y}};
}

// ---- the test's own reading of the NC subset the programs use -----------------------------------

struct Table {
    std::map<std::string, std::array<double, 5>> work;  // X Y Z mm, A C deg
    std::map<int, double> tool_mm;
    double measured_mm = 0;
};

struct BlockEnd {
    double p[5] = {};  // X Y Z mm, A C rad: program frame, absolute
    std::array<double, 5> off{};
    bool tcp = false;
    bool g43 = false;
    double tool_mm = 0;
    double inv_time_total = 0;  // Σ 1/F over the lines of the block (G93)
    int lines = 0;
    bool arc = false;
};

/// Motion blocks by N number (the last motion line of a block is its end).
std::map<int, BlockEnd> read_program(const std::string& text, const Table& t) {
    std::map<int, BlockEnd> out;
    std::istringstream in(text);
    std::string line;
    double pos[5] = {};
    bool abs = true, g93 = false, tcp = false, g43 = false;
    int motion = -1, n = -1;
    double tool = 0;
    std::array<double, 5> off{};
    while (std::getline(in, line)) {
        std::string code;
        for (std::size_t i = 0; i < line.size(); ++i) {
            if (line[i] == '(') {
                i = line.find(')', i);
                if (i == std::string::npos) break;
            } else if (line[i] == ';') {
                break;
            } else {
                code += static_cast<char>(std::toupper(static_cast<unsigned char>(line[i])));
            }
        }
        std::map<char, double> w;
        bool moves = false, arc = false, g28 = false;
        std::size_t i = 0;
        while (i < code.size()) {
            const char c = code[i];
            if (c == ' ' || c == '%' || c == '\r') {
                ++i;
                continue;
            }
            std::size_t used = 0;
            const double v = std::stod(code.substr(i + 1), &used);
            i += 1 + used;
            if (c == 'G') {
                const int g = static_cast<int>(std::lround(v * 10));
                if (g <= 30 && g % 10 == 0) {
                    motion = g / 10;
                    moves = true;
                }
                if (g == 900) abs = true;
                if (g == 910) abs = false;
                if (g == 930) g93 = true;
                if (g == 940) g93 = false;
                if (g == 490) g43 = false;
                if (g == 430) g43 = true;
                if (g == 280) g28 = true;
                if (g >= 540 && g <= 590) {
                    const auto& o = t.work.at("G" + std::to_string(g / 10));
                    off = {o[0], o[1], o[2], rad(o[3]), rad(o[4])};
                }
            } else if (c == 'M') {
                if (v == 428) tcp = true;
                if (v == 429) tcp = false;
            } else if (c == 'N') {
                n = static_cast<int>(v);
            } else if (c == 'H') {
                tool = t.tool_mm.at(static_cast<int>(v));
            } else {
                w[c] = v;
            }
        }
        if (g28) continue;
        const char axes[5] = {'X', 'Y', 'Z', 'A', 'C'};
        bool has_axis = false;
        for (int k = 0; k < 5; ++k)
            if (w.count(axes[k])) {
                const double v = k < 3 ? w[axes[k]] : rad(w[axes[k]]);
                pos[k] = abs ? v : pos[k] + v;
                has_axis = true;
            }
        arc = motion >= 2;
        if (!(moves || has_axis)) continue;
        BlockEnd& b = out[n];
        for (int k = 0; k < 5; ++k) b.p[k] = pos[k];
        b.off = off;
        b.tcp = tcp;
        b.g43 = g43;
        b.tool_mm = tool;
        b.arc = b.arc || arc;
        ++b.lines;
        if (g93 && motion >= 1 && w.count('F')) b.inv_time_total += 1.0 / w['F'];
    }
    return out;
}

/// Where the machine puts the tool relative to the table for a block end of a program.
Seen run_block(const Errors& e, const BlockEnd& b, const Table& t) {
    const double dl = b.g43 ? b.tool_mm - t.measured_mm : 0.0;
    const V tool{0, 0, -dl};  // the model's tool ball is at the commanded point (tool_ball_mm = 0)
    const double A = b.p[3] + b.off[3], C = b.p[4] + b.off[4];
    V u;
    if (b.tcp) {
        u = tcp_machine(kMachine, V{b.p[0] + b.off[0], b.p[1] + b.off[1], b.p[2] + b.off[2]}, A, C) - tool;
    } else {
        u = V{b.p[0] + b.off[0], b.p[1] + b.off[1], b.p[2] + b.off[2] + dl};
    }
    return actual_tool_in_table(kMachine, e, u.x, u.y, u.z, A, C, tool);
}

std::string model_json_compensate_cam(const Errors& e) {
    return json{{"format", "ballbar-model/1"},
                {"machine",
                 {{"type", "TTTRR"},
                  {"name", "cam-test"},
                  {"a_pivot_mm", {kPivot.x, kPivot.y, kPivot.z}},
                  {"c_offset_mm", {kCOffset.x, kCOffset.y, kCOffset.z}},
                  {"tool_ball_mm", {0, 0, 0}}}},
                {"params", params_json(e)}}
        .dump();
}

const char* kOffsets = R"({"work_offsets":{"G54":{"X_mm":10,"Y_mm":-5,"Z_mm":-80,"A_deg":0,"C_deg":0}},
  "tools":{"1":{"length_mm":80}}, "measured_tool_length_mm":50})";
Table table() {
    Table t;
    t.work["G54"] = {10, -5, -80, 0, 0};
    t.tool_mm[1] = 80;
    t.measured_mm = 50;
    return t;
}

struct Outcome {
    double max_position_mm = 0, max_axis_rad = 0;
    json summary;
    std::map<int, BlockEnd> in, out;
};

Outcome compensate_and_run(const TempDir& d, const std::string& program, const Errors& e, const std::string& flags) {
    std::ofstream(d.path / "model.json") << model_json_compensate_cam(e);
    std::ofstream(d.path / "offsets.json") << kOffsets;
    std::ofstream(d.path / "in.ngc") << program;
    const CliRun r =
        run(d, "compensate --model '" + d.file("model.json") + "' --program '" + d.file("in.ngc") + "' --offsets '" +
                   d.file("offsets.json") + "' --out '" + d.file("out.ngc") + "' --decimals 7 --json " + flags);
    EXPECT_EQ(r.code, 0) << r.err;
    Outcome o;
    if (r.code != 0) return o;
    o.summary = json::parse(r.out);
    const Table t = table();
    o.in = read_program(program, t);
    o.out = read_program(slurp(d.path / "out.ngc"), t);
    const Errors none;
    for (const auto& [n, want] : o.in) {
        EXPECT_TRUE(o.out.count(n)) << "block N" << n << " is missing from the output";
        if (!o.out.count(n)) continue;
        const BlockEnd& got = o.out.at(n);
        const Seen intended = run_block(none, want, t);  // the nominal machine at the input program
        const Seen actual = run_block(e, got, t);        // the erroneous machine at the output
        o.max_position_mm = std::max(o.max_position_mm, norm(actual.position - intended.position));
        if (std::abs(std::sin(want.p[3] + want.off[3])) >
            0.2)  // away from the A = 0 singularity (and the bound near it)
            o.max_axis_rad = std::max(o.max_axis_rad, norm(cross(actual.axis, intended.axis)));
        if (want.arc) {
            EXPECT_GT(got.lines, 1) << "N" << n << ": the arc was not linearised";
        }
        if (want.inv_time_total > 0) {  // G93: the compensated block takes the time the input's did
            EXPECT_NEAR(got.inv_time_total, want.inv_time_total, 1e-9 * want.inv_time_total) << "N" << n;
        }
    }
    return o;
}

std::string cam_sample() {
    return slurp(std::filesystem::path(BALLBAR_TEST_DATA_DIR) / "nc" / "cam_trt_5axis.ngc");
}

/// A generated program: random five-axis moves, arcs in all three planes, G93 blocks, N on every block.
std::string generated_program(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> lin(-60, 60), a(-80, 80), c(-360, 360), r(5, 20);
    std::ostringstream p;
    p.setf(std::ios::fixed);
    p.precision(4);
    p << "N1 G21 G90 G94 G54\nN2 G0 G43 H1 X0 Y0 Z40 A20 C0\n";
    int n = 3;
    for (int k = 0; k < 60; ++k) {
        const int kind = k % 5;
        if (kind == 3) {
            // A full circle in the current plane at the current point, around a centre r away.
            const char* plane[] = {"G17", "G18", "G19"};
            const char* ij[] = {"I", "K", "J"};
            p << "N" << n++ << ' ' << plane[k % 3] << (k % 2 ? " G2 " : " G3 ") << ij[k % 3] << r(rng) << " F700\n";
        } else if (kind == 4) {
            p << "N" << n++ << " G93 G1 X" << lin(rng) << " Y" << lin(rng) << " Z" << lin(rng) << " A" << a(rng) << " C"
              << c(rng) << " F" << 5 + k << '\n';
            p << "N" << n++ << " G94 G17 G1 F900 X" << lin(rng) << '\n';
        } else {
            p << "N" << n++ << (kind == 0 ? " G0" : " G1") << " X" << lin(rng) << " Y" << lin(rng) << " Z" << lin(rng)
              << " A" << a(rng) << " C" << c(rng) << (kind == 0 ? "" : " F1200") << '\n';
        }
    }
    p << "N" << n << " M2\n";
    return p.str();
}

// ---- the tests ---------------------------------------------------------------------------------

TEST(CliCompensateCam, ExactPutsTheToolOnTheIntendedPoseAtEveryBlockEnd) {
    TempDir d;
    for (const std::string& program : {cam_sample(), generated_program(1)}) {
        const Outcome o = compensate_and_run(d, program, seed_like(), "--exact");
        std::printf("exact: largest miss %.3g um, tool axis %.3g rad\n", o.max_position_mm * 1e3, o.max_axis_rad);
        EXPECT_LT(o.max_position_mm, 1e-4) << "0.1 um";
        EXPECT_LT(o.max_axis_rad, 1e-8);
        EXPECT_GT(o.summary.value("arcs", 0), 0);
        EXPECT_EQ(o.summary.value("not_converged", -1), 0);
    }
}

TEST(CliCompensateCam, FirstOrderIsWithinItsStatedRemainder) {
    TempDir d;
    // Uncompensated, the erroneous machine misses by tens of µm; first order leaves the second-order
    // remainder, stated in docs/compensation.md as below 0.2 µm for seed-like errors.
    const Errors e = seed_like();
    for (const std::string& program : {cam_sample(), generated_program(2)}) {
        const Outcome o = compensate_and_run(d, program, e, "");
        std::printf("first order: largest miss %.3g um, tool axis %.3g rad\n", o.max_position_mm * 1e3, o.max_axis_rad);
        EXPECT_LT(o.max_position_mm, 2e-4);
        EXPECT_LT(o.max_axis_rad, 1e-7);
    }
    // The remainder is second order: halving the errors quarters it (within rounding of the words).
    Errors half = e;
    for (double* v : {&half.Y0A, &half.Z0A, &half.B0A, &half.C0A, &half.X0C, &half.Y0C, &half.A0C, &half.B0C,
                      &half.A_zero, &half.C_zero, &half.EXX, &half.EYY, &half.C0Y})
        *v *= 0.5;
    const Outcome full = compensate_and_run(d, generated_program(3), e, "");
    const Outcome halved = compensate_and_run(d, generated_program(3), half, "");
    std::printf("first order: %.3g um with the errors, %.3g um with half of them\n", full.max_position_mm * 1e3,
                halved.max_position_mm * 1e3);
    EXPECT_LT(halved.max_position_mm, 0.35 * full.max_position_mm + 1e-6);
}

TEST(CliCompensateCam, UncompensatedMachineMissesByTensOfMicrometres) {
    // The check can fail: the input program itself on the erroneous machine is far off.
    const Table t = table();
    const auto in = read_program(cam_sample(), t);
    double worst = 0;
    for (const auto& [n, b] : in)
        worst = std::max(worst, norm(run_block(seed_like(), b, t).position - run_block(Errors{}, b, t).position));
    std::printf("uncompensated: largest miss %.3g um\n", worst * 1e3);
    EXPECT_GT(worst, 0.01);
}

TEST(CliCompensateCam, ZeroErrorModelReproducesTheProgramsMotion) {
    TempDir d;
    for (const std::string& program : {cam_sample(), generated_program(4)}) {
        const Outcome o = compensate_and_run(d, program, Errors{}, "");
        ASSERT_EQ(o.in.size(), o.out.size());
        for (const auto& [n, want] : o.in) {
            const BlockEnd& got = o.out.at(n);
            for (int k = 0; k < 5; ++k) EXPECT_NEAR(got.p[k], want.p[k], 1e-9) << "N" << n << " axis " << k;
            EXPECT_EQ(got.tcp, want.tcp) << "N" << n;
        }
        EXPECT_LT(o.max_position_mm, 1e-9);
    }
}

TEST(CliCompensateCam, SummaryCountsTheModeOfEveryBlock) {
    TempDir d;
    const Outcome o = compensate_and_run(d, cam_sample(), seed_like(), "");
    EXPECT_EQ(o.summary["modes"]["tool_centre_point"], 5);  // N210–N250
    EXPECT_EQ(o.summary["modes"]["joint"], 15);
    ASSERT_EQ(o.summary["mode_switches"].size(), 2u);
    EXPECT_EQ(o.summary["mode_switches"][0]["line"], 23);  // M428's own line (N200)
    EXPECT_EQ(o.summary["mode_switches"][0]["mode"], "tool-centre-point");
    EXPECT_EQ(o.summary["mode_switches"][1]["line"], 29);  // M429 (N260)
    EXPECT_EQ(o.summary["retracts_uncompensated"], 1);
    // Machine functions, tool changes, offsets and the switch words pass through as written.
    const std::string out = slurp(d.path / "out.ngc");
    for (const char* kept : {"N20 T1 M6 (tool change)", "N30 G54\n", "G43 H1", "N50 S12000 M3\n", "N60 M8 (coolant)",
                             "N200 M428 (tool-centre point on)", "G91 G28 Z0.\nG90\n", "N310 M30\n"})
        EXPECT_NE(out.find(kept), std::string::npos) << kept << " missing from\n" << out;
    EXPECT_EQ(out.find("G2 "), std::string::npos) << "arcs are written as chords";
}

// CAM output that starts with one axis after M428 (as LinuxCNC's boat-xyzac.ngc): refused on the
// move's own line without a start position, compensated with --start; a --start missing an axis is
// refused with what to write.
TEST(CliCompensateCam, AStartPositionLetsAProgramBeginWithOneAxis) {
    TempDir d;
    std::ofstream(d.path / "model.json") << model_json_compensate_cam(seed_like());
    std::ofstream(d.path / "boat.ngc") << "%\nM428 ;TCP\n(BOAT)\nG00 G17 G40 G90 G94\nZ5\nG01 Z-6.6 F300.0\n"
                                          "X-49.375 Y3 A10 C20 F600.0\nG00 Z10\nM429\nM30\n%\n";
    const std::string base = "compensate --model '" + d.file("model.json") + "' --program '" + d.file("boat.ngc") +
                             "' --out '" + d.file("out.ngc") + "' --json";
    const CliRun without = run(d, base);
    EXPECT_EQ(without.code, 2);
    EXPECT_NE(without.err.find("line 5: the position of X is not known here"), std::string::npos) << without.err;
    const CliRun partial = run(d, base + " --start 'X0 Y0 Z50 A0'");
    EXPECT_EQ(partial.code, 2);
    EXPECT_NE(partial.err.find("--start \"X0 Y0 Z50 A0\": an axis is missing"), std::string::npos) << partial.err;
    const CliRun with = run(d, base + " --start 'X0 Y0 Z50 A0 C0'");
    ASSERT_EQ(with.code, 0) << with.err;
    const json summary = json::parse(with.out);
    EXPECT_EQ(summary["mode_switches"][0]["line"], 2);  // M428's line
    EXPECT_EQ(summary["modes"]["tool_centre_point"], 4);
}

TEST(CliCompensateCam, IsoDirectionsAreBallbarsNegated) {
    // The same program for an ISO-direction controller (every A and C word negated, and the table's
    // rotary offsets) compensated with --iso-directions: the same motion, A and C negated back.
    TempDir d;
    const Outcome ballbar = compensate_and_run(d, cam_sample(), seed_like(), "");
    std::string iso_program;
    const std::string src = cam_sample();
    const std::regex word("([AC])(-?)([0-9.]+)");
    auto last = src.cbegin();
    for (std::sregex_iterator it(src.begin(), src.end(), word), end; it != end; ++it) {
        iso_program.append(last, (*it)[0].first);
        iso_program += (*it)[1].str() + ((*it)[2].length() ? "" : "-") + (*it)[3].str();  // A30. <-> A-30.
        last = (*it)[0].second;
    }
    iso_program.append(last, src.cend());
    ASSERT_NE(iso_program.find("A-30. C-45."), std::string::npos) << iso_program;
    std::ofstream(d.path / "iso.ngc") << iso_program;
    std::ofstream(d.path / "model.json") << model_json_compensate_cam(seed_like());
    const CliRun r =
        run(d, "compensate --model '" + d.file("model.json") + "' --program '" + d.file("iso.ngc") + "' --offsets '" +
                   d.file("offsets.json") + "' --out '" + d.file("iso_out.ngc") + "' --decimals 7 --iso-directions");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto iso = read_program(slurp(d.path / "iso_out.ngc"), table());
    ASSERT_EQ(iso.size(), ballbar.out.size());
    for (const auto& [n, b] : ballbar.out) {
        const BlockEnd& i = iso.at(n);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(i.p[k], b.p[k], 1e-9) << "N" << n;
        for (int k = 3; k < 5; ++k) EXPECT_NEAR(i.p[k], -b.p[k], 1e-9) << "N" << n;
    }
}

}  // namespace
