// SPDX-License-Identifier: MIT
#include "ballbar/analysis/nc_compensate.hpp"

#include <charconv>
#include <cmath>
#include <memory>
#include <utility>

namespace ballbar::analysis {
namespace {

std::string fmt(double v, int decimals);

/// An inverse-time feed (G93 F, 1/min) with up to 10 significant digits: in the F word's format only
/// between 0.0001 and 999999.9 (no exponent, at most 6 integer digits).
void append_general(std::string& out, char letter, double value) {
    if (!(value >= 1e-4 && value <= 999'999.9))
        throw AnalysisError(std::string("NC word ") + letter + ": inverse-time feed " + fmt(value, 6) +
                            " does not fit the controller's word format (0.0001 to 999999.9)");
    char buf[64];
    buf[0] = ' ';
    buf[1] = letter;
    const auto res = std::to_chars(buf + 2, buf + sizeof buf, value, std::chars_format::general, 10);
    if (res.ec != std::errc()) throw AnalysisError("NC program: value out of range");
    out.append(buf, static_cast<std::size_t>(res.ptr - buf));
}

inline Vec3 rx(double a, const Vec3& v) {
    const double c = std::cos(a), s = std::sin(a);
    return {v.x(), c * v.y() - s * v.z(), s * v.y() + c * v.z()};
}
inline Vec3 rz(double a, const Vec3& v) {
    const double c = std::cos(a), s = std::sin(a);
    return {c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()};
}

/// One Compensator per tool vector (the tool point seen from the model's commanded point).
class Compensators {
  public:
    Compensators(const MachineGeometry& g, const ErrorParams& e, std::vector<LearnedTerm> terms,
                 const CompensationOptions& o)
        : g_(g), e_(e), terms_(std::move(terms)), o_(o) {}
    const Compensator& get(const Vec3& tool) {
        if (current_ && tool == current_tool_) return *current_;
        for (auto& [t, c] : cache_)
            if (t == tool) {
                current_tool_ = t;
                current_ = c.get();
                return *current_;
            }
        MachineGeometry g = g_;
        g.tool_ball_mm = tool;
        cache_.emplace_back(tool, std::make_unique<Compensator>(g, e_, terms_, o_));
        current_tool_ = tool;
        current_ = cache_.back().second.get();
        return *current_;
    }

  private:
    MachineGeometry g_;
    ErrorParams e_;
    std::vector<LearnedTerm> terms_;
    CompensationOptions o_;
    std::vector<std::pair<Vec3, std::unique_ptr<Compensator>>> cache_;
    const Compensator* current_ = nullptr;
    Vec3 current_tool_ = Vec3::Zero();
};

std::string fmt(double v, int decimals) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
    return r.ec == std::errc() ? std::string(buf, r.ptr) : std::string("huge");
}

}  // namespace

Vec3 tcp_inverse(const MachineGeometry& g, const Vec3& w, double a, double c) {
    return g.a_pivot_mm + rx(a, g.c_offset_mm + rz(c, w - g.a_pivot_mm - g.c_offset_mm));
}

Vec3 tcp_forward(const MachineGeometry& g, const Vec3& m, double a, double c) {
    return g.a_pivot_mm + g.c_offset_mm + rz(-c, rx(-a, m - g.a_pivot_mm) - g.c_offset_mm);
}

NcCompensateSummary compensate_nc_program(std::string_view text, const MachineGeometry& geom, const ErrorParams& e,
                                          const NcInterpreterOptions& io, const NcCompensateOptions& o,
                                          const NcSink& sink) {
    NcCompensateSummary sum;
    const bool second_is_c = rotary_axes(geom.type).second == 'C';
    NcInterpreterOptions iopt = io;
    iopt.second_rotary = second_is_c ? 'C' : 'B';
    NcInterpreter in(text, iopt);
    CompensationOptions co = o.solver;
    co.max_rotary_step_rad = o.max_rotary_rad;
    Compensators comps(geom, e, o.empirical, co);
    const double sign = iopt.iso_directions ? -1.0 : 1.0;  // ballbar → program direction
    const double lm = iopt.offsets.measured_tool_length_mm;
    const int dec = o.decimals;

    std::string out;
    constexpr std::size_t kChunk = 1 << 20;
    out.reserve(kChunk + 4096);
    write_nc_header(out, iopt.dialect, o.title);
    NcStep st;
    NcFrame frame = iopt.tcp_at_start ? NcFrame::Tcp : NcFrame::Joint;
    bool end_by_percent = false;
    // Every number written is in the controller's word format, or the block's line is named.
    auto word = [&](char letter, double value, int decimals, bool inverse_time = false) {
        try {
            if (inverse_time)
                append_general(out, letter, value);
            else
                append_nc_number(out, letter, value, decimals);
        } catch (const NcError&) {
            throw;
        } catch (const AnalysisError& error) {
            throw NcError(st.line, std::string(error.what()) + " (the compensated block)");
        }
    };
    while (in.next(st)) {
        if (!st.verbatim.empty()) {
            out += st.verbatim;
            out += "\nG90\n";
            ++sum.retracts;
            continue;
        }
        if (st.motion == NcMotion::None) {
            if (st.program_end && st.words.empty() && st.comment.empty()) {
                end_by_percent = true;
                continue;
            }
            const std::size_t start = out.size();
            if (!st.sequence.empty()) out += st.sequence;
            if (!st.words.empty()) {
                if (out.size() > start) out += ' ';
                out += st.words;
            }
            if (!st.comment.empty()) {
                if (out.size() > start) out += ' ';
                out.append("(").append(st.comment).append(")");
            }
            if (out.size() > start) out += '\n';
            continue;
        }
        ++sum.moves;
        if (st.frame != frame) {
            frame = st.frame;
            if (sum.mode_switches.size() < 50)
                sum.mode_switches.emplace_back(st.frame_line > 0 ? st.frame_line : st.line, frame);
        }
        const bool tcp = st.frame == NcFrame::Tcp;
        (tcp ? sum.tcp_moves : sum.joint_moves)++;
        if (geom.type != MachineType::TTTRR && (tcp || st.tool_length_active))
            throw NcError(st.line, std::string(tcp ? "tool-centre-point mode" : "G43 tool length") +
                                       " is supported for TTTRR (table-tilting) machines only");
        if (st.tool_length_active && st.machine_coordinates)
            throw NcError(st.line, "G53 with a tool length (G43) in force is not supported");
        if (st.arc) {
            ++sum.arcs;
            sum.arc_chords += st.points.size();
        }
        // The tool point seen from the model's commanded point, and the commanded-point shift of G43.
        const double dl = st.tool_length_active ? st.tool_length_mm - lm : 0.0;
        const Vec3 tool = st.tool_length_active ? Vec3(0, 0, -dl) : (tcp ? Vec3::Zero() : geom.tool_ball_mm);
        const Compensator& comp = comps.get(tool);
        const Pose& off = st.work_offset;
        const std::size_t n = st.points.size();
        for (std::size_t k = 0; k < n; ++k) {
            const Pose& p = st.points[k];
            Pose u;
            if (tcp) {
                const Vec3 w = p.linear_mm() + off.linear_mm();
                u.A_rad = p.A_rad + off.A_rad;
                u.C_rad = p.C_rad + off.C_rad;
                const Vec3 m = tcp_inverse(geom, w, u.A_rad, u.C_rad) - tool;
                u.X_mm = m.x();
                u.Y_mm = m.y();
                u.Z_mm = m.z();
            } else {
                u.X_mm = p.X_mm + off.X_mm;
                u.Y_mm = p.Y_mm + off.Y_mm;
                u.Z_mm = p.Z_mm + off.Z_mm + dl;
                u.A_rad = p.A_rad + off.A_rad;
                u.B_rad = p.B_rad + off.B_rad;
                u.C_rad = p.C_rad + off.C_rad;
            }
            const Correction c = o.exact ? comp.exact(u) : comp.first_order(u);
            ++sum.points;
            sum.commanded.add(u, st.line);
            const double lin = std::sqrt(c.du[0] * c.du[0] + c.du[1] * c.du[1] + c.du[2] * c.du[2]);
            const double rot = std::max(std::abs(c.du[3]), std::abs(c.du[4]));
            if (!std::isfinite(lin) || !std::isfinite(rot))
                throw NcError(
                    st.line,
                    "the correction is not a finite number: the model is beyond any bound (is it for this machine?)");
            if (lin > o.max_linear_mm || rot > o.max_rotary_rad) {
                if (!o.force)
                    throw NcError(st.line, "the correction (" + fmt(lin, 4) + " mm, " + fmt(rad_to_deg(rot), 4) +
                                               " deg) exceeds the bound (" + fmt(o.max_linear_mm, 4) + " mm, " +
                                               fmt(rad_to_deg(o.max_rotary_rad), 4) +
                                               " deg): is the model for this machine? (--force writes it anyway)");
                ++sum.over_bound;
            }
            if (lin > sum.max_linear_mm) {
                sum.max_linear_mm = lin;
                sum.max_linear_line = st.line;
            }
            if (rot > sum.max_rotary_rad) {
                sum.max_rotary_rad = rot;
                sum.max_rotary_line = st.line;
            }
            if (c.singular) {
                ++sum.singular;
                if (sum.singular_lines.size() < 20 &&
                    (sum.singular_lines.empty() || sum.singular_lines.back() != st.line))
                    sum.singular_lines.push_back(st.line);
            }
            if (!c.converged) {
                ++sum.not_converged;
                if (sum.not_converged_lines.size() < 20) sum.not_converged_lines.push_back(st.line);
            }
            // Back to the program's frame.
            Pose q = p;
            if (tcp) {
                const Pose& uc = c.commanded;
                const Vec3 w = tcp_forward(geom, uc.linear_mm() + tool, uc.A_rad, uc.C_rad) - off.linear_mm();
                q.X_mm = w.x();
                q.Y_mm = w.y();
                q.Z_mm = w.z();
                q.A_rad = p.A_rad + c.du[3];
                q.C_rad = p.C_rad + c.du[4];
            } else {
                q.X_mm += c.du[0];
                q.Y_mm += c.du[1];
                q.Z_mm += c.du[2];
                q.A_rad += c.du[3];
                (second_is_c ? q.C_rad : q.B_rad) += c.du[4];
            }
            // The line: [N] G0/G1 X Y Z A C|B [words] [F] [(comment)] (words and comment on the first chord).
            if (k == 0 && !st.sequence.empty()) out.append(st.sequence).append(" ");
            out += st.motion == NcMotion::Rapid ? "G0" : "G1";
            word('X', q.X_mm, dec);
            word('Y', q.Y_mm, dec);
            word('Z', q.Z_mm, dec);
            word('A', sign * rad_to_deg(q.A_rad), dec);
            if (second_is_c)
                word('C', sign * rad_to_deg(q.C_rad), dec);
            else
                word('B', sign * rad_to_deg(q.B_rad), dec);
            if (k == 0 && !st.words.empty()) out.append(" ").append(st.words);
            if (st.motion == NcMotion::Feed && st.feed) {
                if (st.inverse_time)
                    word('F', *st.feed * static_cast<double>(n), 0, true);  // each chord takes 1/n of the time
                else if (k == 0)
                    word('F', *st.feed, 1);
            }
            if (k == 0 && !st.comment.empty()) out.append(" (").append(st.comment).append(")");
            out += '\n';
        }
        if (out.size() >= kChunk) {
            sink(out);
            out.clear();
        }
    }
    sum.blocks = in.blocks();
    if (sum.blocks == 0) throw NcError(std::max(in.line(), 1), "empty program: no blocks (nothing to compensate)");
    if (!in.ended()) {
        if (!o.allow_truncated)
            throw NcError(in.line(),
                          "the program has no end (M2, M30 or a closing %): is it truncated? "
                          "(--allow-truncated compensates it as it is, without adding an end)");
        sum.truncated = true;
        out += "(truncated: the input program has no end)\n";
    } else if (iopt.dialect == NcDialect::Fanuc) {
        out += "%\n";
    } else if (end_by_percent) {
        out += "M2\n";
    }
    sink(out);
    return sum;
}

}  // namespace ballbar::analysis
