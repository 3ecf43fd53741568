// SPDX-License-Identifier: MIT
// A value written at the resolution it was measured or given in, so that its text is the short decimal
// a person wrote or an instrument sent (20.3, not 20.299999237060547; 30°, not 29.999999999999996°).
#pragma once

#include <cmath>

namespace ballbar::analysis {

/// x rounded to `decimals` decimal places, as the double nearest that decimal: x·10^d rounded to a whole
/// number, then one correctly rounded division by the exact 10^d (decimals ≤ 22). Non-finite x is
/// returned as it is.
inline double decimal_round(double x, int decimals) {
    if (!std::isfinite(x) || decimals < 0 || decimals > 22) return x;
    double p = 1;
    for (int i = 0; i < decimals; ++i) p *= 10;
    const double scaled = x * p;
    if (!std::isfinite(scaled) || std::abs(scaled) >= 9007199254740992.0) return x;  // beyond 2^53: as it is
    return std::round(scaled) / p;
}

}  // namespace ballbar::analysis
