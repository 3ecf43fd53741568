// SPDX-License-Identifier: MIT
// The CAM interpreter: units, increments, arcs in three planes and both forms, modes and refusals.
#include <gtest/gtest.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "ballbar/analysis/nc_interpreter.hpp"

namespace ba = ballbar::analysis;

namespace {

std::vector<ba::NcStep> interpret(const std::string& text, ba::NcInterpreterOptions o = {}) {
    ba::NcInterpreter in(text, o);
    std::vector<ba::NcStep> out;
    ba::NcStep s;
    while (in.next(s))
        if (s.motion != ba::NcMotion::None) out.push_back(s);
    return out;
}

TEST(NcInterpreter, InchesIncrementsAndModalWords) {
    const auto s = interpret("%\nG20 G90 G0 X1 Y2 Z3 A10 C20\nG91 G1 X0.5 F10\nG21 G90 Y7\nM30\n%\n");
    ASSERT_EQ(s.size(), 3u);
    EXPECT_DOUBLE_EQ(s[0].points[0].X_mm, 25.4);
    EXPECT_DOUBLE_EQ(s[0].points[0].Z_mm, 76.2);
    EXPECT_NEAR(s[0].points[0].C_rad, ba::deg_to_rad(20), 1e-15);  // degrees are not inches
    EXPECT_DOUBLE_EQ(s[1].points[0].X_mm, 38.1);
    EXPECT_DOUBLE_EQ(*s[1].feed, 254.0);  // in/min to mm/min
    EXPECT_DOUBLE_EQ(s[2].points[0].X_mm, 38.1);
    EXPECT_DOUBLE_EQ(s[2].points[0].Y_mm, 7);
    EXPECT_EQ(s[2].motion, ba::NcMotion::Feed);
}

TEST(NcInterpreter, ArcsInEveryPlaneStayOnTheirCircleWithinTheChordTolerance) {
    ba::NcInterpreterOptions o;
    o.chord_tolerance_mm = 0.001;
    struct Case {
        std::string program;
        int u, v;  // plane axes (0 X, 1 Y, 2 Z)
        double cu, cv, r;
    };
    const std::vector<Case> cases = {
        {"G17 G3 X10 Y10 I0 J10", 0, 1, 0, 10, 10},  // quarter, centre (0, 10)
        {"G18 G2 X10 Z10 K10 I0", 2, 0, 10, 0, 10},  // plane Z-X, centre z = 10, x = 0
        {"G19 G3 Y10 Z10 J0 K10", 1, 2, 0, 10, 10},  // plane Y-Z
        {"G17 G2 X20 Y0 R10", 0, 1, 10, 0, 10},      // half circle by R
        {"G17 G3 I5", 0, 1, 5, 0, 5},                // full circle
    };
    for (const auto& c : cases) {
        const auto s = interpret("%\nG0 X0 Y0 Z0 A0 C0\n" + c.program + " F100\nM30\n%\n", o);
        ASSERT_EQ(s.size(), 2u) << c.program;
        const auto& arc = s[1];
        ASSERT_TRUE(arc.arc);
        ASSERT_GT(arc.points.size(), 10u) << c.program;
        const double half_angle = std::acos(1 - 0.001 / c.r);
        for (std::size_t k = 0; k < arc.points.size(); ++k) {
            const double p[3] = {arc.points[k].X_mm, arc.points[k].Y_mm, arc.points[k].Z_mm};
            EXPECT_NEAR(std::hypot(p[c.u] - c.cu, p[c.v] - c.cv), c.r, 1e-9) << c.program << " chord " << k;
            const double q[3] = {k ? arc.points[k - 1].X_mm : 0.0, k ? arc.points[k - 1].Y_mm : 0.0,
                                 k ? arc.points[k - 1].Z_mm : 0.0};
            const double chord = std::hypot(p[c.u] - q[c.u], p[c.v] - q[c.v]);
            EXPECT_LE(chord, 2 * c.r * std::sin(half_angle) + 1e-9) << c.program;  // sagitta within 1 µm
        }
    }
    // A full circle is 2π: its chord count matches the tolerance.
    const auto full = interpret("%\nG0 X0 Y0 Z0 A0 C0\nG3 I5 F100\nM30\n%\n", o);
    EXPECT_EQ(full[1].points.size(), static_cast<std::size_t>(std::ceil(ba::kPi / std::acos(1 - 0.001 / 5))));
    EXPECT_THROW(interpret("%\nG0 X0 Y0 Z0 A0 C0\nG2 X1 Y1 I5 F100\nM30\n%\n"), ba::NcError);  // end off the circle
}

TEST(NcInterpreter, ToolCentrePointWordsOfEachController) {
    for (const char* controller : {"linuxcnc", "fanuc", "siemens", "heidenhain"}) {
        ba::NcInterpreterOptions o;
        o.tcp = *ba::tcp_codes_for(controller);
        o.offsets.tool_length_mm[1] = 100;
        o.have_offsets = true;
        const std::string on = o.tcp.on[0] == "G43.4" ? "G43.4 H1" : o.tcp.on[0];
        const auto s = interpret("%\nG0 X0 Y0 Z0 A0 C0\n" + on + "\nG1 X1 Y1 Z1 A1 C1 F100\n" + o.tcp.off[0] +
                                     "\nG0 X0 Y0 Z0 A0 C0\nM30\n%\n",
                                 o);
        ASSERT_EQ(s.size(), 3u) << controller;
        EXPECT_EQ(s[0].frame, ba::NcFrame::Joint) << controller;
        EXPECT_EQ(s[1].frame, ba::NcFrame::Tcp) << controller;
        EXPECT_EQ(s[2].frame, ba::NcFrame::Joint) << controller;
    }
}

TEST(NcInterpreter, IsoDirectionsNegateRotaryWordsAndOffsets) {
    ba::NcInterpreterOptions o;
    o.iso_directions = true;
    ba::Pose g54;
    g54.C_rad = ba::deg_to_rad(5);
    o.offsets.work["G54"] = g54;
    o.have_offsets = true;
    const auto s = interpret("%\nG54 G0 X0 Y0 Z0 A30 C-40\nM30\n%\n", o);
    EXPECT_NEAR(s[0].points[0].A_rad, ba::deg_to_rad(-30), 1e-15);
    EXPECT_NEAR(s[0].points[0].C_rad, ba::deg_to_rad(40), 1e-15);
    EXPECT_NEAR(s[0].work_offset.C_rad, ba::deg_to_rad(-5), 1e-15);
}

TEST(NcInterpreter, OffsetChangesKeepTheMachineWhereItIs) {
    ba::NcInterpreterOptions o;
    ba::Pose g54, g55;
    g54.Y_mm = 10;
    g55.Y_mm = -5;
    o.offsets.work["G54"] = g54;
    o.offsets.work["G55"] = g55;
    o.offsets.tool_length_mm[1] = 80;
    o.offsets.tool_length_mm[2] = 50;
    o.have_offsets = true;
    const auto s = interpret("%\nG54 G0 X0 Y0 Z100 A0 C0\nG55\nG1 X5 F100\nG43 H1\nG1 X6\nG43 H2\nX7\nM30\n%\n", o);
    ASSERT_EQ(s.size(), 4u);
    EXPECT_DOUBLE_EQ(s[1].points[0].Y_mm, 15);  // machine Y 10: in G55 (−5) that is 15
    EXPECT_DOUBLE_EQ(s[2].points[0].Z_mm, 20);  // the gauge line stays at 100 − 80 above the tip
    EXPECT_DOUBLE_EQ(s[3].points[0].Z_mm, 50);  // a 30 mm shorter tool: its tip 30 mm higher
    EXPECT_DOUBLE_EQ(s[3].tool_length_mm, 50);
    // G53 Z0 (the machine-coordinate retract): the other axes stay where the machine is.
    const auto r = interpret("%\nG55 G0 X1 Y2 Z3 A0 C0\nG53 G0 Z0\nG0 X4\nM30\n%\n", o);
    ASSERT_EQ(r.size(), 3u);
    EXPECT_TRUE(r[1].machine_coordinates);
    EXPECT_DOUBLE_EQ(r[1].points[0].Y_mm, -3);  // machine Y of program Y 2 in G55
    EXPECT_DOUBLE_EQ(r[1].points[0].Z_mm, 0);
    EXPECT_DOUBLE_EQ(r[2].points[0].Z_mm, 0);  // program Z after machine Z 0 (G55 has no Z)
    EXPECT_DOUBLE_EQ(r[2].points[0].Y_mm, 2);
}

TEST(NcInterpreter, RefusesWhatItCannotKnow) {
    for (const char* bad : {"G0 X0 Y0 Z0 A0 C0 B5", "G0 X0 Y0 Z0 A0 C0 X2", "G0 G1 X0 Y0 Z0 A0 C0",
                            "G81 X0 Y0 Z0 A0 C0 R1", "G68 X0 Y0 R45", "M98 P100", "G0 X0 Y0 Z0 A0 C0 U1"}) {
        EXPECT_THROW(interpret(std::string("%\n") + bad + "\nM30\n%\n"), ba::NcError) << bad;
    }
    try {
        interpret("%\nG0 X0 Y0 Z0 A0 C0\nG1 X#5 F100\nM30\n%\n");
        FAIL();
    } catch (const ba::NcError& e) {
        EXPECT_EQ(e.line(), 3);
        EXPECT_NE(std::string(e.what()).find("expand"), std::string::npos) << e.what();
    }
}

// What CAM programs for LinuxCNC's table-tilting machine start with (its boat-xyzac.ngc): a switch to
// tool-centre point, a modal "G00 G17 G40 G90 G94" without axis words, then "Z5". The motion code alone
// moves nothing; the first move needs the start position the user gives (--start), which holds in the
// frame of the first move; the switch is reported on its own line.
TEST(NcInterpreter, AStartPositionLetsACamProgramBeginWithOneAxis) {
    ba::NcInterpreterOptions o;
    o.tcp = *ba::tcp_codes_for("linuxcnc");
    const std::string program =
        "%\nM428 ;TCP:xyzac\n(BOAT)\nG00 G17 G40 G90 G94\nZ5\nG01 Z-6.6 F300.0\nX-49.375 F600.0\nM30\n%\n";
    try {
        interpret(program, o);
        FAIL() << "the first move names Z only";
    } catch (const ba::NcError& e) {
        EXPECT_EQ(e.line(), 5);  // "Z5", the move: not the G00 line before it
        EXPECT_NE(std::string(e.what()).find("position of X is not known"), std::string::npos) << e.what();
    }
    ba::Pose start;
    start.X_mm = 1, start.Y_mm = 2, start.Z_mm = 50, start.A_rad = 0.1, start.C_rad = 0.2;
    o.start = start;
    const auto s = interpret(program, o);
    ASSERT_EQ(s.size(), 3u);
    EXPECT_EQ(s[0].line, 5);
    EXPECT_EQ(s[0].frame, ba::NcFrame::Tcp);
    EXPECT_EQ(s[0].frame_line, 2);  // M428's line
    EXPECT_DOUBLE_EQ(s[0].points[0].X_mm, 1);
    EXPECT_DOUBLE_EQ(s[0].points[0].Z_mm, 5);
    EXPECT_DOUBLE_EQ(s[0].points[0].C_rad, 0.2);
    EXPECT_DOUBLE_EQ(*s[2].feed, 600);
    EXPECT_DOUBLE_EQ(s[2].points[0].X_mm, -49.375);
    EXPECT_DOUBLE_EQ(s[2].points[0].Z_mm, -6.6);
    // A later switch forgets the position again: the next move must name every axis.
    EXPECT_THROW(interpret("%\nG0 X0 Y0 Z0 A0 C0\nM428\nZ5\nM30\n%\n", o), ba::NcError);
    // A feed on a block without motion is the modal feed of the moves after it: kept in the output.
    ba::NcInterpreter in("%\nG0 X0 Y0 Z0 A0 C0\nG1 F250\nX1\nM30\n%\n", {});
    ba::NcStep st;
    ASSERT_TRUE(in.next(st));
    ASSERT_TRUE(in.next(st));
    EXPECT_EQ(st.motion, ba::NcMotion::None);
    EXPECT_EQ(st.words, "F250");
}

}  // namespace

namespace {

// The interpreter's number reading (an exact fast path for the common short numbers) gives what
// std::from_chars gives for every form: many digits, many decimals, leading zeros, a point first.
TEST(NcInterpreter, NumbersAreReadAsFromCharsReadsThem) {
    std::mt19937_64 rng(5);
    std::vector<std::string> texts{"0",
                                   "-0",
                                   "+0.0",
                                   "000123.4500",
                                   ".5",
                                   "-.25",
                                   "7.",
                                   "1234567.89012345",
                                   "999999999",
                                   "0.1",
                                   "0.30000000000000004",
                                   "900719925.4740993",
                                   "123456789.0123456789012345",
                                   "0.0000000000000000000000001"};
    for (int i = 0; i < 3000; ++i) {
        const int digits = 1 + static_cast<int>(rng() % 9);
        const int decimals = static_cast<int>(rng() % 24);
        std::string t = rng() % 2 ? "-" : "";
        for (int d = 0; d < digits; ++d) t += static_cast<char>('0' + rng() % 10);
        if (decimals > 0) t += '.';
        for (int d = 0; d < decimals; ++d) t += static_cast<char>('0' + rng() % 10);
        texts.push_back(t);
    }
    for (const std::string& t : texts) {
        const auto s = interpret("%\nG1 X" + t + " Y0 Z0 A0 C0 F100\nM30\n%\n");
        ASSERT_EQ(s.size(), 1u) << t;
        std::string body = t[0] == '-' || t[0] == '+' ? t.substr(1) : t;
        if (body[0] == '.') body = "0" + body;
        double v = 0;
        std::from_chars(body.data(), body.data() + body.size(), v);
        if (t[0] == '-') v = -v;
        EXPECT_EQ(std::bit_cast<std::uint64_t>(s[0].points[0].X_mm), std::bit_cast<std::uint64_t>(v)) << t;
    }
}

}  // namespace
