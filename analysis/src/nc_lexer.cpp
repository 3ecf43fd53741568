// SPDX-License-Identifier: MIT
#include "ballbar/analysis/nc_lexer.hpp"

#include <cctype>
#include <charconv>
#include <cmath>

#include "ballbar/analysis/decimal_text.hpp"
#include "ballbar/analysis/nc_program.hpp"

namespace ballbar::analysis {
namespace {

/// "1e308" after a word letter: a number NC does not have, named as such (not as a word E).
[[noreturn]] void exponent_number(std::string_view s, std::size_t start, std::size_t i, int line, char letter) {
    std::size_t end = i + 1;
    while (end < s.size() &&
           (std::isalnum(static_cast<unsigned char>(s[end])) || s[end] == '+' || s[end] == '-' || s[end] == '.'))
        ++end;
    throw NcError(line, std::string("word ") + letter + " has a malformed or out-of-range number '" +
                            shown_token(s.substr(start, end - start)) +
                            "' (NC numbers are plain decimals, without an exponent)");
}

/// A number after a word letter: [+-]digits[.digits] (no exponent, no nan/inf: NC has none).
double plain_number(std::string_view s, std::size_t& i, int line, char letter);

double number_of(std::string_view s, std::size_t& i, int line, char letter) {
    const std::size_t start = i;
    const double v = plain_number(s, i, line, letter);
    if (exponent_at(s, i)) exponent_number(s, start, i, line, letter);
    return v;
}

double plain_number(std::string_view s, std::size_t& i, int line, char letter) {
    const std::size_t start = i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    // The common case, a digit first: the exact fast path (decimal_text.hpp), else from_chars (no exponent) in one
    // pass. It is the number below when it ends where the run of digits and points does (a second point: malformed).
    if (i < s.size() && s[i] >= '0' && s[i] <= '9') {
        double v = 0;
        if (std::size_t k = i; read_short_decimal(s, k, v) && v <= kMaxNcNumber) {
            i = k;
            return s[start] == '-' ? -v : v;
        }
        const auto res = std::from_chars(s.data() + i, s.data() + s.size(), v, std::chars_format::fixed);
        const auto end = static_cast<std::size_t>(res.ptr - s.data());
        if (res.ec == std::errc() && (end == s.size() || !((s[end] >= '0' && s[end] <= '9') || s[end] == '.')) &&
            std::isfinite(v) && std::abs(v) <= kMaxNcNumber) {
            i = end;
            return s[start] == '-' ? -v : v;
        }
    }
    std::size_t digits = 0;
    while (i < s.size() && ((s[i] >= '0' && s[i] <= '9') || s[i] == '.')) {
        if (s[i] != '.') ++digits;
        ++i;
    }
    if (digits == 0) {
        throw NcError(line, std::string("word ") + letter + " has no number");
    }
    std::string_view num = s.substr(start, i - start);
    bool negative = false;
    if (num.front() == '+' || num.front() == '-') {
        negative = num.front() == '-';
        num.remove_prefix(1);
    }
    char buf[80];
    if (num.front() == '.') {  // from_chars needs a digit first
        if (num.size() + 1 > sizeof buf) throw NcError(line, std::string("word ") + letter + ": number too long");
        buf[0] = '0';
        num.copy(buf + 1, num.size());
        num = std::string_view(buf, num.size() + 1);
    }
    double v = 0;
    const auto res = std::from_chars(num.data(), num.data() + num.size(), v);
    if (res.ec != std::errc() || res.ptr != num.data() + num.size() || !std::isfinite(v) || std::abs(v) > kMaxNcNumber)
        throw NcError(line, std::string("word ") + letter + " has a malformed or out-of-range number '" +
                                shown_token(s.substr(start, i - start)) + "'");
    return negative ? -v : v;
}

}  // namespace

std::string_view split_nc_comments(std::string_view raw, int line, bool semicolon_comments, std::string& buffer,
                                   std::string& comment) {
    // Whether the line has a comment at all: memchr, vectorised (find_first_of would call it per character).
    if (raw.find('(') == std::string_view::npos && (!semicolon_comments || raw.find(';') == std::string_view::npos))
        return raw;
    buffer.clear();
    buffer.reserve(raw.size());
    for (std::size_t i = 0; i < raw.size(); ++i) {
        const char c = raw[i];
        if (c == '(') {
            const std::size_t close = raw.find(')', i + 1);
            if (close == std::string_view::npos) throw NcError(line, "comment opened with '(' is not closed");
            if (!comment.empty()) comment += ' ';
            comment += trim_nc_blanks(raw.substr(i + 1, close - i - 1));
            i = close;
        } else if (c == ';' && semicolon_comments) {
            if (!comment.empty()) comment += ' ';
            comment += trim_nc_blanks(raw.substr(i + 1));
            break;
        } else {
            buffer += c;
        }
    }
    return buffer;
}

double read_nc_number(std::string_view text, std::size_t& pos, int line, char letter) {
    return number_of(text, pos, line, letter);
}

}  // namespace ballbar::analysis
