// SPDX-License-Identifier: MIT
#include "ballbar/analysis/nc_interpreter.hpp"

#include <cctype>
#include <charconv>
#include <cmath>

#include "ballbar/analysis/decimal_text.hpp"
#include "ballbar/analysis/nc_lexer.hpp"

namespace ballbar::analysis {
namespace {

constexpr char upper(char c) {
    return c >= 'a' && c <= 'z' ? static_cast<char>(c - 'a' + 'A') : c;
}
constexpr bool is_letter(char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}
constexpr double kInch = 25.4;

bool iequal(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (upper(a[i]) != upper(b[i])) return false;
    return true;
}

/// A character that starts no word: parameters and expressions get what to do about them.
[[noreturn]] void unexpected(char c, int line) {
    if (c == '#')
        throw NcError(line,
                      "parameters (#) are not supported: expand the program with the controller's interpreter "
                      "(or the CAM post-processor) first");
    if (c == '[')
        throw NcError(line,
                      "expressions ([ ]) are not supported: expand the program with the controller's "
                      "interpreter (or the CAM post-processor) first");
    throw NcError(line, std::string("unexpected character '") + c + "'");
}

/// A word's number (nc_lexer.hpp); a character no number starts with gets what to do about it.
double number(std::string_view s, std::size_t& i, int line, char letter) {
    std::size_t k = i;
    if (k < s.size() && (s[k] == '+' || s[k] == '-')) ++k;
    if (k < s.size() && !((s[k] >= '0' && s[k] <= '9') || s[k] == '.')) unexpected(s[k], line);
    return read_nc_number(s, i, line, letter);
}

int axis_index(char c) {
    switch (c) {
        case 'X':
            return 0;
        case 'Y':
            return 1;
        case 'Z':
            return 2;
        case 'A':
            return 3;
        case 'B':
            return 4;
        case 'C':
            return 5;
        default:
            return -1;
    }
}
double& axis_ref(Pose& p, int k) {
    switch (k) {
        case 0:
            return p.X_mm;
        case 1:
            return p.Y_mm;
        case 2:
            return p.Z_mm;
        case 3:
            return p.A_rad;
        case 4:
            return p.B_rad;
        default:
            return p.C_rad;
    }
}

std::string code_name(char letter, double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(1, letter) + std::string(buf, r.ptr);
}

}  // namespace

std::optional<TcpCodes> tcp_codes_for(std::string_view controller) {
    if (controller == "linuxcnc") return TcpCodes{{"M428"}, {"M429"}};
    if (controller == "fanuc") return TcpCodes{{"G43.4"}, {"G49"}};
    if (controller == "siemens") return TcpCodes{{"TRAORI"}, {"TRAFOOF"}};
    if (controller == "heidenhain") return TcpCodes{{"M128"}, {"M129"}};
    if (controller == "none") return TcpCodes{};
    return std::nullopt;
}

NcInterpreter::NcInterpreter(std::string_view text, NcInterpreterOptions options)
    : text_(text), opt_(std::move(options)), tcp_(opt_.tcp_at_start) {
    // The G and M words among the switch codes, as numbers: a block's G1 is compared, not formatted.
    for (const auto* list : {&opt_.tcp.on, &opt_.tcp.off})
        for (const std::string& w : *list) {
            if (w.size() < 2 || (upper(w[0]) != 'G' && upper(w[0]) != 'M')) continue;
            double v = 0;
            const auto r = std::from_chars(w.data() + 1, w.data() + w.size(), v);
            if (r.ec == std::errc() && r.ptr == w.data() + w.size()) tcp_numeric_.emplace_back(upper(w[0]), v);
        }
    if (opt_.start) {  // every axis known from the start
        pos_now_ = *opt_.start;
        known_ = 0b111111;
    }
    if (opt_.iso_directions)  // the table is in the controller's directions; inside, ballbar's
        for (auto& [name, p] : opt_.offsets.work) {
            p.A_rad = -p.A_rad;
            p.B_rad = -p.B_rad;
            p.C_rad = -p.C_rad;
        }
}

bool NcInterpreter::next(NcStep& step) {
    while (!ended_ && pos_ < text_.size()) {
        std::size_t end = text_.find('\n', pos_);
        if (end == std::string_view::npos) end = text_.size();
        std::string_view raw = text_.substr(pos_, end - pos_);
        pos_ = end + 1;
        ++line_;
        step.line = line_;
        step.motion = NcMotion::None;
        step.arc = false;
        step.machine_coordinates = false;
        step.feed.reset();
        step.points.clear();
        step.sequence.clear();
        step.words.clear();
        step.comment.clear();
        step.verbatim.clear();
        step.program_end = false;
        parse_line(raw, step);
        if (step.motion != NcMotion::None || !step.words.empty() || !step.comment.empty() || !step.verbatim.empty() ||
            step.program_end)
            return true;
    }
    return false;
}

void NcInterpreter::parse_line(std::string_view raw, NcStep& step) {
    const int line = line_;
    // Comments: ( … ) anywhere, ; to the end of the line (nc_lexer.hpp).
    std::string code_buf;
    std::string_view code = split_nc_comments(raw, line, /*semicolon_comments=*/true, code_buf, step.comment);
    code = trim_nc_blanks(code);
    if (code.empty()) return;
    if (code == "%") {
        if (started_) {
            ended_ = true;
            step.program_end = true;
        }
        started_ = true;
        return;
    }
    if (code.front() == '/') throw NcError(line, "block delete '/' is not supported: remove the '/' blocks or the '/'");
    if (upper(code.front()) == 'O') {
        std::size_t i = 1;
        while (i < code.size() && code[i] >= '0' && code[i] <= '9') ++i;
        if (opt_.dialect == NcDialect::Fanuc && i > 1 && trim_nc_blanks(code.substr(i)).empty()) {
            started_ = true;  // Fanuc program number
            return;
        }
        throw NcError(line,
                      "O-word subroutines and control flow are not supported: expand them with the "
                      "controller's interpreter first");
    }
    started_ = true;
    ++blocks_;

    // Words.
    // The words' values by letter: `seen` has bit (letter − 'A') set for those present (a 26-optional
    // array would be zeroed per block: 10 % of a million-block run).
    double value[26];
    unsigned seen = 0;
    auto has = [&](char c) { return (seen >> (c - 'A')) & 1u; };
    int motion_code = -1;  // 0..3 when the block names one
    bool dwell = false, g53 = false, g28 = false, tcp_switch = false;
    bool tool_change = false;
    std::optional<int> g43;  // 430 or 434
    bool g49 = false;
    bool g91_in_block = false;
    std::string_view f_text;  // the F word as written
    std::size_t i = 0;
    auto add_word = [&](std::string_view w) {
        if (!step.words.empty()) step.words += ' ';
        step.words += w;
    };
    auto is_code = [&](const std::vector<std::string>& list, std::string_view w) {
        for (const auto& c : list)
            if (iequal(c, w)) return true;
        return false;
    };
    while (i < code.size()) {
        if (is_nc_blank(code[i])) {
            ++i;
            continue;
        }
        const std::size_t word_start = i;
        if (!is_letter(code[i])) unexpected(code[i], line);
        // A keyword (Siemens TRAORI): letters followed by a non-digit.
        if (i + 1 < code.size() && is_letter(code[i + 1])) {
            std::size_t k = i;
            while (k < code.size() && is_letter(code[k])) ++k;
            const std::string_view kw = code.substr(i, k - i);
            if (is_code(opt_.tcp.on, kw) || is_code(opt_.tcp.off, kw)) {
                tcp_ = is_code(opt_.tcp.on, kw);
                tcp_switch = true;
                add_word(kw);
                i = k;
                continue;
            }
            throw NcError(line, "unknown word '" + std::string(kw) + "'");
        }
        const char c = upper(code[i]);
        ++i;
        while (i < code.size() && is_nc_blank(code[i])) ++i;
        const double v = number(code, i, line, c);
        const std::string_view text = code.substr(word_start, i - word_start);
        if ((c == 'G' || c == 'M') && is_tcp_code(c, v)) {
            char nb[40];
            nb[0] = c;
            const auto nr = std::to_chars(nb + 1, nb + sizeof nb, v);
            const std::string_view name(nb, static_cast<std::size_t>(nr.ptr - nb));
            {
                if (name == "G43.4" || (c == 'G' && v == 49)) {
                    // Fanuc: tool-centre point with tool length (H), G49 cancels both.
                } else {
                    tcp_ = is_code(opt_.tcp.on, name);
                    tcp_switch = true;
                    add_word(text);
                    continue;
                }
            }
        }
        if (c == 'G') {
            const int g10 = static_cast<int>(std::lround(v * 10));
            if (std::abs(v * 10 - g10) > 1e-9) throw NcError(line, "unsupported G code " + code_name('G', v));
            switch (g10) {
                case 0:
                case 10:
                case 20:
                case 30:
                    if (motion_code >= 0) throw NcError(line, "two motion codes (G0/G1/G2/G3) in one block");
                    motion_code = g10 / 10;
                    break;
                case 40:
                    if (dwell) throw NcError(line, "G4 twice in one block");
                    dwell = true;
                    add_word(text);
                    break;
                case 170:
                case 180:
                case 190:
                    plane_ = g10 / 10;
                    add_word(text);
                    break;
                case 200:
                    inch_ = true;
                    break;
                case 210:
                    inch_ = false;
                    break;
                case 900:
                    absolute_ = true;
                    break;
                case 910:
                    absolute_ = false;
                    g91_in_block = true;
                    break;
                case 901:
                    arc_absolute_ = true;
                    break;
                case 911:
                    arc_absolute_ = false;
                    break;
                case 930:
                    inverse_time_ = true;
                    add_word(text);
                    break;
                case 940:
                    inverse_time_ = false;
                    add_word(text);
                    break;
                case 400:
                case 800:
                case 610:
                case 611:
                case 640:
                    add_word(text);
                    break;
                case 410:
                case 420:
                    throw NcError(line,
                                  "cutter radius compensation (G41/G42) is not supported: post the tool-centre "
                                  "path (G40) from the CAM system");
                case 430:
                case 434:
                    g43 = g10;
                    add_word(text);
                    break;
                case 490:
                    g49 = true;
                    add_word(text);
                    break;
                case 530:
                    g53 = true;
                    add_word(text);
                    break;
                case 540:
                case 550:
                case 560:
                case 570:
                case 580:
                case 590:
                case 591:
                case 592:
                case 593: {
                    const std::string name = code_name('G', v);
                    const auto it = opt_.offsets.work.find(name);
                    if (it == opt_.offsets.work.end())
                        throw NcError(line, name + " needs its work offset: give it in the --offsets table (" +
                                                (opt_.have_offsets ? "it has no \"" + name + "\"" : "none given") +
                                                ")");
                    // The machine stays where it is: the program position of the unnamed axes moves.
                    const Pose& next = it->second;
                    pos_now_.X_mm += work_offset_.X_mm - next.X_mm;
                    pos_now_.Y_mm += work_offset_.Y_mm - next.Y_mm;
                    pos_now_.Z_mm += work_offset_.Z_mm - next.Z_mm;
                    pos_now_.A_rad += work_offset_.A_rad - next.A_rad;
                    pos_now_.B_rad += work_offset_.B_rad - next.B_rad;
                    pos_now_.C_rad += work_offset_.C_rad - next.C_rad;
                    work_offset_ = next;
                    add_word(text);
                    break;
                }
                case 280:
                case 300:
                    g28 = true;
                    break;
                default:
                    if (g10 >= 810 && g10 <= 890)
                        throw NcError(line, "canned cycles (G81–G89) are not supported: post them as G0/G1 moves");
                    throw NcError(line, "unsupported G code " + code_name('G', v) +
                                            " (it may change the geometry: post the program without it)");
            }
            continue;
        }
        if (c == 'M') {
            if (std::floor(v) != v) throw NcError(line, "M word must be an integer");
            const int m = static_cast<int>(v);
            if (m == 98 || m == 99)
                throw NcError(line,
                              "subprogram calls (M98/M99) are not supported: expand them with the controller's "
                              "interpreter first");
            if (m == 2 || m == 30) {
                ended_ = true;
                step.program_end = true;
            }
            if (m == 6) tool_change = true;
            add_word(text);
            continue;
        }
        if (c == 'N') {
            step.sequence.assign(text);
            continue;
        }
        if (c == 'S' || c == 'D') {
            add_word(text);
            continue;
        }
        if (c == 'E' || c == 'L' || c == 'U' || c == 'V' || c == 'W' || c == 'O')
            throw NcError(line, std::string("unsupported word ") + c);
        if (c == 'B' && opt_.second_rotary != 'B')
            throw NcError(line,
                          "B word: the model's machine has rotary axes A and C (a model of another machine type?)");
        if (c == 'C' && opt_.second_rotary != 'C')
            throw NcError(line,
                          "C word: the model's machine has rotary axes A and B (a model of another machine type?)");
        if (has(c)) throw NcError(line, std::string("word ") + c + " twice in one block");
        seen |= 1u << (c - 'A');
        value[c - 'A'] = v;
        if (c == 'F') f_text = text;
        if (c == 'T') {
            if (std::floor(v) != v || v < 0) throw NcError(line, "T word must be a tool number");
            next_tool_ = static_cast<int>(v);
            add_word(text);
        } else if (c == 'H') {
            if (std::floor(v) != v || v < 0) throw NcError(line, "H word must be a tool-length register");
            add_word(text);
        } else if (c == 'P' || c == 'Q') {
            add_word(text);  // G4 P, G64 P Q: kept as written
        }
    }
    if (tool_change) tool_ = next_tool_;
    if (has('P') && motion_code >= 2) throw NcError(line, "P on an arc (turns) is not supported");

    // Tool length. G43/G49 do not move the machine: the program Z of the current point changes.
    const double lm = opt_.offsets.measured_tool_length_mm;
    const double dl_before = tool_length_active_ ? tool_length_mm_ - lm : 0.0;
    if (g49) {
        tool_length_active_ = false;
        tool_length_mm_ = 0;
        if (is_code(opt_.tcp.off, "G49")) {
            tcp_ = false;
            tcp_switch = true;
        }
    }
    if (g43) {
        const int reg = has('H') ? static_cast<int>(value['H' - 'A']) : tool_;
        const auto it = opt_.offsets.tool_length_mm.find(reg);
        if (it == opt_.offsets.tool_length_mm.end())
            throw NcError(line, "G43 needs the length of tool " + std::to_string(reg) +
                                    ": give it in the --offsets table (\"tools\")");
        tool_length_active_ = true;
        tool_length_mm_ = it->second;
        if (*g43 == 434) {
            if (!is_code(opt_.tcp.on, "G43.4"))
                throw NcError(line, "G43.4 (tool-centre point) without --controller fanuc or --tcp-on G43.4");
            tcp_ = true;
            tcp_switch = true;
        }
    }
    const double dl_after = tool_length_active_ ? tool_length_mm_ - lm : 0.0;
    if (dl_after != dl_before) {
        pos_now_.Z_mm += dl_before - dl_after;
        if (tcp_) known_ = 0;  // in TCP mode the length enters the kinematics: name every axis
    }
    if (tcp_switch) {
        frame_line_ = line;
        if (moved_ || !opt_.start) known_ = 0;  // a given start holds in the frame of the first move
    }

    // Axis words to absolute positions (mm, rad, ballbar directions). G53: machine coordinates, the
    // unnamed axes where the machine is.
    if (g53 && (!absolute_ || tcp_ || tool_length_active_))
        throw NcError(line, "G53 is supported in G90, out of tool-centre-point mode and without G43 in force");
    bool has_axis = false;
    Pose target = pos_now_;
    if (g53) {
        target.X_mm += work_offset_.X_mm;
        target.Y_mm += work_offset_.Y_mm;
        target.Z_mm += work_offset_.Z_mm;
        target.A_rad += work_offset_.A_rad;
        target.B_rad += work_offset_.B_rad;
        target.C_rad += work_offset_.C_rad;
    }
    int named = 0;
    for (char c : {'X', 'Y', 'Z', 'A', 'B', 'C'}) {
        if (!has(c)) continue;
        has_axis = true;
        const int k = axis_index(c);
        named |= 1 << k;
        double v = value[c - 'A'];
        if (k < 3) {
            if (inch_) v *= kInch;
        } else {
            v = deg_to_rad(v);
            if (opt_.iso_directions) v = -v;
        }
        double& dst = axis_ref(target, k);
        dst = absolute_ ? v : dst + v;
    }
    // A motion code alone only sets the modal motion ("G00 G17 G40 G90 G94"); an arc with a centre or a
    // radius and no axis word is a full circle.
    const bool moves =
        (has_axis && !dwell && !g28) || (motion_code >= 2 && (has('I') || has('J') || has('K') || has('R')));
    if (dwell && has_axis) throw NcError(line, "G4 with axis words: dwell and motion must be separate blocks");
    if (motion_code >= 0) motion_ = motion_code;
    if (g28) {
        // Only the retract idiom "G91 G28 Z0" (an incremental zero move to the intermediate point, then the
        // reference point): copied as written and not compensated.
        bool zero = true;
        for (char c : {'X', 'Y', 'Z', 'A', 'B', 'C'})
            if (has(c) && value[c - 'A'] != 0) zero = false;
        if (!g91_in_block || !zero || motion_code >= 0)
            throw NcError(line, "G28/G30 is supported only as the retract \"G91 G28 Z0\" (incremental, zero words)");
        step.verbatim.assign(code);
        known_ = 0;
        absolute_ = true;  // the output is absolute: the copied G91 is cancelled after the line
        return;
    }
    if (!moves) {
        if (has_axis) throw NcError(line, "axis words without motion");
        if (has('F')) add_word(f_text);  // the modal feed, for the moves that follow
        return;
    }
    moved_ = true;
    if (motion_ < 0) throw NcError(line, "axis words before any G0/G1/G2/G3");

    // Every axis of the model must have a known position for an absolute move.
    const int model_axes = 0b000111 | (1 << 3) | (1 << (opt_.second_rotary == 'B' ? 4 : 5));
    const int missing = model_axes & ~(known_ | named);
    if (missing)
        for (int k = 0; k < 6; ++k)
            if (missing & (1 << k)) {
                if (!absolute_ || (known_ & (1 << k)) == 0)
                    throw NcError(line, std::string("the position of ") + "XYZABC"[k] +
                                            " is not known here (at the start, after a tool-centre-point switch or "
                                            "a retract): name every axis of the machine in this move");
            }
    if (!absolute_) {
        for (int k = 0; k < 6; ++k)
            if ((named & (1 << k)) && !(known_ & (1 << k)))
                throw NcError(line, std::string("incremental move of ") + "XYZABC"[k] + " from an unknown position");
    }
    known_ |= named;

    step.motion = motion_ == 0 ? NcMotion::Rapid : NcMotion::Feed;
    step.machine_coordinates = g53;
    step.frame = tcp_ ? NcFrame::Tcp : NcFrame::Joint;
    step.frame_line = frame_line_;
    step.inverse_time = inverse_time_ && motion_ != 0;
    step.start = pos_now_;
    step.work_offset = g53 ? Pose{} : work_offset_;
    step.tool_length_active = tool_length_active_;
    step.tool_length_mm = tool_length_mm_;
    if (has('F')) {
        const double f = value['F' - 'A'];
        if (f <= 0) throw NcError(line, "feed F must be positive");
        step.feed = (inch_ && !inverse_time_) ? f * kInch : f;
    } else if (step.inverse_time) {
        throw NcError(line, "G93 (inverse time) needs an F word in every feed block");
    }
    if (g53 && tcp_) throw NcError(line, "G53 in tool-centre-point mode is not supported");
    if (motion_ >= 2) {
        if (g53) throw NcError(line, "G53 with an arc");
        const double scale = inch_ ? kInch : 1.0;
        auto w = [&](char c) { return has(c) ? value[c - 'A'] * scale : 0.0; };
        const bool have_ijk = has('I') || has('J') || has('K');
        std::optional<double> r;
        if (has('R')) r = value['R' - 'A'] * scale;
        if (have_ijk && r) throw NcError(line, "arc with both I/J/K and R");
        if (!have_ijk && !r) throw NcError(line, "arc without a centre (I/J/K) or a radius (R)");
        arc_points(step, target, w('I'), w('J'), w('K'), r, motion_ == 2, have_ijk);
    } else {
        for (char c : {'I', 'J', 'K', 'R'})
            if (has(c)) throw NcError(line, std::string("word ") + c + " outside an arc");
        step.points.push_back(target);
    }
    pos_now_ = target;
    if (g53) {  // back to the program frame
        pos_now_.X_mm -= work_offset_.X_mm;
        pos_now_.Y_mm -= work_offset_.Y_mm;
        pos_now_.Z_mm -= work_offset_.Z_mm;
        pos_now_.A_rad -= work_offset_.A_rad;
        pos_now_.B_rad -= work_offset_.B_rad;
        pos_now_.C_rad -= work_offset_.C_rad;
    }
}

bool NcInterpreter::is_tcp_code(char letter, double v) const {
    for (const auto& [l, n] : tcp_numeric_)
        if (l == letter && n == v) return true;
    return false;
}

void NcInterpreter::arc_points(NcStep& step, const Pose& end, double i, double j, double k, std::optional<double> r,
                               bool cw, bool have_ijk) {
    const int line = line_;
    const Pose& s = pos_now_;
    // Plane coordinates (u, v) and the normal w: G17 (X, Y; Z), G18 (Z, X; Y), G19 (Y, Z; X).
    int iu = 0, iv = 1, iw = 2;
    double cu = i, cv = j;
    if (plane_ == 18) {
        iu = 2, iv = 0, iw = 1;
        cu = k, cv = i;
    } else if (plane_ == 19) {
        iu = 1, iv = 2, iw = 0;
        cu = j, cv = k;
    }
    auto get = [](const Pose& p, int a) { return a == 0 ? p.X_mm : a == 1 ? p.Y_mm : p.Z_mm; };
    const double su = get(s, iu), sv = get(s, iv), eu = get(end, iu), ev = get(end, iv);
    double ou, ov;  // centre
    if (have_ijk) {
        ou = arc_absolute_ ? cu : su + cu;
        ov = arc_absolute_ ? cv : sv + cv;
    } else {
        const double dx = eu - su, dy = ev - sv, d = std::hypot(dx, dy);
        const double rr = std::abs(*r);
        if (d == 0) throw NcError(line, "R-form arc with its end at its start");
        if (d > 2 * rr * (1 + 1e-9)) throw NcError(line, "R-form arc: the end is farther than the diameter");
        const double h = std::sqrt(std::max(0.0, rr * rr - d * d / 4));
        // The centre left of the chord for CCW short arcs; R < 0 asks for the long way round.
        const double side = ((cw ? -1.0 : 1.0) * (*r < 0 ? -1.0 : 1.0));
        ou = su + dx / 2 - side * h * dy / d;
        ov = sv + dy / 2 + side * h * dx / d;
    }
    const double r0 = std::hypot(su - ou, sv - ov), r1 = std::hypot(eu - ou, ev - ov);
    if (r0 == 0) throw NcError(line, "arc of radius 0");
    if (std::abs(r0 - r1) > 0.002 + 1e-4 * r0)
        throw NcError(line, "arc end is not on the arc: radius " + std::to_string(r0) + " at the start, " +
                                std::to_string(r1) + " at the end");
    const double a0 = std::atan2(sv - ov, su - ou), a1 = std::atan2(ev - ov, eu - ou);
    double sweep = a1 - a0;
    if (cw) {
        while (sweep >= 0) sweep -= 2 * kPi;
        if (sweep < -2 * kPi) sweep += 2 * kPi;
    } else {
        while (sweep <= 0) sweep += 2 * kPi;
        if (sweep > 2 * kPi) sweep -= 2 * kPi;
    }
    // A start and end that coincide is a full circle (sweep ±2π from the loops above).
    const double rmax = std::max(r0, r1);
    const double tol = opt_.chord_tolerance_mm;
    const double half = tol >= rmax ? kPi / 2 : std::acos(1 - tol / rmax);  // chord half-angle within tol
    const int n = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / (2 * half) - 1e-12)));
    if (n > 1000000) throw NcError(line, "arc needs more than a million chords at this --chord-tolerance");
    step.arc = true;
    for (int m = 1; m <= n; ++m) {
        const double t = static_cast<double>(m) / n;
        if (m == n) {
            step.points.push_back(end);
            break;
        }
        Pose p;
        const double a = a0 + sweep * t, rad = r0 + (r1 - r0) * t;
        double uvw[3];
        uvw[iu] = ou + rad * std::cos(a);
        uvw[iv] = ov + rad * std::sin(a);
        uvw[iw] = get(s, iw) + (get(end, iw) - get(s, iw)) * t;
        p.X_mm = uvw[0];
        p.Y_mm = uvw[1];
        p.Z_mm = uvw[2];
        p.A_rad = s.A_rad + (end.A_rad - s.A_rad) * t;
        p.B_rad = s.B_rad + (end.B_rad - s.B_rad) * t;
        p.C_rad = s.C_rad + (end.C_rad - s.C_rad) * t;
        step.points.push_back(p);
    }
}

}  // namespace ballbar::analysis
