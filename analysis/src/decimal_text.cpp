// SPDX-License-Identifier: MIT
#include "ballbar/analysis/decimal_text.hpp"

#include <cstdint>

namespace ballbar::analysis {

bool read_short_decimal(std::string_view s, std::size_t& pos, double& value) {
    static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                        1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    constexpr std::uint64_t kExact = std::uint64_t{1} << 53;
    auto digit = [&s](std::size_t k) { return k < s.size() && s[k] >= '0' && s[k] <= '9'; };
    std::size_t k = pos;
    if (!digit(k)) return false;
    std::uint64_t w = 0;
    int decimals = 0;
    for (; digit(k); ++k) {
        if (w >= kExact / 10) return false;  // w·10 + d may pass 2^53
        w = w * 10 + static_cast<std::uint64_t>(s[k] - '0');
    }
    if (k < s.size() && s[k] == '.') {
        if (!digit(++k)) return false;
        for (; digit(k); ++k, ++decimals) {
            if (w >= kExact / 10 || decimals == 22) return false;
            w = w * 10 + static_cast<std::uint64_t>(s[k] - '0');
        }
    }
    if (k < s.size() && (s[k] == '.' || s[k] == 'e' || s[k] == 'E')) return false;
    value = static_cast<double>(w) / kPow10[decimals];
    pos = k;
    return true;
}

bool exponent_at(std::string_view text, std::size_t pos) {
    if (pos >= text.size() || (text[pos] != 'e' && text[pos] != 'E')) return false;
    std::size_t k = pos + 1;
    if (k < text.size() && (text[k] == '+' || text[k] == '-')) ++k;
    return k < text.size() && text[k] >= '0' && text[k] <= '9';
}

std::string shown_token(std::string_view token, std::size_t max_chars) {
    if (token.size() <= max_chars) return std::string(token);
    std::size_t n = max_chars;
    while (n > 0 && (static_cast<unsigned char>(token[n]) & 0xC0) == 0x80) --n;
    return std::string(token.substr(0, n)) + "…";
}

}  // namespace ballbar::analysis
