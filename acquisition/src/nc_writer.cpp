// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/nc_writer.hpp"

#include <algorithm>
#include <cmath>
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
    NcBlock b;
    b.comment = std::move(text);
    return b;
}

/// Spherical interpolation of unit vectors.
Vec3 slerp(const Vec3& a, const Vec3& b, double t) {
    const double angle = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
    if (angle < 1e-9) return a;
    return (std::sin((1 - t) * angle) * a + std::sin(t * angle) * b) / std::sin(angle);
}

/// G1 segments from `from` to `to` with the tool ball on the bar's sphere around the moving datum.
void append_transfer(NcProgram& prog, const Plan& plan, const PlannedPoint& from, const PlannedPoint& to,
                     const NcOptions& opt) {
    const MachineGeometry& geom = plan.machine.geometry;
    const double L = plan.spec.bar_length_mm;
    const Vec3 u0 = (from.tool_ball_mm - from.datum_mm).normalized();
    const Vec3 u1 = (to.tool_ball_mm - to.datum_mm).normalized();
    const double arc = std::acos(std::clamp(u0.dot(u1), -1.0, 1.0));
    const double rot = std::max({std::abs(to.pose.A_rad - from.pose.A_rad), std::abs(to.pose.B_rad - from.pose.B_rad),
                                 std::abs(to.pose.C_rad - from.pose.C_rad)});
    const int n = std::max({1, static_cast<int>(std::ceil(arc / opt.max_arc_step_rad)),
                            static_cast<int>(std::ceil(rot / opt.max_rotary_step_rad))});
    for (int k = 1; k <= n; ++k) {
        const double t = static_cast<double>(k) / n;
        Pose r;
        r.A_rad = from.pose.A_rad + t * (to.pose.A_rad - from.pose.A_rad);
        r.B_rad = from.pose.B_rad + t * (to.pose.B_rad - from.pose.B_rad);
        r.C_rad = from.pose.C_rad + t * (to.pose.C_rad - from.pose.C_rad);
        const Pose p =
            k == n ? to.pose
                   : command_for_tool_ball(geom, r, nominal_table_ball(geom, r, to.socket_mm) + L * slerp(u0, u1, t));
        if (const std::string why = check_travel(plan.machine, p); !why.empty())
            throw PlanError("NC program: the move to test " + std::to_string(to.test + 1) + ", step " +
                            std::to_string(to.step) + ", point " + std::to_string(to.point + 1) + " passes " + why);
        NcBlock b = pose_block(geom, NcMotion::Feed, p);
        if (k == 1) b.feed_mm_min = plan.machine.feed_mm_min;
        prog.blocks.push_back(std::move(b));
    }
}

void append_dwell(NcProgram& prog, const Plan& plan, const PlannedPoint& p) {
    NcBlock d;
    d.motion = NcMotion::Dwell;
    d.dwell_s = plan.spec.dwell_s;
    d.comment = "test " + std::to_string(p.test + 1) + " step " + std::to_string(p.step) + " point " +
                std::to_string(p.point + 1);
    prog.blocks.push_back(std::move(d));
}

}  // namespace

NcProgram make_nc_program(const Plan& plan, std::size_t from_point, const NcOptions& options) {
    if (from_point >= plan.points.size()) throw PlanError("NC program: nothing left to measure");
    const MachineGeometry& geom = plan.machine.geometry;
    NcProgram prog;
    prog.dialect = plan.machine.dialect;
    const PlannedPoint& first = plan.points[from_point];
    prog.blocks.push_back(comment_block("ballbar two-step SSM, " + std::string(to_string(geom.type)) + ", " +
                                        std::to_string(plan.test_count()) + " tests"));
    prog.blocks.push_back(comment_block(
        "mount the bar at the first point, socket at table frame X" + std::to_string(first.socket_mm.x()) + " Y" +
        std::to_string(first.socket_mm.y()) + " Z" + std::to_string(first.socket_mm.z())));
    prog.blocks.push_back(pose_block(geom, NcMotion::Rapid, first.pose));
    append_dwell(prog, plan, first);
    for (std::size_t i = from_point + 1; i < plan.points.size(); ++i) {
        const PlannedPoint& prev = plan.points[i - 1];
        const PlannedPoint& cur = plan.points[i];
        if (cur.point == 0) {
            std::string what = cur.step == 1 ? "step 1: rotary axes at their start" : "step 2: rotate";
            if (cur.step == 2 && plan.spec.tests[static_cast<std::size_t>(cur.test)].kind == TestKind::TableAlpha)
                what += ", socket on the turning table";
            prog.blocks.push_back(comment_block("test " + std::to_string(cur.test + 1) + " " + what));
        }
        if ((cur.socket_mm - prev.socket_mm).norm() > 1e-9) {
            // A new socket position: the operator remounts; the machine moves there in rapid.
            prog.blocks.push_back(comment_block("move the socket to the next position and remount the bar"));
            prog.blocks.push_back(pose_block(geom, NcMotion::Rapid, cur.pose));
        } else {
            append_transfer(prog, plan, prev, cur, options);
        }
        append_dwell(prog, plan, cur);
    }
    return prog;
}

std::string write_plan_program(const Plan& plan, std::size_t from_point) {
    return write_nc_program(make_nc_program(plan, from_point), "ballbar SSM");
}

}  // namespace ballbar::acquisition
