// SPDX-License-Identifier: MIT
// How the report prints numbers, restated independently for the tests that search the PDF's text.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

namespace ballbar::report::testing {

inline std::string fixed_text(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    std::string s(buf);
    if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
    return s;
}

/// "v ± u" with 2 decimals, the uncertainty with up to 4 so that it does not round to zero.
inline std::string plus_minus_text(double v, double u) {
    int d = 2;
    while (u > 0 && d < 4 && std::abs(u) < 0.5 * std::pow(10.0, -d)) ++d;
    return fixed_text(v, 2) + " ± " + fixed_text(std::abs(u), d);
}

}  // namespace ballbar::report::testing
