// SPDX-License-Identifier: MIT
#include "ballbar/analysis/reading_model.hpp"

#include <cmath>

namespace ballbar::analysis {

ReadingModel::RotaryTrig::RotaryTrig(const Pose& pose) {
    const double angle[3] = {pose.A_rad, pose.B_rad, pose.C_rad};
    for (std::size_t k = 0; k < 3; ++k) {
        cos[k] = std::cos(angle[k]);
        sin[k] = std::sin(angle[k]);
    }
}

Mat3 ReadingModel::Axis::rotation(double c0, double s0) const {
    const double c = c0 * cos_zero - s0 * sin_zero;  // cos(angle + zero offset)
    const double s = s0 * cos_zero + c0 * sin_zero;
    return detail::rotation_about(dir, outer, c, s);
}

void ReadingModel::Axis::gradient(const Mat3& r, const Vec3& u, const Vec3& rel_in, const Vec3& rel_out, double g,
                                  std::array<double, kParamCount>& grad) const {
    // p' = q + R(p − q): ∂p'/∂q = I − R; ∂p'/∂zero = dir × (p' − q); for a tilt, ∂R/∂φ = [w]×R − R[w]×,
    // so ∂p'/∂φ = w × (p' − q) − R(w × (p − q)). Dotted with u, where u·(R v) = (Rᵀu)·v.
    const Vec3 rtu = r.transpose() * u;
    for (std::size_t k = 0; k < 2; ++k) {
        grad[static_cast<std::size_t>(off[k])] += g * (u.dot(off_dir[k]) - rtu.dot(off_dir[k]));
        grad[static_cast<std::size_t>(tilt[k])] += g * (u.dot(w[k].cross(rel_out)) - rtu.dot(w[k].cross(rel_in)));
    }
    grad[static_cast<std::size_t>(zero)] += g * u.dot(dir.cross(rel_out));
}

ReadingModel::ReadingModel(const MachineGeometry& geom, const ErrorParams& e) : geom_(geom), e_(e) {
    tool_mm_ = geom.tool_ball_mm - Vec3(0, 0, e[Param::tool_length]);
    // Each axis: its location errors (along unit vectors), its tilts with their w, its zero offset.
    auto make = [&e](Vec3 offset, Vec3 dir, std::array<Param, 2> off, std::array<Vec3, 2> off_dir,
                     std::array<Param, 2> tilt, std::array<Vec3, 2> w, Param zero) {
        Axis a;
        a.offset = offset;
        a.dir = dir;
        a.outer = dir * dir.transpose();
        a.off = off;
        a.off_dir = off_dir;
        a.tilt = tilt;
        a.w = w;
        a.zero = zero;
        a.cos_zero = std::cos(e[zero]);
        a.sin_zero = std::sin(e[zero]);
        return a;
    };
    const Vec3 x = Vec3::UnitX(), y = Vec3::UnitY(), z = Vec3::UnitZ();
    // A: about X, located by Y0A/Z0A, tilted by B0A (about Rz(C0A)·Y) then C0A (about Z).
    a_ = make(Vec3(0, e[Param::Y0A], e[Param::Z0A]), detail::a_axis_dir(e), {Param::Y0A, Param::Z0A}, {y, z},
              {Param::B0A, Param::C0A}, {rot_z(e[Param::C0A]) * y, z}, Param::A_zero);
    // B: about Y, located by X0B/Z0B, tilted by A0B (about Rz(C0B)·X) then C0B (about Z).
    b_ = make(Vec3(e[Param::X0B], 0, e[Param::Z0B]), detail::b_axis_dir(e), {Param::X0B, Param::Z0B}, {x, z},
              {Param::A0B, Param::C0B}, {rot_z(e[Param::C0B]) * x, z}, Param::B_zero);
    // C: about Z, located by X0C/Y0C, tilted by A0C (about Ry(B0C)·X) then B0C (about Y).
    c_ = make(Vec3(e[Param::X0C], e[Param::Y0C], 0), detail::c_axis_dir(e), {Param::X0C, Param::Y0C}, {x, y},
              {Param::A0C, Param::B0C}, {rot_y(e[Param::B0C]) * x, y}, Param::C_zero);
}

double ReadingModel::predict(const Pose& pose, const Vec3& socket_mm, const ReadingConditions& cond,
                             Gradient* grad) const {
    return predict(pose, RotaryTrig(pose), socket_mm, cond, grad);
}

double ReadingModel::predict(const Pose& pose, const RotaryTrig& trig, const Vec3& socket_mm,
                             const ReadingConditions& cond, Gradient* grad) const {
    auto rotation = [&trig](const Axis& axis, std::size_t k) { return axis.rotation(trig.cos[k], trig.sin[k]); };
    const double hours = cond.time_s / 3600.0;
    Vec3 pivot = detail::linear_axes(e_, pose);
    pivot.z() += e_[Param::spindle_growth] * hours;

    Vec3 b = Vec3::Zero(), s = Vec3::Zero();
    // The rotations and the intermediate vectors each branch needs for its gradient.
    Mat3 r_outer = Mat3::Identity(), r_inner = Mat3::Identity();
    Vec3 outer_in = Vec3::Zero(), outer_out = Vec3::Zero(), inner_in = Vec3::Zero(), inner_out = Vec3::Zero();
    switch (geom_.type) {
        case MachineType::TTTRR: {  // table: C carried by A
            const Vec3 p0 = geom_.a_pivot_mm + geom_.c_offset_mm;
            const Vec3 qc = p0 + c_.offset;
            const Vec3 qa = geom_.a_pivot_mm + a_.offset;
            r_inner = rotation(c_, 2);
            r_outer = rotation(a_, 0);
            inner_in = p0 + socket_mm - qc;
            inner_out = r_inner * inner_in;
            outer_in = qc + inner_out - qa;
            outer_out = r_outer * outer_in;
            b = pivot + tool_mm_;
            s = qa + outer_out;
            break;
        }
        case MachineType::RRTTT: {  // head: B carried by A
            const Vec3 qb = pivot + b_.offset;
            const Vec3 qa = pivot + a_.offset;
            r_inner = rotation(b_, 1);
            r_outer = rotation(a_, 0);
            inner_in = pivot + tool_mm_ - qb;
            inner_out = r_inner * inner_in;
            outer_in = qb + inner_out - qa;
            outer_out = r_outer * outer_in;
            b = qa + outer_out;
            s = socket_mm;
            break;
        }
        case MachineType::RTTTR: {  // A on the table, B in the head
            const Vec3 qb = pivot + b_.offset;
            const Vec3 qa = geom_.a_pivot_mm + a_.offset;
            r_inner = rotation(b_, 1);  // "inner": the head's only axis
            r_outer = rotation(a_, 0);  // "outer": the table's only axis
            inner_in = pivot + tool_mm_ - qb;
            inner_out = r_inner * inner_in;
            b = qb + inner_out;
            outer_in = geom_.a_pivot_mm + socket_mm - qa;
            outer_out = r_outer * outer_in;
            s = qa + outer_out;
            break;
        }
    }
    const Vec3 d = b - s;
    const double length = d.norm();
    const double dt = cond.bar_temp_C - 20.0;
    const double gain = 1.0 + e_[Param::bar_kappa] * dt;
    const double value = length * gain + e_[Param::bar_length];
    if (!grad) return value;

    // ∂reading/∂p = gain · u·(∂b/∂p − ∂s/∂p) with u the unit bar direction, plus the bar's own terms.
    auto& g = grad->params;
    g.fill(0.0);
    const Vec3 u = length > 0 ? Vec3(d / length) : Vec3::Zero();
    // The spindle pivot moves the tool ball rigidly on every type (∂b/∂pivot = I).
    const double X = pose.X_mm, Y = pose.Y_mm, Z = pose.Z_mm;
    const double ux = gain * u.x(), uy = gain * u.y(), uz = gain * u.z();
    g[static_cast<std::size_t>(Param::EXX)] = ux * X;
    g[static_cast<std::size_t>(Param::EYY)] = -ux * Y * e_[Param::C0Y] + uy * Y;
    g[static_cast<std::size_t>(Param::EZZ)] = ux * Z * e_[Param::B0Z] - uy * Z * e_[Param::A0Z] + uz * Z;
    g[static_cast<std::size_t>(Param::C0Y)] = -ux * Y * (1.0 + e_[Param::EYY]);
    g[static_cast<std::size_t>(Param::B0Z)] = ux * Z * (1.0 + e_[Param::EZZ]);
    g[static_cast<std::size_t>(Param::A0Z)] = -uy * Z * (1.0 + e_[Param::EZZ]);
    g[static_cast<std::size_t>(Param::spindle_growth)] = uz * hours;
    g[static_cast<std::size_t>(Param::bar_length)] = 1.0;
    g[static_cast<std::size_t>(Param::bar_kappa)] = length * dt;
    // A longer tool moves the ball along the head frame's −Z.
    auto tool_length = [&](const Vec3& u_head) {
        g[static_cast<std::size_t>(Param::tool_length)] = -gain * u_head.z();
    };
    switch (geom_.type) {
        case MachineType::TTTRR: {
            const Vec3 us = -u;  // the table ball enters with −
            a_.gradient(r_outer, us, outer_in, outer_out, gain, g);
            const Vec3 us_c = r_outer.transpose() * us;  // into the frame the A rotation acts on
            c_.gradient(r_inner, us_c, inner_in, inner_out, gain, g);
            grad->socket_mm = gain * (r_inner.transpose() * us_c);
            tool_length(u);
            break;
        }
        case MachineType::RRTTT: {
            a_.gradient(r_outer, u, outer_in, outer_out, gain, g);
            const Vec3 ub = r_outer.transpose() * u;
            b_.gradient(r_inner, ub, inner_in, inner_out, gain, g);
            tool_length(r_inner.transpose() * ub);
            grad->socket_mm = -gain * u;
            break;
        }
        case MachineType::RTTTR: {
            b_.gradient(r_inner, u, inner_in, inner_out, gain, g);
            tool_length(r_inner.transpose() * u);
            const Vec3 us = -u;
            a_.gradient(r_outer, us, outer_in, outer_out, gain, g);
            grad->socket_mm = gain * (r_outer.transpose() * us);
            break;
        }
    }
    return value;
}

}  // namespace ballbar::analysis
