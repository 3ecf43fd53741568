// SPDX-License-Identifier: MIT
// Reading the short decimal numbers of NC programs and readings files ("100.0000", "0.0023329") at a
// fraction of std::from_chars' cost, with its result bit for bit.
#pragma once

#include <cstddef>
#include <string_view>

namespace ballbar::analysis {

/// Reads digits[.digits] at text[pos] when both the digits (as an integer w ≤ 2^53) and 10^k (k
/// decimals ≤ 22) are exact doubles: then w / 10^k, one correctly rounded division, is the correctly
/// rounded value std::from_chars gives (Clinger's fast path). Advances `pos` past the number and
/// returns true; returns false, leaving `pos`, for anything else (a sign, more digits, a second
/// point, a point without digits after it, an exponent): from_chars reads those.
bool read_short_decimal(std::string_view text, std::size_t& pos, double& value);

}  // namespace ballbar::analysis
