// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/nc_writer.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::acquisition {

using namespace ballbar::analysis;

namespace {

NcBlock pose_block(const MachineGeometry& geom, NcMotion motion, const Pose& p) {
    NcBlock b;
    b.motion = motion;
    b.X_mm = p.X_mm;
    b.Y_mm = p.Y_mm;
    b.Z_mm = p.Z_mm;
    b.A_rad = p.A_rad;
    if (rotary_axes(geom.type).second == 'B')
        b.B_rad = p.B_rad;
    else
        b.C_rad = p.C_rad;
    return b;
}

NcBlock comment_block(std::string text) {
    // Fanuc comments are parenthesised and do not nest.
    for (char& c : text) {
        if (c == '(') c = '[';
        if (c == ')') c = ']';
    }
    NcBlock b;
    b.comment = std::move(text);
    return b;
}

std::string socket_text(const Vec3& s) {
    std::ostringstream os;
    os << "[" << s.x() << ", " << s.y() << ", " << s.z() << "] mm";
    return os.str();
}

/// Spherical interpolation of unit vectors.
Vec3 slerp(const Vec3& a, const Vec3& b, double t) {
    const double angle = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
    if (angle < 1e-9) return a;
    return (std::sin((1 - t) * angle) * a + std::sin(t * angle) * b) / std::sin(angle);
}

double linear_mm(const Pose& a, const Pose& b) {
    return (b.linear_mm() - a.linear_mm()).norm();
}

double rotary_deg(const Pose& a, const Pose& b) {
    const double da = b.A_rad - a.A_rad, db = b.B_rad - a.B_rad, dc = b.C_rad - a.C_rad;
    return rad_to_deg(std::sqrt(da * da + db * db + dc * dc));
}

class Builder {
  public:
    Builder(const Plan& plan, const NcOptions& opt) : plan_(plan), opt_(opt), geom_(plan.machine.geometry) {
        prog_.nc.dialect = plan.machine.dialect;
        digits_ = code_data_digits(plan.points.size());
    }

    void comment(std::string text) { prog_.nc.blocks.push_back(comment_block(std::move(text))); }

    void stop(std::string what, std::optional<Vec3> socket = std::nullopt) {
        comment("PROGRAM STOP: " + what);
        NcBlock b;
        b.raw = "M0";
        prog_.nc.blocks.push_back(std::move(b));
        pending_.stops_before.push_back({std::move(what), socket});
    }

    void rapid(const Pose& p) {
        pending_.rapid_mm += linear_mm(here_, p);
        prog_.nc.blocks.push_back(pose_block(geom_, NcMotion::Rapid, p));
        here_ = p;
    }

    void feed(const Pose& p, bool first_of_move) {
        const double minutes = std::max(linear_mm(here_, p), rotary_deg(here_, p)) / plan_.machine.feed_mm_min;
        pending_.feed_s += 60.0 * minutes;
        NcBlock b = pose_block(geom_, NcMotion::Feed, p);
        if (first_of_move || !feed_set_) b.feed_mm_min = plan_.machine.feed_mm_min;
        feed_set_ = true;
        prog_.nc.blocks.push_back(std::move(b));
        here_ = p;
    }

    void dwell(double s, std::string text) {
        NcBlock d;
        d.motion = NcMotion::Dwell;
        d.dwell_s = s;
        d.comment = std::move(text);
        pending_.dwell_s += s;
        prog_.nc.blocks.push_back(std::move(d));
    }

    void start_at(const PlannedPoint& first) {
        here_ = first.pose;  // unknown before the program: the rapid's length is not counted
        prog_.nc.blocks.push_back(pose_block(geom_, NcMotion::Rapid, first.pose));
        stop("mount the bar: socket at " + socket_text(first.socket_mm) +
             " in the table frame, tool ball in the spindle; then cycle start");
    }

    /// G1 segments from `from` to `to` with the tool ball on the bar's sphere around the moving datum.
    void transfer(const PlannedPoint& from, const PlannedPoint& to) {
        const double L = plan_.spec.bar_length_mm;
        const Vec3 u0 = (from.tool_ball_mm - from.datum_mm).normalized();
        const Vec3 u1 = (to.tool_ball_mm - to.datum_mm).normalized();
        const double arc = std::acos(std::clamp(u0.dot(u1), -1.0, 1.0));
        const double rot =
            std::max({std::abs(to.pose.A_rad - from.pose.A_rad), std::abs(to.pose.B_rad - from.pose.B_rad),
                      std::abs(to.pose.C_rad - from.pose.C_rad)});
        const int n = std::max({1, static_cast<int>(std::ceil(arc / opt_.max_arc_step_rad)),
                                static_cast<int>(std::ceil(rot / opt_.max_rotary_step_rad))});
        for (int k = 1; k <= n; ++k) {
            const double t = static_cast<double>(k) / n;
            Pose r;
            r.A_rad = from.pose.A_rad + t * (to.pose.A_rad - from.pose.A_rad);
            r.B_rad = from.pose.B_rad + t * (to.pose.B_rad - from.pose.B_rad);
            r.C_rad = from.pose.C_rad + t * (to.pose.C_rad - from.pose.C_rad);
            const Pose p = k == n ? to.pose
                                  : command_for_tool_ball(
                                        geom_, r, nominal_table_ball(geom_, r, to.socket_mm) + L * slerp(u0, u1, t));
            check(p, to);
            feed(p, k == 1);
        }
    }

    /// The point's code: tag lengths along the bar's axis, then back to the point.
    void code(std::size_t index, const PlannedPoint& p) {
        const Vec3 u = (p.tool_ball_mm - p.datum_mm).normalized();
        const std::vector<int> digits = encode_point(index, digits_);
        std::string text;
        for (int d : digits) text += std::to_string(d);
        comment("code of " + point_label(p) + ": " + text);
        for (std::size_t k = 0; k < digits.size(); ++k) {
            const double off = tag_offset_mm(opt_.code, static_cast<int>(k), digits[k]);
            const Pose q = command_for_tool_ball(geom_, p.pose, p.tool_ball_mm + off * u);
            check(q, p);
            feed(q, k == 0);
            dwell(opt_.code.tag_dwell_s, {});
        }
        feed(p.pose, false);
    }

    void measure(std::size_t index) {
        const PlannedPoint& p = plan_.points[index];
        code(index, p);
        dwell(plan_.spec.dwell_s, point_label(p));
        pending_.point = index;
        prog_.entries.push_back(std::move(pending_));
        pending_ = {};
    }

    void check(const Pose& p, const PlannedPoint& to) const {
        if (const std::string why = check_travel(plan_.machine, p); !why.empty())
            throw PlanError("NC program: the move to test " + std::to_string(to.test + 1) + ", step " +
                            std::to_string(to.step) + ", point " + std::to_string(to.point + 1) + " passes " + why);
    }

    MeasuringProgram take() { return std::move(prog_); }

  private:
    const Plan& plan_;
    const NcOptions& opt_;
    const MachineGeometry& geom_;
    MeasuringProgram prog_;
    ProgramEntry pending_;
    Pose here_;
    bool feed_set_ = false;
    int digits_ = 2;
};

}  // namespace

MeasuringProgram make_measuring_program(const Plan& plan, std::span<const std::size_t> points,
                                        const NcOptions& options) {
    if (points.empty()) throw PlanError("NC program: nothing left to measure");
    for (std::size_t i : points)
        if (i >= plan.points.size()) throw PlanError("NC program: the plan has no point " + std::to_string(i));
    const MachineGeometry& geom = plan.machine.geometry;
    Builder b(plan, options);
    const PlannedPoint& first = plan.points[points.front()];
    b.comment("ballbar two-step SSM, " + std::string(to_string(geom.type)) + ", " + std::to_string(points.size()) +
              " of " + std::to_string(plan.points.size()) + " points");
    b.start_at(first);
    b.measure(points.front());
    for (std::size_t k = 1; k < points.size(); ++k) {
        const PlannedPoint& prev = plan.points[points[k - 1]];
        const PlannedPoint& cur = plan.points[points[k]];
        if (cur.test != prev.test || cur.step != prev.step) {
            std::string what = cur.step == 1 ? "step 1: rotary axes at their start" : "step 2: rotate";
            if (cur.step == 2 && plan.spec.tests[static_cast<std::size_t>(cur.test)].kind == TestKind::TableAlpha)
                what += ", socket on the turning table";
            b.comment("test " + std::to_string(cur.test + 1) + " " + what);
        }
        if ((cur.socket_mm - prev.socket_mm).norm() > 1e-9) {
            // A new socket position: the bar comes off, the machine moves, the operator remounts.
            b.stop("remove the bar from the socket at " + socket_text(prev.socket_mm) + "; move the socket to " +
                       socket_text(cur.socket_mm) + " in the table frame; then cycle start",
                   cur.socket_mm);
            b.rapid(cur.pose);
            b.stop("mount the bar: socket at " + socket_text(cur.socket_mm) + "; then cycle start");
        } else {
            b.transfer(prev, cur);
        }
        b.measure(points[k]);
    }
    return b.take();
}

std::vector<std::size_t> points_from(const Plan& plan, std::size_t from_point) {
    std::vector<std::size_t> out;
    for (std::size_t i = from_point; i < plan.points.size(); ++i) out.push_back(i);
    return out;
}

NcProgram make_nc_program(const Plan& plan, std::size_t from_point, const NcOptions& options) {
    const auto pts = points_from(plan, from_point);
    return make_measuring_program(plan, pts, options).nc;
}

namespace {

/// The program's text; a number outside the controller's word format (a position beyond five
/// integer digits, say) is the plan's fault: PlanError.
std::string program_text(const NcProgram& program) {
    try {
        return write_nc_program(program, "ballbar SSM");
    } catch (const AnalysisError& e) {
        throw PlanError(std::string("NC program: ") + e.what());
    }
}

}  // namespace

std::string write_plan_program(const Plan& plan, std::size_t from_point) {
    return program_text(make_nc_program(plan, from_point));
}

std::string write_program(const Plan& plan, std::span<const std::size_t> points) {
    return program_text(make_measuring_program(plan, points).nc);
}

bool is_program_stop(const NcBlock& block) {
    if (block.motion != NcMotion::None) return false;
    std::istringstream words(block.extra_words.empty() ? block.raw : block.extra_words);
    std::string w;
    while (words >> w)
        if (w == "M0" || w == "M00" || w == "M1" || w == "M01") return true;
    return false;
}

}  // namespace ballbar::acquisition
