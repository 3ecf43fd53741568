// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "ballbar/analysis/nc_program.hpp"

namespace ba = ballbar::analysis;

TEST(NcProgram, ParsesFanucDwellInMillisecondsAndModalMotion) {
    const auto p = ba::parse_nc_program(
        "%\nO0001 (SSM)\nG90 G21\nG0 X10 Y-20.5 Z.5 A30 C-45 (start)\nG1 X11 F500\nY3\nG4 P1500\nM30\n%\n",
        ba::NcDialect::Fanuc);
    ASSERT_EQ(p.blocks.size(), 6u);  // G90 G21, G0, G1, modal G1, G4, M30
    EXPECT_EQ(p.blocks[1].motion, ba::NcMotion::Rapid);
    EXPECT_DOUBLE_EQ(*p.blocks[1].Z_mm, 0.5);
    EXPECT_NEAR(*p.blocks[1].A_rad, ba::deg_to_rad(30), 1e-15);
    EXPECT_EQ(p.blocks[1].comment, "start");
    EXPECT_EQ(p.blocks[2].motion, ba::NcMotion::Feed);
    EXPECT_DOUBLE_EQ(*p.blocks[2].feed_mm_min, 500);
    EXPECT_EQ(p.blocks[3].motion, ba::NcMotion::Feed);  // modal
    EXPECT_EQ(p.blocks[4].motion, ba::NcMotion::Dwell);
    EXPECT_DOUBLE_EQ(p.blocks[4].dwell_s, 1.5);
    const auto poses = ba::resolve_poses(p);
    EXPECT_DOUBLE_EQ(poses[3].X_mm, 11);
    EXPECT_DOUBLE_EQ(poses[3].Y_mm, 3);
    EXPECT_DOUBLE_EQ(poses[3].Z_mm, 0.5);
    EXPECT_NEAR(poses[3].C_rad, ba::deg_to_rad(-45), 1e-15);
}

TEST(NcProgram, ParsesLinuxCncDwellInSecondsAndSemicolonComments) {
    const auto p = ba::parse_nc_program("G90\nG0 X1 B15 ; approach\nG4 P2.5\nM2\n", ba::NcDialect::LinuxCNC);
    ASSERT_EQ(p.blocks.size(), 4u);
    EXPECT_EQ(p.blocks[1].comment, "approach");
    EXPECT_DOUBLE_EQ(p.blocks[2].dwell_s, 2.5);
}

// Found by fuzz_nc_program: a LinuxCNC ';' comment may hold parentheses and control characters; written
// back inside ( ) they ended the comment early and the program did not read back ("unexpected
// character").
TEST(NcProgram, ACommentWithParenthesesIsWrittenSoThatItReadsBack) {
    const ba::NcProgram p = ba::parse_nc_program("G1 X1 F100 ; tool (T2) reset \x01 (ok\n", ba::NcDialect::LinuxCNC);
    ASSERT_EQ(p.blocks.size(), 1u);
    const std::string text = ba::write_nc_program(p);
    EXPECT_NE(text.find("(tool [T2] reset"), std::string::npos) << text;
    ba::NcProgram back;
    ASSERT_NO_THROW(back = ba::parse_nc_program(text, ba::NcDialect::LinuxCNC)) << text;
    const auto moves =
        std::find_if(back.blocks.begin(), back.blocks.end(), [](const ba::NcBlock& b) { return b.X_mm; });
    ASSERT_NE(moves, back.blocks.end()) << text;
    EXPECT_EQ(moves->X_mm, p.blocks[0].X_mm);
    EXPECT_EQ(moves->comment, "tool [T2] reset   [ok");
}

// Found by fuzz_nc_program: machine-function words were kept as "%g" text, so M3444444 was written
// back as M3.44444e+06 (and S12345678 lost digits); they are kept as the shortest text that reads back.
TEST(NcProgram, LargeMachineFunctionWordsAreWrittenBackExactly) {
    const ba::NcProgram p = ba::parse_nc_program("G1 X1 F100 M3444444 S12345678.5 T7\n", ba::NcDialect::Fanuc);
    ASSERT_EQ(p.blocks.size(), 1u);
    EXPECT_EQ(p.blocks[0].extra_words, "M3444444 S12345678.5 T7");
    const std::string text = ba::write_nc_program(p);
    EXPECT_NO_THROW((void)ba::parse_nc_program(text, ba::NcDialect::Fanuc)) << text;
}

TEST(NcProgram, WriteThenParseRoundTripsBothDialects) {
    for (auto dialect : {ba::NcDialect::Fanuc, ba::NcDialect::LinuxCNC}) {
        ba::NcProgram p;
        p.dialect = dialect;
        ba::NcBlock a;
        a.motion = ba::NcMotion::Rapid;
        a.X_mm = -49.2751;
        a.Y_mm = 14.312;
        a.Z_mm = -177.777;
        a.A_rad = ba::deg_to_rad(10);
        a.C_rad = ba::deg_to_rad(-30.5);
        a.comment = "location 1 point 0";
        ba::NcBlock d;
        d.motion = ba::NcMotion::Dwell;
        d.dwell_s = 2.0;
        ba::NcBlock f;
        f.motion = ba::NcMotion::Feed;
        f.X_mm = 1;
        f.feed_mm_min = 1000;
        p.blocks = {a, d, f};
        const auto back = ba::parse_nc_program(ba::write_nc_program(p, "test"), dialect);
        std::vector<ba::NcBlock> motion;
        for (const auto& b : back.blocks)
            if (b.motion != ba::NcMotion::None) motion.push_back(b);
        ASSERT_EQ(motion.size(), 3u) << ba::write_nc_program(p, "test");
        EXPECT_NEAR(*motion[0].X_mm, -49.2751, 1e-4);
        EXPECT_NEAR(*motion[0].C_rad, ba::deg_to_rad(-30.5), ba::deg_to_rad(1e-4));
        EXPECT_EQ(motion[0].comment, "location 1 point 0");
        EXPECT_DOUBLE_EQ(motion[1].dwell_s, 2.0);
        EXPECT_DOUBLE_EQ(*motion[2].feed_mm_min, 1000);
    }
}

TEST(NcProgram, KeepsUninterpretedBlocksOnRewrite) {
    const auto p = ba::parse_nc_program("G90 G21\nT1 M6\nM3 S1000\nG0 X1\nG1 X2 F100 M8\nM30\n", ba::NcDialect::Fanuc);
    const std::string out = ba::write_nc_program(p);
    EXPECT_NE(out.find("T1 M6\n"), std::string::npos) << out;
    EXPECT_NE(out.find("M3 S1000\n"), std::string::npos) << out;
    EXPECT_NE(out.find("G1 X2.0000 M8 F100.0\n"), std::string::npos) << out;
    EXPECT_EQ(out.find("M30"), out.rfind("M30")) << "program end written once:\n" << out;
}

TEST(NcProgram, RefusesWhatItCannotRunWithTheLine) {
    struct Bad {
        const char* text;
        const char* says;
        int line;
    };
    const Bad bad[] = {
        {"G90\nG2 X1 Y1 I1\n", "unsupported G code G2", 2},
        {"G91\n", "G91", 1},
        {"G20\n", "inch", 1},
        {"G0 X1\nG4\n", "needs a P word", 2},
        {"X1\n", "before any G0/G1", 1},
        {"G0 X1..2\n", "malformed or out-of-range number", 1},
        {"G0 X\n", "has no number", 1},
        {"G0 X1 (open\n", "not closed", 1},
        {"G0 X1\nG1 F-5 X2\n", "positive", 2},
        {"G0 X1 P5\n", "P word outside", 1},
        {"G0 X1 #3\n", "unexpected character", 1},
    };
    for (const auto& b : bad) {
        try {
            ba::parse_nc_program(b.text, ba::NcDialect::Fanuc);
            ADD_FAILURE() << "accepted: " << b.text;
        } catch (const ba::NcError& e) {
            EXPECT_EQ(e.line(), b.line) << b.text;
            EXPECT_NE(std::string(e.what()).find(b.says), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("line " + std::to_string(b.line)), std::string::npos) << e.what();
        }
    }
}

TEST(NcProgram, ReaderStreamsTheSameBlocksAndResetsTheReusedOne) {
    const std::string text =
        "%\nO0001\nG90 G21\nG0 X1 Y2 (first) M8\nG1 Z3 F200\nX4\nT1 M6\nG4 P250\nG1 A10 C-20\nM30\n%\n";
    const auto whole = ba::parse_nc_program(text, ba::NcDialect::Fanuc);
    ba::NcReader reader(text, ba::NcDialect::Fanuc);
    ba::NcBlock b;
    ba::Pose pose;
    const auto poses = ba::resolve_poses(whole);
    std::size_t i = 0;
    while (reader.next(b)) {
        ASSERT_LT(i, whole.blocks.size());
        const ba::NcBlock& w = whole.blocks[i];
        EXPECT_EQ(b.line, w.line);
        EXPECT_EQ(b.motion, w.motion) << "line " << b.line;
        EXPECT_EQ(b.X_mm, w.X_mm) << "line " << b.line;
        EXPECT_EQ(b.Z_mm, w.Z_mm) << "line " << b.line;
        EXPECT_EQ(b.C_rad, w.C_rad) << "line " << b.line;
        EXPECT_EQ(b.feed_mm_min, w.feed_mm_min) << "line " << b.line;
        EXPECT_EQ(b.comment, w.comment) << "line " << b.line;
        EXPECT_EQ(b.extra_words, w.extra_words) << "line " << b.line;
        EXPECT_EQ(b.raw, w.raw) << "line " << b.line;
        pose = ba::pose_after(b, pose);
        EXPECT_EQ(pose.X_mm, poses[i].X_mm);
        EXPECT_EQ(pose.Z_mm, poses[i].Z_mm);
        ++i;
    }
    EXPECT_EQ(i, whole.blocks.size());
    EXPECT_FALSE(reader.next(b)) << "stays at the end";
    // The block after "G0 X1 Y2 (first) M8" kept none of its comment, words or axes.
    EXPECT_TRUE(whole.blocks[2].comment.empty());
    EXPECT_TRUE(whole.blocks[2].extra_words.empty());
    EXPECT_FALSE(whole.blocks[2].X_mm.has_value());
    // Only blocks without motion keep their source line.
    EXPECT_EQ(whole.blocks[0].raw, "G90 G21");
    EXPECT_TRUE(whole.blocks[1].raw.empty());
}

TEST(NcProgram, ReadsEverySpellingOfANumber) {
    const auto p = ba::parse_nc_program("G0 X+1.5 Y.25 Z-.75 A-0 C+.5\nG0 X7. Y-3\n", ba::NcDialect::Fanuc);
    ASSERT_EQ(p.blocks.size(), 2u);
    EXPECT_DOUBLE_EQ(*p.blocks[0].X_mm, 1.5);
    EXPECT_DOUBLE_EQ(*p.blocks[0].Y_mm, 0.25);
    EXPECT_DOUBLE_EQ(*p.blocks[0].Z_mm, -0.75);
    EXPECT_DOUBLE_EQ(*p.blocks[0].C_rad, ba::deg_to_rad(0.5));
    EXPECT_DOUBLE_EQ(*p.blocks[1].X_mm, 7);
    EXPECT_DOUBLE_EQ(*p.blocks[1].Y_mm, -3);
}

TEST(NcProgram, WritesFixedDecimalsLikePrintf) {
    ba::NcProgram p;
    ba::NcBlock b;
    b.motion = ba::NcMotion::Feed;
    b.X_mm = 1.23456;
    b.Y_mm = -0.00004;  // rounds to zero and keeps its sign, as printf's %.4f does
    b.Z_mm = 12345.5;
    b.feed_mm_min = 1500.04;
    p.blocks = {b};
    const std::string out = ba::write_nc_program(p);
    EXPECT_NE(out.find("G1 X1.2346 Y-0.0000 Z12345.5000 F1500.0\n"), std::string::npos) << out;
}

// append_nc_number is std::to_chars(fixed) at a fraction of its cost: the same text for every value
// in the controller's word format (at most 5 integer digits for X), ties (k / 2^j, exactly halfway at
// some decimal) and signed zeros included; every other value is refused (nc_program.hpp).
TEST(NcProgram, NumbersAreTheTextOfToCharsFixed) {
    std::mt19937_64 rng(17);
    std::vector<double> values{0.0,
                               -0.0,
                               0.5,
                               -0.5,
                               1.5,
                               2.5,
                               0.03125,
                               -0.03125,
                               1e-300,
                               -4e-5,
                               5e-5,
                               1e300,
                               std::numeric_limits<double>::denorm_min(),
                               9007199254740993.0,
                               9.3e18,
                               1e19,
                               std::numeric_limits<double>::infinity(),
                               std::nan("")};
    std::uniform_real_distribution<double> nc(-2000.0, 2000.0);
    std::uniform_int_distribution<int> exponent(-40, 70);
    for (int i = 0; i < 20000; ++i) {
        values.push_back(nc(rng));
        values.push_back(std::ldexp(nc(rng), exponent(rng)));
        values.push_back(std::ldexp(static_cast<double>(static_cast<int>(nc(rng) * 1000)), -(i % 24)));  // ties
    }
    for (int decimals = 0; decimals <= 8; ++decimals)
        for (double v : values) {
            char buf[400];
            buf[0] = ' ';
            buf[1] = 'X';
            const auto res = std::to_chars(buf + 2, buf + sizeof buf, v, std::chars_format::fixed, decimals);
            const std::string text(buf + 2, res.ptr);
            const std::size_t sign = text[0] == '-' ? 1 : 0;
            const bool fits = std::isfinite(v) && std::min(text.find('.'), text.size()) - sign <= 5;
            std::string out = "G1";
            if (!fits) {
                ASSERT_THROW(ba::append_nc_number(out, 'X', v, decimals), ba::AnalysisError) << v;
                ASSERT_EQ(out, "G1") << "nothing of a refused word is written";
                continue;
            }
            ba::append_nc_number(out, 'X', v, decimals);
            ASSERT_EQ(out, "G1" + std::string(buf, res.ptr)) << v << " with " << decimals << " decimals";
        }
}
