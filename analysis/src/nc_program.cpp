// SPDX-License-Identifier: MIT
#include "ballbar/analysis/nc_program.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>

#include "ballbar/analysis/decimal_text.hpp"
#include "ballbar/analysis/limits.hpp"
#include "ballbar/analysis/nc_lexer.hpp"

namespace ballbar::analysis {
namespace {

constexpr char to_upper(char c) {
    return c >= 'a' && c <= 'z' ? static_cast<char>(c - 'a' + 'A') : c;
}

/// Removes "( ... )" comments (both dialects) and "; ..." (LinuxCNC) from a line; returns the comment text
/// (nc_lexer.hpp).
std::string strip_comments(std::string& code, int line, NcDialect dialect) {
    std::string comment, buffer;
    const std::string_view rest = split_nc_comments(code, line, dialect == NcDialect::LinuxCNC, buffer, comment);
    if (rest.size() != code.size()) code = std::string(rest);
    return comment;
}

/// Lines the writer emits itself: absolute/metric set-up and program end.
bool is_framing(std::string_view body) {
    return body == "G90 G21" || body == "G90" || body == "G21" || body == "G21 G90" || body == "M30" || body == "M2" ||
           body == "M02" || body == "%";
}

bool is_integer(double v) {
    return std::floor(v) == v;
}

NcMotion motion_for_g(double g, int line) {
    if (g == 0) return NcMotion::Rapid;
    if (g == 1) return NcMotion::Feed;
    if (g == 4) return NcMotion::Dwell;
    char num[32];
    std::snprintf(num, sizeof num, "%g", g);
    throw NcError(line, std::string("unsupported G code G") + num + " (ballbar runs G0, G1, G4 in G90/G21)");
}

__extension__ typedef unsigned __int128 Uint128;  // GCC and Clang; -Wpedantic knows it as an extension

/// The fixed-notation digits of |value| × 10^decimals, rounded to nearest with ties to even, from the
/// exact binary value m·2^e: m·10^d fits 128 bits (m < 2^53, 10^8 < 2^27), so one multiplication and
/// one shift give the quotient and the remainder that decides the rounding. False when |value| ≥ 2^63
/// (or not finite): std::to_chars does those.
bool fixed_digits(double value, int decimals, std::uint64_t& int_part, std::uint64_t& frac_part) {
    static constexpr std::uint64_t kPow10[] = {1, 10, 100, 1000, 10000, 100000, 1000000, 10000000, 100000000};
    if (decimals < 0 || decimals > 8) return false;
    const auto bits = std::bit_cast<std::uint64_t>(value);
    const auto biased = static_cast<int>((bits >> 52) & 0x7FF);
    const std::uint64_t fraction = bits & ((std::uint64_t{1} << 52) - 1);
    if (biased == 0x7FF) return false;  // inf, nan
    const std::uint64_t m = biased == 0 ? fraction : fraction | (std::uint64_t{1} << 52);
    const int e = (biased == 0 ? 1 : biased) - 1075;  // value = ±m·2^e
    const std::uint64_t scale = kPow10[decimals];
    Uint128 n = 0;  // round(|value| · 10^decimals)
    if (e >= 0) {
        if (e > 10) return false;  // m·2^e ≥ 2^63 possible
        n = static_cast<Uint128>(m << e) * scale;
    } else if (-e <= 80) {  // beyond, m·10^d < 2^80 is below half a unit: zero
        const int s = -e;
        const Uint128 p = static_cast<Uint128>(m) * scale;
        n = p >> s;
        const Uint128 rem = p - (n << s), half = Uint128{1} << (s - 1);
        if (rem > half || (rem == half && (n & 1) != 0)) ++n;
    }
    if (n > std::numeric_limits<std::uint64_t>::max()) {
        int_part = static_cast<std::uint64_t>(n / scale);
        frac_part = static_cast<std::uint64_t>(n % scale);
    } else {  // NC words: a 64-bit division
        int_part = static_cast<std::uint64_t>(n) / scale;
        frac_part = static_cast<std::uint64_t>(n) % scale;
    }
    return true;
}

/// What a word of `letter` may hold (the controller's word format).
struct NcWordRange {
    std::uint64_t max_integer = 99'999;  ///< largest integer part
    bool negative = true;                ///< negative values allowed
    bool positive = false;               ///< must be > 0 once written (a feed)
};

NcWordRange nc_word_range(char letter, int /*decimals*/) {
    if (letter == 'F') return {999'999, false, true};
    if (letter == 'P') return {99'999'999, false, false};
    return {};
}

}  // namespace

std::string nc_word_problem(char letter, double value, int decimals) {
    const NcWordRange r = nc_word_range(letter, decimals);
    if (decimals < 0 || decimals > 8)
        return std::string("NC word ") + letter + ": " + std::to_string(decimals) + " decimals (the format has 0 to 8)";
    std::uint64_t int_part = 0, frac_part = 0;
    const bool fits =
        std::isfinite(value) && std::abs(value) < 1e15 && fixed_digits(value, decimals, int_part, frac_part);
    const bool zero = int_part == 0 && frac_part == 0;
    const bool negative = std::signbit(value) && !zero;
    if (fits && int_part <= r.max_integer && (r.negative || !negative) && !(r.positive && (zero || negative)))
        return {};
    std::string why = std::string("NC word ") + letter + ": " + limits::number_text(value) + " ";
    if (!std::isfinite(value)) return why + "is not a finite number";
    why += "does not fit the controller's word format (";
    const std::string max = std::to_string(r.max_integer) +
                            (decimals > 0 ? "." + std::string(static_cast<std::size_t>(decimals), '9') : std::string());
    if (r.positive)
        why += "0 < " + std::string(1, letter) + " <= " + max + ", written with " + std::to_string(decimals) +
               " decimal" + (decimals == 1 ? "" : "s");
    else if (!r.negative)
        why += "0 <= " + std::string(1, letter) + " <= " + max;
    else
        why += "|" + std::string(1, letter) + "| <= " + max;
    return why + ")";
}

void append_nc_number(std::string& out, char letter, double value, int decimals) {
    const NcWordRange r = nc_word_range(letter, decimals);
    char buf[64];
    buf[0] = ' ';
    buf[1] = letter;
    char* p = buf + 2;
    std::uint64_t int_part = 0, frac_part = 0;
    // Every word is finite and within its format: X/Y/Z/A/B/C/I/J/K/R at most 5 integer digits, F
    // positive (not rounded to zero) with at most 6, P not negative with at most 8 (docs/cli.md).
    if (decimals < 0 || decimals > 8 || !fixed_digits(value, decimals, int_part, frac_part) || int_part > r.max_integer)
        throw AnalysisError(nc_word_problem(letter, value, decimals));
    const bool zero = int_part == 0 && frac_part == 0;
    if ((r.positive && (zero || std::signbit(value))) || (!r.negative && std::signbit(value) && !zero))
        throw AnalysisError(nc_word_problem(letter, value, decimals));
    if (std::signbit(value) && r.negative) *p++ = '-';  // (F and P: only a zero gets here with its sign)
    p = std::to_chars(p, buf + sizeof buf, int_part).ptr;
    if (decimals > 0) {
        *p++ = '.';
        for (int k = decimals - 1; k >= 0; --k, frac_part /= 10) p[k] = static_cast<char>('0' + frac_part % 10);
        p += decimals;
    }
    out.append(buf, static_cast<std::size_t>(p - buf));  // (pointer, length): the iterator pair goes through replace()
}

NcError::NcError(int line, const std::string& message)
    : AnalysisError("line " + std::to_string(line) + ": " + message), line_(line) {}

std::string_view to_string(NcDialect d) {
    return d == NcDialect::Fanuc ? "fanuc" : "linuxcnc";
}

std::optional<NcDialect> parse_nc_dialect(std::string_view text) {
    if (text == "fanuc") return NcDialect::Fanuc;
    if (text == "linuxcnc") return NcDialect::LinuxCNC;
    return std::nullopt;
}

NcReader::NcReader(std::string_view text, NcDialect dialect) : text_(text), dialect_(dialect) {}

bool NcReader::next(NcBlock& block) {
    const std::string_view text = text_;
    const NcDialect dialect = dialect_;
    NcMotion& modal = modal_;
    int& line_no = line_;
    std::size_t& pos = pos_;
    while (pos <= text.size()) {
        std::size_t end = text.find('\n', pos);
        if (end == std::string_view::npos) end = text.size();
        std::string_view raw = text.substr(pos, end - pos);
        pos = end + 1;
        ++line_no;
        if (!raw.empty() && raw.back() == '\r') raw.remove_suffix(1);
        if (end == text.size() && raw.empty()) break;

        // The caller's block is reused: its strings keep their capacity.
        block.line = line_no;
        block.motion = NcMotion::None;
        block.X_mm.reset();
        block.Y_mm.reset();
        block.Z_mm.reset();
        block.A_rad.reset();
        block.B_rad.reset();
        block.C_rad.reset();
        block.feed_mm_min.reset();
        block.dwell_s = 0;
        block.comment.clear();
        block.extra_words.clear();
        block.raw.clear();
        // Most lines have no comment: parse them in place, without copying the line.
        std::string code;
        std::string_view body = raw;
        if (raw.find('(') != std::string_view::npos ||
            (dialect == NcDialect::LinuxCNC && raw.find(';') != std::string_view::npos)) {
            code = std::string(raw);
            block.comment = strip_comments(code, line_no, dialect);
            body = code;
        }
        body = trim_nc_blanks(body);
        if (body == "%") continue;  // Fanuc tape framing
        if (!body.empty() && (body.front() == 'O' || body.front() == 'o') && dialect == NcDialect::Fanuc) {
            continue;  // program number
        }

        std::optional<double> p_word;
        bool has_axis = false;
        bool has_g_motion = false;
        std::size_t i = 0;
        while (i < body.size()) {
            const char c = to_upper(body[i]);
            if (is_nc_blank(c)) {
                ++i;
                continue;
            }
            if (c < 'A' || c > 'Z') throw NcError(line_no, std::string("unexpected character '") + body[i] + "'");
            ++i;
            while (i < body.size() && body[i] == ' ') ++i;
            const double v = read_nc_number(body, i, line_no, c);
            switch (c) {
                case 'N':
                    break;  // sequence number
                case 'G':
                    if (v == 90 || v == 21 || v == 17 || v == 94 || v == 40 || v == 49 || v == 80) break;
                    if (v == 91) throw NcError(line_no, "G91 (incremental) is not supported: ballbar programs are G90");
                    if (v == 20)
                        throw NcError(line_no, "G20 (inch) is not supported: ballbar programs are in mm (G21)");
                    block.motion = motion_for_g(v, line_no);
                    has_g_motion = true;
                    if (block.motion != NcMotion::Dwell) modal = block.motion;
                    break;
                case 'M':
                case 'S':
                case 'T': {
                    // Machine functions (coolant, spindle, tool change): not simulated, kept on rewrite.
                    if (c != 'S' && !is_integer(v))
                        throw NcError(line_no, std::string(1, c) + " word must be an integer");
                    // The shortest fixed-point text that reads back to v ("%g" wrote M3444444 as
                    // M3.44444e+06, which no reader takes back; found by fuzz_nc_program).
                    std::array<char, 400> word{};
                    word[0] = c;
                    const auto [last, ec] =
                        std::to_chars(word.data() + 1, word.data() + word.size(), v, std::chars_format::fixed);
                    if (ec != std::errc()) throw NcError(line_no, std::string(1, c) + " word out of range");
                    if (!block.extra_words.empty()) block.extra_words += ' ';
                    block.extra_words.append(word.data(), last);
                    break;
                }
                case 'X':
                    block.X_mm = v;
                    has_axis = true;
                    break;
                case 'Y':
                    block.Y_mm = v;
                    has_axis = true;
                    break;
                case 'Z':
                    block.Z_mm = v;
                    has_axis = true;
                    break;
                case 'A':
                    block.A_rad = deg_to_rad(v);
                    has_axis = true;
                    break;
                case 'B':
                    block.B_rad = deg_to_rad(v);
                    has_axis = true;
                    break;
                case 'C':
                    block.C_rad = deg_to_rad(v);
                    has_axis = true;
                    break;
                case 'F':
                    if (v <= 0) throw NcError(line_no, "feed F must be positive");
                    block.feed_mm_min = v;
                    break;
                case 'P':
                    p_word = v;
                    break;
                default:
                    throw NcError(line_no, std::string("unsupported word ") + c);
            }
        }
        if (block.motion == NcMotion::Dwell) {
            if (!p_word) throw NcError(line_no, "G4 needs a P word (dwell time)");
            if (*p_word < 0) throw NcError(line_no, "G4 dwell time must not be negative");
            // Fanuc: P in milliseconds; LinuxCNC: P in seconds.
            block.dwell_s = dialect == NcDialect::Fanuc ? *p_word / 1000.0 : *p_word;
            if (has_axis) throw NcError(line_no, "G4 with axis words: dwell and motion must be separate blocks");
        } else if (p_word) {
            throw NcError(line_no, "P word outside a G4 dwell");
        }
        if (has_axis && !has_g_motion) {
            if (modal == NcMotion::None) throw NcError(line_no, "axis words before any G0/G1");
            block.motion = modal;
        }
        if (block.motion == NcMotion::None) {
            if (block.comment.empty() && body.empty()) continue;
            block.raw = raw;  // words ballbar does not interpret are kept on rewrite
        }
        return true;
    }
    pos = text.size() + 1;
    return false;
}

NcProgram parse_nc_program(std::string_view text, NcDialect dialect) {
    NcProgram program;
    program.dialect = dialect;
    NcReader reader(text, dialect);
    NcBlock block;
    while (reader.next(block)) program.blocks.push_back(block);
    return program;
}

void write_nc_header(std::string& out, NcDialect dialect, std::string_view title) {
    const bool fanuc = dialect == NcDialect::Fanuc;
    if (fanuc) {
        out += "%\nO0001";
        if (!title.empty()) out.append(" (").append(title).append(")");
        out += '\n';
    } else if (!title.empty()) {
        out.append("(").append(title).append(")\n");
    }
    out += "G90 G21\n";
}

void write_nc_block(std::string& out, const NcBlock& b, NcDialect dialect) {
    const bool fanuc = dialect == NcDialect::Fanuc;
    if (b.motion == NcMotion::None && !b.raw.empty()) {
        // A block ballbar does not interpret (M3 S1000, T1 M6, ...): kept verbatim, except the
        // framing this writer adds itself.
        std::string code = b.raw;
        strip_comments(code, b.line, dialect);
        const std::string_view body = trim_nc_blanks(code);
        if (!body.empty()) {
            if (!is_framing(body)) {
                out += trim_nc_blanks(b.raw);
                out += '\n';
            }
            return;
        }
    }
    // The line is built in place at the end of `out`; nothing is appended for an empty block.
    const std::size_t start = out.size();
    switch (b.motion) {
        case NcMotion::Rapid:
            out += "G0";
            break;
        case NcMotion::Feed:
            out += "G1";
            break;
        case NcMotion::Dwell:
            if (!(b.dwell_s >= 0 && b.dwell_s <= kMaxDwell_s))
                throw AnalysisError("G4 dwell " + limits::number_text(b.dwell_s) + " s" +
                                    (b.line > 0 ? " (line " + std::to_string(b.line) + ")" : std::string()) +
                                    " does not fit the controller's P word (0 to 99999.999 s)");
            out += "G4";
            if (fanuc)
                append_nc_number(out, 'P', std::round(b.dwell_s * 1000.0), 0);
            else
                append_nc_number(out, 'P', b.dwell_s, 3);
            break;
        case NcMotion::None:
            break;
    }
    if (b.X_mm) append_nc_number(out, 'X', *b.X_mm);
    if (b.Y_mm) append_nc_number(out, 'Y', *b.Y_mm);
    if (b.Z_mm) append_nc_number(out, 'Z', *b.Z_mm);
    if (b.A_rad) append_nc_number(out, 'A', rad_to_deg(*b.A_rad));
    if (b.B_rad) append_nc_number(out, 'B', rad_to_deg(*b.B_rad));
    if (b.C_rad) append_nc_number(out, 'C', rad_to_deg(*b.C_rad));
    if (!b.extra_words.empty()) out.append(" ").append(b.extra_words);
    if (b.feed_mm_min && b.motion == NcMotion::Feed) append_nc_number(out, 'F', *b.feed_mm_min, 1);
    if (!b.comment.empty()) {
        if (out.size() > start) out += ' ';
        // Inside ( ) a comment cannot hold parentheses (a ';' comment of LinuxCNC can) nor control
        // characters: brackets and blanks instead, so that the line reads back.
        out += '(';
        for (const char c : b.comment) {
            out += c == '(' ? '[' : c == ')' ? ']' : (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? ' ' : c;
        }
        out += ')';
    }
    if (out.size() > start) out += '\n';
}

void write_nc_footer(std::string& out, NcDialect dialect) {
    out += dialect == NcDialect::Fanuc ? "M30\n%\n" : "M2\n";
}

std::string write_nc_program(const NcProgram& program, std::string_view title) {
    std::string out;
    out.reserve(64 * program.blocks.size() + 64);
    write_nc_header(out, program.dialect, title);
    for (const auto& b : program.blocks) write_nc_block(out, b, program.dialect);
    write_nc_footer(out, program.dialect);
    return out;
}

Pose pose_after(const NcBlock& b, const Pose& before) {
    Pose p = before;
    if (b.X_mm) p.X_mm = *b.X_mm;
    if (b.Y_mm) p.Y_mm = *b.Y_mm;
    if (b.Z_mm) p.Z_mm = *b.Z_mm;
    if (b.A_rad) p.A_rad = *b.A_rad;
    if (b.B_rad) p.B_rad = *b.B_rad;
    if (b.C_rad) p.C_rad = *b.C_rad;
    return p;
}

std::vector<Pose> resolve_poses(const NcProgram& program, const Pose& start) {
    std::vector<Pose> poses;
    poses.reserve(program.blocks.size());
    Pose p = start;
    for (const auto& b : program.blocks) {
        p = pose_after(b, p);
        poses.push_back(p);
    }
    return poses;
}

}  // namespace ballbar::analysis
