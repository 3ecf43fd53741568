// SPDX-License-Identifier: MIT
#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::analysis {

Mat3 rot_x(double a) {
    return detail::rot_x_t(a);
}
Mat3 rot_y(double a) {
    return detail::rot_y_t(a);
}
Mat3 rot_z(double a) {
    return detail::rot_z_t(a);
}

Vec3 nominal_tool_ball(const MachineGeometry& geom, const Pose& pose) {
    const Vec3 p = pose.linear_mm();
    switch (geom.type) {
        case MachineType::RRTTT:
            return p + rot_x(pose.A_rad) * rot_y(pose.B_rad) * geom.tool_ball_mm;
        case MachineType::TTTRR:
            return p + geom.tool_ball_mm;
        case MachineType::RTTTR:
            return p + rot_y(pose.B_rad) * geom.tool_ball_mm;
    }
    return p;
}

Vec3 nominal_table_ball(const MachineGeometry& geom, const Pose& pose, const Vec3& socket_mm) {
    switch (geom.type) {
        case MachineType::RRTTT:
            return socket_mm;
        case MachineType::TTTRR:
            return geom.a_pivot_mm + rot_x(pose.A_rad) * (geom.c_offset_mm + rot_z(pose.C_rad) * socket_mm);
        case MachineType::RTTTR:
            return geom.a_pivot_mm + rot_x(pose.A_rad) * socket_mm;
    }
    return socket_mm;
}

BallCentres nominal_balls(const MachineGeometry& geom, const Pose& pose, const Vec3& socket_mm) {
    return {nominal_tool_ball(geom, pose), nominal_table_ball(geom, pose, socket_mm)};
}

double nominal_length(const MachineGeometry& geom, const Pose& pose, const Vec3& socket_mm) {
    return (nominal_tool_ball(geom, pose) - nominal_table_ball(geom, pose, socket_mm)).norm();
}

Pose command_for_tool_ball(const MachineGeometry& geom, const Pose& rotary, const Vec3& tool_ball_mm) {
    Pose out = rotary;
    out.X_mm = out.Y_mm = out.Z_mm = 0;
    const Vec3 p = tool_ball_mm - nominal_tool_ball(geom, out);
    out.X_mm = p.x();
    out.Y_mm = p.y();
    out.Z_mm = p.z();
    return out;
}

BallCentres actual_balls(const MachineGeometry& geom, const ErrorParams& e, const Pose& pose, const Vec3& socket_mm,
                         const ReadingConditions& cond) {
    return {actual_tool_ball(geom, e, pose, cond), actual_table_ball<double>(geom, e, pose, socket_mm)};
}

double predicted_reading(const MachineGeometry& geom, const ErrorParams& e, const Pose& pose, const Vec3& socket_mm,
                         const ReadingConditions& cond) {
    return predicted_reading<double>(geom, e, pose, socket_mm, cond);
}

Vec3 total_position_error(const MachineGeometry& geom, const ErrorParams& e, const Pose& pose, const Vec3& socket_mm,
                          const ReadingConditions& cond) {
    const BallCentres act = actual_balls(geom, e, pose, socket_mm, cond);
    const BallCentres nom = nominal_balls(geom, pose, socket_mm);
    return (act.tool - act.table) - (nom.tool - nom.table);
}

}  // namespace ballbar::analysis
