// SPDX-License-Identifier: MIT
// Forward kinematics of the three seed machine types: where the tool ball `b` and the table ball `s`
// are in the machine frame, nominally and with error parameters.
//
// The actual model is templated on the scalar so identification can differentiate it with Eigen's
// forward-mode AutoDiffScalar; `double` instantiations are what everything else calls.
// docs/kinematics.md derives the conventions and the error terms.
#pragma once

#include <cmath>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

template <typename T>
using Vec3T = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat3T = Eigen::Matrix<T, 3, 3>;

Mat3 rot_x(double angle_rad);
Mat3 rot_y(double angle_rad);
Mat3 rot_z(double angle_rad);

/// Ball centres in the machine frame.
struct BallCentres {
    Vec3 tool;   ///< b
    Vec3 table;  ///< s
};

/// Nominal centres: exactly the table of `ballbar-readings/1`. `socket_mm` is the table ball in the
/// table's own frame (for RRTTT the machine frame).
BallCentres nominal_balls(const MachineGeometry& geom, const Pose& pose, const Vec3& socket_mm);
Vec3 nominal_tool_ball(const MachineGeometry& geom, const Pose& pose);
Vec3 nominal_table_ball(const MachineGeometry& geom, const Pose& pose, const Vec3& socket_mm);
/// |b − s|: the bar length the machine commands.
double nominal_length(const MachineGeometry& geom, const Pose& pose, const Vec3& socket_mm);

/// The inverse of the linear part: the commanded X, Y, Z that put the nominal tool ball at
/// `tool_ball_mm` with the rotary axes of `rotary` (its X/Y/Z are ignored).
Pose command_for_tool_ball(const MachineGeometry& geom, const Pose& rotary, const Vec3& tool_ball_mm);

/// Everything the actual model needs beyond the pose: session time (spindle growth) and bar
/// temperature (bar expansion).
struct ReadingConditions {
    double time_s = 0;
    double bar_temp_C = 20.0;
};

namespace detail {

template <typename T>
Mat3T<T> rot_x_t(const T& a) {
    using std::cos;
    using std::sin;
    Mat3T<T> r;
    r << T(1), T(0), T(0), T(0), cos(a), -sin(a), T(0), sin(a), cos(a);
    return r;
}
template <typename T>
Mat3T<T> rot_y_t(const T& a) {
    using std::cos;
    using std::sin;
    Mat3T<T> r;
    r << cos(a), T(0), sin(a), T(0), T(1), T(0), -sin(a), T(0), cos(a);
    return r;
}
template <typename T>
Mat3T<T> rot_z_t(const T& a) {
    using std::cos;
    using std::sin;
    Mat3T<T> r;
    r << cos(a), -sin(a), T(0), sin(a), cos(a), T(0), T(0), T(0), T(1);
    return r;
}

/// Rotates p by `angle` about the line through `q` with unit direction `d` (Rodrigues).
template <typename T>
Vec3T<T> rotate_about_line(const Vec3T<T>& p, const Vec3T<T>& q, const Vec3T<T>& d, const T& angle) {
    using std::cos;
    using std::sin;
    const Vec3T<T> v = p - q;
    const T c = cos(angle);
    const T s = sin(angle);
    return q + v * c + d.cross(v) * s + d * (d.dot(v) * (T(1) - c));
}

/// R(d, θ) = c·I + s·[d]× + (1 − c)·d·dᵀ, entry by entry, for a unit axis d with d·dᵀ = `outer` and
/// c, s the cosine and sine of θ (the compensation and identification hot paths build it per pose).
inline Mat3 rotation_about(const Vec3& d, const Mat3& outer, double c, double s) {
    const double k = 1.0 - c;
    const double sx = s * d.x(), sy = s * d.y(), sz = s * d.z();
    Mat3 r;
    r << c + k * outer(0, 0), k * outer(0, 1) - sz, k * outer(0, 2) + sy,  //
        k * outer(1, 0) + sz, c + k * outer(1, 1), k * outer(1, 2) - sx,   //
        k * outer(2, 0) - sy, k * outer(2, 1) + sx, c + k * outer(2, 2);
    return r;
}

template <typename T>
Vec3T<T> vec(const Vec3& v) {
    return Vec3T<T>(T(v.x()), T(v.y()), T(v.z()));
}

/// Actual position of the commanded linear point: scale and squareness of the linear axes.
template <typename T>
Vec3T<T> linear_axes(const ErrorParamsT<T>& e, const Pose& pose) {
    const T x = T(pose.X_mm) * (T(1) + e[Param::EXX]);
    const T y = T(pose.Y_mm) * (T(1) + e[Param::EYY]);
    const T z = T(pose.Z_mm) * (T(1) + e[Param::EZZ]);
    return Vec3T<T>(x - y * e[Param::C0Y] + z * e[Param::B0Z], y - z * e[Param::A0Z], z);
}

// Directions of the actual rotary axes: the nominal axis turned by its two tilt errors.
template <typename T>
Vec3T<T> a_axis_dir(const ErrorParamsT<T>& e) {
    return rot_z_t(e[Param::C0A]) * rot_y_t(e[Param::B0A]) * Vec3T<T>(T(1), T(0), T(0));
}
template <typename T>
Vec3T<T> b_axis_dir(const ErrorParamsT<T>& e) {
    return rot_z_t(e[Param::C0B]) * rot_x_t(e[Param::A0B]) * Vec3T<T>(T(0), T(1), T(0));
}
template <typename T>
Vec3T<T> c_axis_dir(const ErrorParamsT<T>& e) {
    return rot_y_t(e[Param::B0C]) * rot_x_t(e[Param::A0C]) * Vec3T<T>(T(0), T(0), T(1));
}

}  // namespace detail

/// Actual tool-ball centre with error parameters `e` (see docs/kinematics.md).
template <typename T>
Vec3T<T> actual_tool_ball(const MachineGeometry& geom, const ErrorParamsT<T>& e, const Pose& pose,
                          const ReadingConditions& cond) {
    using namespace detail;
    Vec3T<T> pivot = linear_axes(e, pose);
    pivot.z() += e[Param::spindle_growth] * T(cond.time_s / 3600.0);
    // A longer tool moves the ball along the head frame's −Z (the tool points down).
    const Vec3T<T> tool = vec<T>(geom.tool_ball_mm) - Vec3T<T>(T(0), T(0), e[Param::tool_length]);
    switch (geom.type) {
        case MachineType::TTTRR:
            return pivot + tool;
        case MachineType::RRTTT: {
            // B is carried by A: rotate about B's line first, then about A's line.
            const Vec3T<T> qb = pivot + Vec3T<T>(e[Param::X0B], T(0), e[Param::Z0B]);
            const Vec3T<T> qa = pivot + Vec3T<T>(T(0), e[Param::Y0A], e[Param::Z0A]);
            Vec3T<T> b = rotate_about_line<T>(pivot + tool, qb, b_axis_dir(e), T(pose.B_rad) + e[Param::B_zero]);
            return rotate_about_line<T>(b, qa, a_axis_dir(e), T(pose.A_rad) + e[Param::A_zero]);
        }
        case MachineType::RTTTR: {
            const Vec3T<T> qb = pivot + Vec3T<T>(e[Param::X0B], T(0), e[Param::Z0B]);
            return rotate_about_line<T>(pivot + tool, qb, b_axis_dir(e), T(pose.B_rad) + e[Param::B_zero]);
        }
    }
    return pivot + tool;
}

/// Actual table-ball centre. `socket_mm` is the socket's actual place in the table frame (the nominal
/// socket plus its set-up offset, which identification estimates per socket position).
template <typename T>
Vec3T<T> actual_table_ball(const MachineGeometry& geom, const ErrorParamsT<T>& e, const Pose& pose,
                           const Vec3T<T>& socket_mm) {
    using namespace detail;
    switch (geom.type) {
        case MachineType::RRTTT:
            return socket_mm;
        case MachineType::TTTRR: {
            // C is carried by A. At zero angles the ball sits at a_pivot + c_offset + socket.
            const Vec3T<T> s0 = vec<T>(geom.a_pivot_mm + geom.c_offset_mm) + socket_mm;
            const Vec3T<T> qc =
                vec<T>(geom.a_pivot_mm + geom.c_offset_mm) + Vec3T<T>(e[Param::X0C], e[Param::Y0C], T(0));
            const Vec3T<T> qa = vec<T>(geom.a_pivot_mm) + Vec3T<T>(T(0), e[Param::Y0A], e[Param::Z0A]);
            const Vec3T<T> sc = rotate_about_line<T>(s0, qc, c_axis_dir(e), T(pose.C_rad) + e[Param::C_zero]);
            return rotate_about_line<T>(sc, qa, a_axis_dir(e), T(pose.A_rad) + e[Param::A_zero]);
        }
        case MachineType::RTTTR: {
            const Vec3T<T> s0 = vec<T>(geom.a_pivot_mm) + socket_mm;
            const Vec3T<T> qa = vec<T>(geom.a_pivot_mm) + Vec3T<T>(T(0), e[Param::Y0A], e[Param::Z0A]);
            return rotate_about_line<T>(s0, qa, a_axis_dir(e), T(pose.A_rad) + e[Param::A_zero]);
        }
    }
    return socket_mm;
}

/// What the bar would read: |b − s| plus the bar's own errors (length offset, thermal expansion).
template <typename T>
T predicted_reading(const MachineGeometry& geom, const ErrorParamsT<T>& e, const Pose& pose, const Vec3T<T>& socket_mm,
                    const ReadingConditions& cond) {
    const T length = (actual_tool_ball(geom, e, pose, cond) - actual_table_ball(geom, e, pose, socket_mm)).norm();
    return length + e[Param::bar_length] + length * e[Param::bar_kappa] * T(cond.bar_temp_C - 20.0);
}

BallCentres actual_balls(const MachineGeometry& geom, const ErrorParams& e, const Pose& pose, const Vec3& socket_mm,
                         const ReadingConditions& cond = {});
double predicted_reading(const MachineGeometry& geom, const ErrorParams& e, const Pose& pose, const Vec3& socket_mm,
                         const ReadingConditions& cond = {});

/// The seeds' total position error at a pose: (b − s)_actual − (b − s)_nominal, what SSM measures
/// with the table ball as datum when the error is common to the location's points.
Vec3 total_position_error(const MachineGeometry& geom, const ErrorParams& e, const Pose& pose, const Vec3& socket_mm,
                          const ReadingConditions& cond = {});

}  // namespace ballbar::analysis
