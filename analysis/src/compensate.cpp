// SPDX-License-Identifier: MIT
#include "ballbar/analysis/compensate.hpp"

#include <cmath>

#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::analysis {
namespace {

Mat3 cross_matrix(const Vec3& d) {
    Mat3 k;
    k << 0, -d.z(), d.y(), d.z(), 0, -d.x(), -d.y(), d.x(), 0;
    return k;
}

double rotary_angle(MachineType type, const Pose& p, int which) {
    if (which == 0) return p.A_rad;
    return rotary_axes(type).second == 'C' ? p.C_rad : p.B_rad;
}

double angle_between(const Vec3& a, const Vec3& b) {
    return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace

Mat3 MachineModel::Axis::rotation(double c0, double s0) const {
    const double c = c0 * cos_zero - s0 * sin_zero;  // cos(angle + zero offset)
    const double s = s0 * cos_zero + c0 * sin_zero;
    Mat3 r = (1.0 - c) * outer + s * cross;
    r.diagonal().array() += c;
    return r;
}

MachineModel::MachineModel(const MachineGeometry& geom, const ErrorParams& e) : geom_(geom), e_(e) {
    using namespace detail;
    auto make = [](const Vec3& point, const Vec3& dir, double zero) {
        Axis a;
        a.point = point;
        a.dir = dir.normalized();
        a.cross = cross_matrix(a.dir);
        a.outer = a.dir * a.dir.transpose();
        a.cos_zero = std::cos(zero);
        a.sin_zero = std::sin(zero);
        return a;
    };
    const Vec3 a_dir = a_axis_dir(e);
    tool_mm_ = geom.tool_ball_mm - Vec3(0, 0, e[Param::tool_length]);
    switch (geom.type) {
        case MachineType::TTTRR:
            first_ = make(geom.a_pivot_mm + Vec3(0, e[Param::Y0A], e[Param::Z0A]), a_dir, e[Param::A_zero]);
            second_ = make(geom.a_pivot_mm + geom.c_offset_mm + Vec3(e[Param::X0C], e[Param::Y0C], 0), c_axis_dir(e),
                           e[Param::C_zero]);
            break;
        case MachineType::RRTTT:  // head axes: points relative to the spindle pivot
            first_ = make(Vec3(0, e[Param::Y0A], e[Param::Z0A]), a_dir, e[Param::A_zero]);
            second_ = make(Vec3(e[Param::X0B], 0, e[Param::Z0B]), b_axis_dir(e), e[Param::B_zero]);
            break;
        case MachineType::RTTTR:  // A on the table, B in the head (point relative to the pivot)
            first_ = make(geom.a_pivot_mm + Vec3(0, e[Param::Y0A], e[Param::Z0A]), a_dir, e[Param::A_zero]);
            second_ = make(Vec3(e[Param::X0B], 0, e[Param::Z0B]), b_axis_dir(e), e[Param::B_zero]);
            break;
    }
}

MachineModel::Trig MachineModel::trig(MachineType type, const Pose& pose) {
    const double r1 = rotary_angle(type, pose, 0);
    const double r2 = rotary_angle(type, pose, 1);
    return {std::cos(r1), std::sin(r1), std::cos(r2), std::sin(r2)};
}

ToolPose MachineModel::tool_pose(const Pose& pose) const {
    return tool_pose(pose, trig(geom_.type, pose));
}

ToolPose MachineModel::tool_pose(const Pose& pose, const Trig& tr) const {
    const Vec3 pivot = detail::linear_axes(e_, pose);
    const Mat3 ra = first_.rotation(tr.c1, tr.s1);
    const Mat3 rb = second_.rotation(tr.c2, tr.s2);
    Mat3 rt = Mat3::Identity();  // table frame → machine
    Vec3 t = Vec3::Zero();
    Vec3 ball = Vec3::Zero();
    Vec3 dir = Vec3::UnitZ();
    switch (geom_.type) {
        case MachineType::TTTRR: {
            const Vec3& qa = first_.point;
            const Vec3& qc = second_.point;
            rt = ra * rb;
            t = qa + ra * (qc - qa + rb * (geom_.a_pivot_mm + geom_.c_offset_mm - qc));
            ball = pivot + tool_mm_;
            break;
        }
        case MachineType::RRTTT: {
            const Vec3 qa = pivot + first_.point;
            const Vec3 qb = pivot + second_.point;
            ball = qa + ra * (qb - qa + rb * (pivot + tool_mm_ - qb));
            dir = ra * (rb * Vec3::UnitZ());
            break;
        }
        case MachineType::RTTTR: {
            const Vec3& qa = first_.point;
            const Vec3 qb = pivot + second_.point;
            rt = ra;
            t = qa + ra * (geom_.a_pivot_mm - qa);
            ball = qb + rb * (pivot + tool_mm_ - qb);
            dir = rb * Vec3::UnitZ();
            break;
        }
    }
    return {rt.transpose() * (ball - t), rt.transpose() * dir};
}

Pose add_correction(MachineType type, const Pose& u, const std::array<double, 5>& du) {
    Pose out = u;
    out.X_mm += du[0];
    out.Y_mm += du[1];
    out.Z_mm += du[2];
    out.A_rad += du[3];
    if (rotary_axes(type).second == 'C')
        out.C_rad += du[4];
    else
        out.B_rad += du[4];
    return out;
}

Compensator::Compensator(const MachineGeometry& geom, const ErrorParams& e, CompensationOptions options)
    : nominal_(geom, ErrorParams{}), actual_(geom, e), options_(options) {
    if (!(options_.singular_tolerance >= 0 && options_.singular_tolerance < 1))
        throw AnalysisError("compensation: singular_tolerance must be in [0, 1)");
    if (options_.max_iterations < 1) throw AnalysisError("compensation: max_iterations must be at least 1");
}

Compensator::Frame Compensator::frame(const Pose& u, const MachineModel::Trig& tr) const {
    // A table axis turns the workpiece under the tool (sign −), a head axis turns the tool (sign +).
    const MachineGeometry& g = nominal_.geometry();
    Mat3 rx, r2;
    rx << 1, 0, 0, 0, tr.c1, -tr.s1, 0, tr.s1, tr.c1;
    if (g.type == MachineType::TTTRR)
        r2 << tr.c2, -tr.s2, 0, tr.s2, tr.c2, 0, 0, 0, 1;  // Rz(C)
    else
        r2 << tr.c2, 0, tr.s2, 0, 1, 0, -tr.s2, 0, tr.c2;  // Ry(B)
    Frame f;
    f.rt = Mat3::Identity();
    f.t = Vec3::Zero();
    f.ball = u.linear_mm();
    f.dir = Vec3::UnitZ();
    struct Line {
        Vec3 k, p;
        double sign;
    } lines[2];
    switch (g.type) {
        case MachineType::TTTRR:
            f.rt = rx * r2;
            f.t = g.a_pivot_mm + rx * g.c_offset_mm;
            f.ball += g.tool_ball_mm;
            lines[0] = {Vec3::UnitX(), g.a_pivot_mm, -1};
            lines[1] = {rx.col(2), f.t, -1};
            break;
        case MachineType::RRTTT:
            f.dir = rx * r2.col(2);
            f.ball += rx * (r2 * g.tool_ball_mm);
            lines[0] = {Vec3::UnitX(), u.linear_mm(), 1};
            lines[1] = {rx.col(1), u.linear_mm(), 1};
            break;
        case MachineType::RTTTR:
            f.rt = rx;
            f.t = g.a_pivot_mm;
            f.dir = r2.col(2);
            f.ball += r2 * g.tool_ball_mm;
            lines[0] = {Vec3::UnitX(), g.a_pivot_mm, -1};
            lines[1] = {Vec3::UnitY(), u.linear_mm(), 1};
            break;
    }
    for (int j = 0; j < 2; ++j) {
        f.cw[j] = lines[j].sign * (f.rt.transpose() * lines[j].k.cross(f.ball - lines[j].p));
        f.cq[j] = lines[j].sign * (f.rt.transpose() * lines[j].k.cross(f.dir));
    }
    return f;
}

std::array<double, 5> Compensator::step(const Frame& f, const Vec3& dw, const Vec3& dq, int& suppressed) const {
    const Vec3* cq = f.cq;
    const Vec3* cw = f.cw;
    if (suppressed < 0) {
        // |cq| = |sin| of the angle between the axis and the tool axis.
        if (cq[1].norm() < options_.singular_tolerance)
            suppressed = 4;
        else if (cq[0].norm() < options_.singular_tolerance)
            suppressed = 3;
    }
    double d1 = 0, d2 = 0;
    if (suppressed == 4) {
        d1 = cq[0].dot(dq) / cq[0].squaredNorm();
    } else if (suppressed == 3) {
        d2 = cq[1].dot(dq) / cq[1].squaredNorm();
    } else {  // least squares over the three direction components
        const double n11 = cq[0].squaredNorm(), n12 = cq[0].dot(cq[1]), n22 = cq[1].squaredNorm();
        const double b1 = cq[0].dot(dq), b2 = cq[1].dot(dq);
        const double det = n11 * n22 - n12 * n12;
        d1 = (n22 * b1 - n12 * b2) / det;
        d2 = (n11 * b2 - n12 * b1) / det;
    }
    const Vec3 dp = f.rt * (dw - cw[0] * d1 - cw[1] * d2);
    return {dp.x(), dp.y(), dp.z(), d1, d2};
}

Correction Compensator::first_order(const Pose& u) const {
    const MachineModel::Trig tr = MachineModel::trig(nominal_.geometry().type, u);
    const Frame f = frame(u, tr);
    const ToolPose want = f.tool_pose();
    const ToolPose got = actual_.tool_pose(u, tr);
    Correction c;
    int suppressed = -1;
    c.du = step(f, want.position_mm - got.position_mm, want.direction - got.direction, suppressed);
    c.singular = suppressed >= 0;
    c.suppressed_axis = suppressed;
    c.commanded = add_correction(nominal_.geometry().type, u, c.du);
    c.iterations = 1;
    return c;
}

Correction Compensator::exact(const Pose& u) const {
    const MachineType type = nominal_.geometry().type;
    const ToolPose want = nominal_.tool_pose(u);
    Correction c;
    int suppressed = -1;
    Pose cur = u;
    c.converged = false;
    for (c.iterations = 0; c.iterations <= options_.max_iterations; ++c.iterations) {
        const ToolPose got = actual_.tool_pose(cur);
        const Vec3 dw = want.position_mm - got.position_mm;
        const Vec3 dq = want.direction - got.direction;
        c.position_error_mm = dw.norm();
        c.direction_error_rad = angle_between(want.direction, got.direction);
        if (c.iterations == options_.max_iterations) break;
        const std::array<double, 5> inc = step(frame(cur, MachineModel::trig(type, cur)), dw, dq, suppressed);
        const bool direction_done = suppressed >= 0 ? std::abs(inc[3]) + std::abs(inc[4]) <= options_.tolerance_rad
                                                    : c.direction_error_rad <= options_.tolerance_rad;
        if (c.position_error_mm <= options_.tolerance_mm && direction_done) {
            c.converged = true;
            break;
        }
        for (int k = 0; k < 5; ++k) c.du[static_cast<std::size_t>(k)] += inc[static_cast<std::size_t>(k)];
        cur = add_correction(type, u, c.du);
    }
    c.singular = suppressed >= 0;
    c.suppressed_axis = suppressed;
    c.commanded = cur;
    return c;
}

}  // namespace ballbar::analysis
