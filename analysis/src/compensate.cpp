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

// Rotations about the coordinate axes by the angle with cosine c and sine s (and their inverses, _t),
// component-wise: the nominal machine's rotary axes are coordinate axes.
inline Vec3 rotate_x(double c, double s, const Vec3& v) {
    return {v.x(), c * v.y() - s * v.z(), s * v.y() + c * v.z()};
}
inline Vec3 rot_x_t(double c, double s, const Vec3& v) {
    return {v.x(), c * v.y() + s * v.z(), -s * v.y() + c * v.z()};
}
inline Vec3 rotate_y(double c, double s, const Vec3& v) {
    return {c * v.x() + s * v.z(), v.y(), -s * v.x() + c * v.z()};
}
inline Vec3 rotate_z(double c, double s, const Vec3& v) {
    return {c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()};
}
inline Vec3 rot_z_t(double c, double s, const Vec3& v) {
    return {c * v.x() + s * v.y(), -s * v.x() + c * v.y(), v.z()};
}

// Only TTTRR's second rotary axis is C (rotary_axes(), without a call per pose).
constexpr bool second_is_c(MachineType type) {
    return type == MachineType::TTTRR;
}

double rotary_angle(MachineType type, const Pose& p, int which) {
    if (which == 0) return p.A_rad;
    return second_is_c(type) ? p.C_rad : p.B_rad;
}

double angle_between(const Vec3& a, const Vec3& b) {
    return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace

Mat3 MachineModel::Axis::rotation(double c0, double s0) const {
    const double c = c0 * cos_zero - s0 * sin_zero;  // cos(angle + zero offset)
    const double s = s0 * cos_zero + c0 * sin_zero;
    return detail::rotation_about(dir, outer, c, s);
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
    switch (geom.type) {
        case MachineType::TTTRR:
            chain_ = second_.point - first_.point;
            base_ = geom.a_pivot_mm + geom.c_offset_mm - second_.point;
            break;
        case MachineType::RTTTR:
            base_ = geom.a_pivot_mm - first_.point;
            break;
        case MachineType::RRTTT:
            break;
    }
}

MachineModel::MachineModel(const MachineGeometry& geom, const ErrorParams& e, std::span<const LearnedTerm> terms)
    : MachineModel(geom, e) {
    for (const LearnedTerm& t : terms)
        if (t.term.kind == EmpiricalKind::rotary_angular || t.term.kind == EmpiricalKind::linear_positioning)
            terms_.push_back(t);
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
    return tool_pose(pose, tr, Vec3::Zero());
}

ToolPose MachineModel::tool_pose(const Pose& pose, const Trig& tr, const Vec3& shift) const {
    // Rotation matrices are built once per pose and applied to vectors; their products are never
    // formed (two matrix products cost more than the four matrix-vector products they save).
    if (!terms_.empty()) {  // learned terms: the axes' actual positions, then the model as it is
        Pose p = pose;
        p.X_mm += linear_positioning_error(terms_, 'X', pose.X_mm);
        p.Y_mm += linear_positioning_error(terms_, 'Y', pose.Y_mm);
        p.Z_mm += linear_positioning_error(terms_, 'Z', pose.Z_mm);
        const RotaryAxes ax = rotary_axes(geom_.type);
        const double e1 = rotary_angle_error(terms_, ax.first, rotary_angle(geom_.type, pose, 0));
        const double e2 = rotary_angle_error(terms_, ax.second, rotary_angle(geom_.type, pose, 1));
        const double c1 = std::cos(e1), s1 = std::sin(e1), c2 = std::cos(e2), s2 = std::sin(e2);
        const Trig shifted{tr.c1 * c1 - tr.s1 * s1, tr.s1 * c1 + tr.c1 * s1, tr.c2 * c2 - tr.s2 * s2,
                           tr.s2 * c2 + tr.c2 * s2};
        return static_pose(p, shifted, shift);
    }
    return static_pose(pose, tr, shift);
}

ToolPose MachineModel::static_pose(const Pose& pose, const Trig& tr, const Vec3& shift) const {
    const Vec3 pivot = detail::linear_axes(e_, pose);
    const Vec3 tool_mm = tool_mm_ + shift;
    const Mat3 ra = first_.rotation(tr.c1, tr.s1);
    const Mat3 rb = second_.rotation(tr.c2, tr.s2);
    switch (geom_.type) {
        case MachineType::TTTRR: {
            // Table point x ↦ qa + Ra(qc − qa + Rc(x + p0 − qc)); inverted for the tool ball.
            const Vec3 ball = pivot + tool_mm;
            const Vec3 in_a = ra.transpose() * (ball - first_.point) - chain_;
            return {rb.transpose() * in_a - base_, rb.transpose() * ra.row(2).transpose()};
        }
        case MachineType::RRTTT: {
            const Vec3 qa = pivot + first_.point;
            const Vec3 qb = pivot + second_.point;
            return {qa + ra * (qb - qa + rb * (pivot + tool_mm - qb)), ra * rb.col(2)};
        }
        case MachineType::RTTTR: {
            const Vec3 qb = pivot + second_.point;
            const Vec3 ball = qb + rb * (pivot + tool_mm - qb);
            return {ra.transpose() * (ball - first_.point) - base_, ra.transpose() * rb.col(2)};
        }
    }
    return {};
}

double default_singular_tolerance() {
    return std::sin(deg_to_rad(kDefaultSingularDeg));
}

Pose add_correction(MachineType type, const Pose& u, const std::array<double, 5>& du) {
    Pose out = u;
    out.X_mm += du[0];
    out.Y_mm += du[1];
    out.Z_mm += du[2];
    out.A_rad += du[3];
    if (second_is_c(type))
        out.C_rad += du[4];
    else
        out.B_rad += du[4];
    return out;
}

Compensator::Compensator(const MachineGeometry& geom, const ErrorParams& e, CompensationOptions options)
    : Compensator(geom, e, {}, options) {}

Compensator::Compensator(const MachineGeometry& geom, const ErrorParams& e, std::span<const LearnedTerm> terms,
                         CompensationOptions options)
    : nominal_(geom, ErrorParams{}), actual_(geom, e, terms), options_(options) {
    if (!(options_.singular_tolerance >= 0 && options_.singular_tolerance < 1))
        throw AnalysisError("compensation: singular_tolerance must be in [0, 1)");
    if (options_.max_iterations < 1) throw AnalysisError("compensation: max_iterations must be at least 1");
}

Compensator::Frame Compensator::frame(const Pose& u, const MachineModel::Trig& tr, const Vec3& shift) const {
    // The nominal axes are coordinate axes, so the rotations are applied component-wise. A table
    // axis turns the workpiece under the tool (sign −), a head axis turns the tool (sign +). The
    // Jacobian columns rtᵀ(k × v) are formed in the table frame as (rtᵀk) × (rtᵀv).
    const MachineGeometry& g = nominal_.geometry();
    const double c1 = tr.c1, s1 = tr.s1, c2 = tr.c2, s2 = tr.s2;
    Frame f;
    f.type = g.type;
    f.tr = tr;
    const Vec3 lin = u.linear_mm();
    const Vec3 tool_ball = g.tool_ball_mm + shift;
    switch (g.type) {
        case MachineType::TTTRR: {
            // rt = Rx(A)·Rz(C), t = a_pivot + Rx(A)·c_offset.
            const Vec3 v = lin + tool_ball - g.a_pivot_mm;                  // ball − a_pivot, machine frame
            const Vec3 va = rot_x_t(c1, s1, v) - g.c_offset_mm;             // Rxᵀ(ball − t)
            f.position = rot_z_t(c2, s2, va);                               // rtᵀ(ball − t)
            f.direction = rot_z_t(c2, s2, Vec3(0, s1, c1));                 // rtᵀ e_z
            const Vec3 kx(c2, -s2, 0);                                      // rtᵀ e_x
            const Vec3 to_a = f.position + rot_z_t(c2, s2, g.c_offset_mm);  // rtᵀ(ball − a_pivot)
            f.cw[0] = -kx.cross(to_a);
            f.cq[0] = -kx.cross(f.direction);
            // rtᵀ(Rx e_z) = e_z, and −e_z × v = (v.y, −v.x, 0).
            f.cw[1] = Vec3(f.position.y(), -f.position.x(), 0);
            f.cq[1] = Vec3(f.direction.y(), -f.direction.x(), 0);
            break;
        }
        case MachineType::RRTTT: {
            // rt = I: the head turns the tool by Rx(A)·Ry(B) about the spindle pivot.
            const Vec3 arm = rotate_x(c1, s1, rotate_y(c2, s2, tool_ball));
            f.position = lin + arm;
            f.direction = rotate_x(c1, s1, Vec3(s2, 0, c2));
            const Vec3 kb(0, c1, s1);  // Rx e_y
            f.cw[0] = Vec3::UnitX().cross(arm);
            f.cq[0] = Vec3::UnitX().cross(f.direction);
            f.cw[1] = kb.cross(arm);
            f.cq[1] = kb.cross(f.direction);
            break;
        }
        case MachineType::RTTTR: {
            // rt = Rx(A), t = a_pivot; the head turns the tool by Ry(B).
            const Vec3 arm = rotate_y(c2, s2, tool_ball);
            f.position = rot_x_t(c1, s1, lin + arm - g.a_pivot_mm);
            f.direction = rot_x_t(c1, s1, Vec3(s2, 0, c2));
            const Vec3 kb(0, c1, -s1);  // Rxᵀ e_y
            // −e_x × v = (0, v.z, −v.y).
            f.cw[0] = Vec3(0, f.position.z(), -f.position.y());
            f.cq[0] = Vec3(0, f.direction.z(), -f.direction.y());
            f.cw[1] = kb.cross(rot_x_t(c1, s1, arm));
            f.cq[1] = kb.cross(f.direction);
            break;
        }
    }
    return f;
}

Vec3 Compensator::Frame::to_machine(const Vec3& v) const {
    switch (type) {
        case MachineType::TTTRR:
            return rotate_x(tr.c1, tr.s1, rotate_z(tr.c2, tr.s2, v));
        case MachineType::RTTTR:
            return rotate_x(tr.c1, tr.s1, v);
        case MachineType::RRTTT:
            break;
    }
    return v;
}

std::array<double, 5> Compensator::step(const Frame& f, const Vec3& dw, const Vec3& dq, int& suppressed) const {
    const Vec3* cq = f.cq;
    const Vec3* cw = f.cw;
    const double n11 = cq[0].squaredNorm(), n22 = cq[1].squaredNorm();
    if (suppressed < 0) {
        // |cq| = |sin| of the angle between the axis and the tool axis.
        const double tol2 = options_.singular_tolerance * options_.singular_tolerance;
        if (n22 <= tol2)
            suppressed = 4;
        else if (n11 <= tol2)
            suppressed = 3;
    }
    double d1 = 0, d2 = 0;
    if (suppressed < 0) {  // least squares over the three direction components
        const double n12 = cq[0].dot(cq[1]);
        const double b1 = cq[0].dot(dq), b2 = cq[1].dot(dq);
        const double det = n11 * n22 - n12 * n12;
        if (det > 0) {
            const double inv_det = 1.0 / det;
            d1 = (n22 * b1 - n12 * b2) * inv_det;
            d2 = (n11 * b2 - n12 * b1) * inv_det;
        }
        if (!(det > 0) || !(std::abs(d1) <= options_.max_rotary_step_rad) ||
            !(std::abs(d2) <= options_.max_rotary_step_rad))
            suppressed = n22 <= n11 ? 4 : 3;  // too near a singularity for the split
    }
    if (suppressed == 4) {
        d1 = n11 > 0 ? cq[0].dot(dq) / n11 : 0.0;
        d2 = 0;
    } else if (suppressed == 3) {
        d1 = 0;
        d2 = n22 > 0 ? cq[1].dot(dq) / n22 : 0.0;
    }
    const Vec3 dp = f.to_machine(dw - cw[0] * d1 - cw[1] * d2);
    return {dp.x(), dp.y(), dp.z(), d1, d2};
}

// The hot path of `ballbar compensate` (≥ 10 M poses/s): everything it calls, Eigen's fixed-size
// kernels included, is inlined into it (GCC and Clang; GCC 12 at -O2 otherwise leaves calls per
// 3-vector assignment). It takes -fno-semantic-interposition (cmake/Warnings.cmake) as well: under
// -fPIC, GCC will not inline a function another library could interpose. 99 → 73 ns per pose.
#if defined(__GNUC__)
__attribute__((flatten))
#endif
Correction
Compensator::first_order_shifted(const Pose& u, const Vec3& shift) const {
    const MachineModel::Trig tr = MachineModel::trig(nominal_.geometry().type, u);
    const Frame f = frame(u, tr, shift);
    const ToolPose got = actual_.tool_pose(u, tr, shift);
    Correction c;
    int suppressed = -1;
    c.du = step(f, f.position - got.position_mm, f.direction - got.direction, suppressed);
    c.singular = suppressed >= 0;
    c.suppressed_axis = suppressed;
    c.commanded = add_correction(nominal_.geometry().type, u, c.du);
    c.iterations = 1;
    return c;
}

Correction Compensator::first_order(const Pose& u) const {
    return first_order_shifted(u, Vec3::Zero());
}

Correction Compensator::first_order(const Pose& u, const Vec3& tool_ball_mm) const {
    return first_order_shifted(u, tool_ball_mm - nominal_.geometry().tool_ball_mm);
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
        const std::array<double, 5> inc =
            step(frame(cur, MachineModel::trig(type, cur), Vec3::Zero()), dw, dq, suppressed);
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
