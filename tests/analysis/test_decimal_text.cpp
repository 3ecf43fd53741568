// SPDX-License-Identifier: MIT
// read_short_decimal: what it takes (digits[.digits] whose integer and power of ten are exact
// doubles), where it stops, and that what it reads is bit for bit what std::from_chars reads.
#include <gtest/gtest.h>

#include <bit>
#include <charconv>
#include <cstdint>
#include <random>
#include <string>

#include "ballbar/analysis/decimal_text.hpp"

namespace {

using ballbar::analysis::read_short_decimal;

double from_chars_value(const std::string& t) {
    double v = 0;
    std::from_chars(t.data(), t.data() + t.size(), v);
    return v;
}

TEST(DecimalText, ReadsShortDecimalsAsFromCharsDoes) {
    std::mt19937_64 rng(11);
    for (int i = 0; i < 200000; ++i) {
        // Up to 20 digits in all: both sides of the 15-digit limit below which no check is needed.
        const int digits = 1 + static_cast<int>(rng() % 12);
        const int decimals = static_cast<int>(rng() % 12);
        std::string t;
        for (int d = 0; d < digits; ++d) t += static_cast<char>('0' + rng() % 10);
        if (decimals > 0) t += '.';
        for (int d = 0; d < decimals; ++d) t += static_cast<char>('0' + rng() % 10);
        std::size_t pos = 0;
        double v = -1;
        if (!read_short_decimal(t, pos, v)) continue;  // from_chars's to read
        ASSERT_EQ(pos, t.size()) << t;
        ASSERT_EQ(std::bit_cast<std::uint64_t>(v), std::bit_cast<std::uint64_t>(from_chars_value(t))) << t;
    }
}

TEST(DecimalText, TakesWhatIsExactAndLeavesTheRest) {
    auto reads = [](const std::string& t, std::size_t from = 0) {
        std::size_t pos = from;
        double v = 0;
        const bool ok = read_short_decimal(t, pos, v);
        if (!ok) {
            EXPECT_EQ(pos, from) << t;  // a refusal leaves pos
        }
        return ok ? static_cast<long long>(pos) : -1LL;
    };
    EXPECT_EQ(reads("0"), 1);
    EXPECT_EQ(reads("101.8178703,0.5"), 11);  // stops at the comma
    EXPECT_EQ(reads("x12.5", 1), 5);
    EXPECT_EQ(reads(""), -1);
    EXPECT_EQ(reads(".5"), -1);     // a point first
    EXPECT_EQ(reads("7."), -1);     // a point without digits after it
    EXPECT_EQ(reads("1.2.3"), -1);  // a second point
    EXPECT_EQ(reads("1e5"), -1);    // an exponent
    EXPECT_EQ(reads("1.5E-3"), -1);
    EXPECT_EQ(reads("-1"), -1);  // a sign
    // 15 digits always; more while the integer stays below 2^53 / 10 before each digit.
    EXPECT_EQ(reads("999999999999999"), 15);
    EXPECT_EQ(reads("9007199254740991"), -1);           // 2^53 − 1: past the limit before its last digit
    EXPECT_EQ(reads("0000000000000000000001.5"), 24);   // leading zeros keep the integer small
    EXPECT_EQ(reads("0.0000000000000000000001"), 24);   // 22 decimals: 10^22 is exact
    EXPECT_EQ(reads("0.00000000000000000000001"), -1);  // 23: it is not
}

}  // namespace
