// SPDX-License-Identifier: MIT
// The lexical layer of NC programs that every reader shares — the program reader (nc_program.hpp), the
// interpreter of CAM programs (nc_interpreter.hpp) and the emulator's continuous machine — each keeping
// its own dialect rules (which words it takes, what a G code means) on top: how a line's comments are
// found, and how a word's number is read.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace ballbar::analysis {

/// NC text is ASCII: a blank is the "C" locale's space class, without a library call per character.
constexpr bool is_nc_blank(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

/// `s` without its leading and trailing blanks.
constexpr std::string_view trim_nc_blanks(std::string_view s) {
    while (!s.empty() && is_nc_blank(s.front())) s.remove_prefix(1);
    while (!s.empty() && is_nc_blank(s.back())) s.remove_suffix(1);
    return s;
}

/// Numbers larger than this are refused: no NC value is that large (1000 km, 10⁹ degrees).
inline constexpr double kMaxNcNumber = 1e9;

/// Splits a line into its code and its comments: "( … )" anywhere (an unclosed one is an NcError naming
/// the line), and "; …" to the end of the line where `semicolon_comments`. The comments' text, trimmed,
/// is appended to `comment` (space separated). Returns the code: `raw` itself when the line has no
/// comment (nothing copied), else a view of `buffer`, which holds it.
std::string_view split_nc_comments(std::string_view raw, int line, bool semicolon_comments, std::string& buffer,
                                   std::string& comment);

/// The number of the word `letter` at `pos`: [+-]digits[.digits] or [+-].digits — a plain decimal (NC has
/// no exponent, nan or inf), at most kMaxNcNumber. Leaves `pos` after it. NcError naming the line and the
/// word: "word X has no number", "word X has a malformed or out-of-range number '…'" (an exponent named
/// as such, not read as a word E).
double read_nc_number(std::string_view text, std::size_t& pos, int line, char letter);

}  // namespace ballbar::analysis
