// SPDX-License-Identifier: MIT
// Every number written to an NC program is finite and in the controller's word format, or refused
// naming the word; the range checks every input layer uses (analysis/limits.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "ballbar/analysis/limits.hpp"
#include "ballbar/analysis/nc_program.hpp"

namespace ballbar::analysis {
namespace {

struct Word {
    const char* name;
    char letter;
    double value;
    int decimals;
    const char* written;  ///< nullptr: refused
};

void PrintTo(const Word& w, std::ostream* os) {
    *os << w.name;
}

class NcWordFormat : public ::testing::TestWithParam<Word> {};

TEST_P(NcWordFormat, IsWrittenOrRefusedNamingTheWord) {
    const Word& w = GetParam();
    std::string out;
    if (w.written) {
        append_nc_number(out, w.letter, w.value, w.decimals);
        EXPECT_EQ(out, std::string(" ") + w.letter + w.written);
        EXPECT_EQ(nc_word_problem(w.letter, w.value, w.decimals), "");
        return;
    }
    try {
        append_nc_number(out, w.letter, w.value, w.decimals);
        FAIL() << "wrote " << out;
    } catch (const AnalysisError& e) {
        EXPECT_NE(std::string(e.what()).find(std::string("NC word ") + w.letter), std::string::npos) << e.what();
        EXPECT_EQ(std::string(e.what()), nc_word_problem(w.letter, w.value, w.decimals));
    }
    EXPECT_TRUE(out.empty()) << "nothing of a refused word is written: " << out;
}

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

INSTANTIATE_TEST_SUITE_P(
    Words, NcWordFormat,
    ::testing::Values(Word{"X_ordinary", 'X', -12.34567, 4, "-12.3457"},
                      Word{"X_largest", 'X', 99999.9999, 4, "99999.9999"},
                      Word{"X_six_digits", 'X', 100000.0, 4, nullptr}, Word{"X_1e308", 'X', 1e308, 4, nullptr},
                      Word{"X_minus_1e308", 'X', -1e308, 4, nullptr}, Word{"X_inf", 'X', kInf, 4, nullptr},
                      Word{"X_nan", 'X', kNan, 4, nullptr}, Word{"C_1e20_deg", 'C', 1e20, 4, nullptr},
                      Word{"I_negative", 'I', -50.0, 4, "-50.0000"}, Word{"F_ordinary", 'F', 2000.0, 1, "2000.0"},
                      Word{"F_1e_minus_300", 'F', 1e-300, 1, nullptr}, Word{"F_rounds_to_zero", 'F', 0.04, 1, nullptr},
                      Word{"F_smallest", 'F', 0.1, 1, "0.1"}, Word{"F_1e308", 'F', 1e308, 1, nullptr},
                      Word{"F_seven_digits", 'F', 1e6, 1, nullptr}, Word{"F_negative", 'F', -100.0, 1, nullptr},
                      Word{"F_zero", 'F', 0.0, 1, nullptr}, Word{"P_ms", 'P', 1500.0, 0, "1500"},
                      Word{"P_negative", 'P', -1.0, 0, nullptr}, Word{"P_nine_digits", 'P', 1e9, 0, nullptr},
                      Word{"P_inf", 'P', kInf, 0, nullptr}, Word{"decimals_beyond_8", 'X', 1.0, 9, nullptr}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(NcWordFormat, ADwellBeyondTheControllersPWordIsRefused) {
    NcBlock b;
    b.motion = NcMotion::Dwell;
    for (const double s : {1e308, kInf, -1.0, 100000.0}) {
        b.dwell_s = s;
        for (const NcDialect d : {NcDialect::Fanuc, NcDialect::LinuxCNC}) {
            std::string out;
            try {
                write_nc_block(out, b, d);
                FAIL() << "wrote " << out;
            } catch (const AnalysisError& e) {
                EXPECT_NE(std::string(e.what()).find("G4 dwell"), std::string::npos) << e.what();
            }
        }
    }
    b.dwell_s = 99999.999;
    std::string out;
    write_nc_block(out, b, NcDialect::Fanuc);
    EXPECT_EQ(out, "G4 P99999999\n");
}

TEST(NcWordFormat, AFeedOfTheWriterIsCheckedInEveryBlock) {
    NcBlock b;
    b.motion = NcMotion::Feed;
    b.X_mm = 1;
    b.feed_mm_min = 1e-300;
    std::string out;
    EXPECT_THROW(write_nc_block(out, b, NcDialect::Fanuc), AnalysisError);
    b.feed_mm_min = 1e308;
    EXPECT_THROW(write_nc_block(out, b, NcDialect::LinuxCNC), AnalysisError);
}

TEST(Limits, CheckInNamesTheValueAndTheRange) {
    EXPECT_EQ(limits::check_in(5, 0, 10, "mm"), "");
    EXPECT_EQ(limits::check_in(1e308, -1e5, 1e5, "mm"), "= 1e+308 is outside [-100000, 100000] mm");
    EXPECT_EQ(limits::check_in(kNan, 0, 1, "s"), "is not a finite number");
    EXPECT_EQ(limits::check_in(-kInf, 0, 1, "s"), "is not a finite number");
    EXPECT_EQ(limits::check_above(0, 0, 10, "mm"), "= 0 must be > 0 and <= 10 mm");
    EXPECT_EQ(limits::check_above(1e-300, 0, 10, ""), "");
    EXPECT_EQ(limits::check_integer_in(-1, 0, 100), "= -1 is not an integer in [0, 100]");
    EXPECT_EQ(limits::check_integer_in(2.5, 0, 100), "= 2.5 is not an integer in [0, 100]");
    EXPECT_EQ(limits::check_integer_in(3, 0, 100), "");
}

TEST(Limits, ErrorParametersHaveTheRangeOfTheirUnit) {
    EXPECT_EQ(limits::check_param(Param::X0C, 0.05), "");
    EXPECT_NE(limits::check_param(Param::X0C, 1e308).find("mm"), std::string::npos);
    EXPECT_NE(limits::check_param(Param::B0A, 4.0).find("rad"), std::string::npos);
    EXPECT_EQ(limits::check_param(Param::B0A, 1e-4), "");
    EXPECT_NE(limits::check_param(Param::bar_kappa, 0.1), "");
    EXPECT_EQ(limits::check_param(Param::Y0A, 50.0), "") << "a model of another machine: compensate's bounds say so";
}

}  // namespace
}  // namespace ballbar::analysis
