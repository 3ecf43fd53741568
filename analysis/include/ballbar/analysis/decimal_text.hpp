// SPDX-License-Identifier: MIT
// Reading the short decimal numbers of NC programs and readings files ("100.0000", "0.0023329") at a
// fraction of std::from_chars' cost, with its result bit for bit.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace ballbar::analysis {

/// Reads digits[.digits] at text[pos] when both the digits (as an integer w ≤ 2^53) and 10^k (k
/// decimals ≤ 22) are exact doubles: then w / 10^k, one correctly rounded division, is the correctly
/// rounded value std::from_chars gives (Clinger's fast path). Advances `pos` past the number and
/// returns true; returns false, leaving `pos`, for anything else (a sign, more digits, a second
/// point, a point without digits after it, an exponent): from_chars reads those.
bool read_short_decimal(std::string_view text, std::size_t& pos, double& value);

/// True when text[pos] starts an exponent ("e308", "E-5") right after a number: NC numbers have none,
/// so "X1e308" is a malformed number, not an X word followed by an E word.
bool exponent_at(std::string_view text, std::size_t pos);

/// A token of the user's text for an error message: at most `max_chars` bytes (at a UTF-8 boundary),
/// "…" appended when cut.
std::string shown_token(std::string_view token, std::size_t max_chars = 40);

}  // namespace ballbar::analysis
