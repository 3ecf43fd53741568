// SPDX-License-Identifier: MIT
// Value types shared by every layer: machine types, geometry, commanded poses.
//
// Units: lengths in millimetres, angles in radians, times in seconds, temperatures in °C.
// Conventions are the seeds' (see docs/kinematics.md and docs/formats/readings.md): rotations are
// right-handed about +X/+Y/+Z, applied in the order written.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace ballbar::analysis {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

/// The three five-axis configurations of the seed paper.
enum class MachineType {
    RRTTT,  ///< spindle head tilts: A about X carries B about Y; the table ball (socket) is fixed
    TTTRR,  ///< table tilts: A about X carries C about Z; the tool ball rides on the linear axes
    RTTTR,  ///< head B about Y, table A about X
};

std::string_view to_string(MachineType type);
std::optional<MachineType> parse_machine_type(std::string_view text);

/// Which rotary axis letter a machine type uses, in the order of the readings file's columns.
struct RotaryAxes {
    char first;   ///< 'A' for all three types
    char second;  ///< 'B' (RRTTT), 'C' (TTTRR), 'B' (RTTTR)
};
RotaryAxes rotary_axes(MachineType type);

/// Nominal geometry of a machine, with the keys of the `machine` header of `ballbar-readings/1`.
struct MachineGeometry {
    MachineType type = MachineType::TTTRR;
    std::string name;
    /// RRTTT/RTTTR: tool-ball centre from the spindle pivot, in the head frame at zero angles.
    /// TTTRR: tool-ball centre from the commanded point (X,Y,Z).
    Vec3 tool_ball_mm = Vec3::Zero();
    /// TTTRR/RTTTR: a point on the table's A axis (machine frame).
    Vec3 a_pivot_mm = Vec3::Zero();
    /// TTTRR: origin of the C frame in the A frame (the seeds' [0, 0, z_αγ]).
    Vec3 c_offset_mm = Vec3::Zero();
};

/// Commanded axis positions. Only the type's two rotary axes are read; the others are ignored.
struct Pose {
    double X_mm = 0, Y_mm = 0, Z_mm = 0;
    double A_rad = 0, B_rad = 0, C_rad = 0;

    Vec3 linear_mm() const { return {X_mm, Y_mm, Z_mm}; }
};

/// The span of a set of poses, axis by axis (X, Y, Z in mm; A, B, C in radians): where a model was
/// measured, where a program goes. `line` holds, for each axis, the NC line of the pose that set its min
/// and max (0 when not from a program).
struct PoseRange {
    static constexpr int kAxes = 6;
    std::array<double, kAxes> min{}, max{};
    std::array<int, kAxes> min_line{}, max_line{};
    bool empty = true;
    static std::array<double, kAxes> values(const Pose& p) {
        return {p.X_mm, p.Y_mm, p.Z_mm, p.A_rad, p.B_rad, p.C_rad};
    }
    void add(const Pose& p, int line = 0) {
        const auto v = values(p);
        for (int i = 0; i < kAxes; ++i) {
            const auto k = static_cast<std::size_t>(i);
            if (empty || v[k] < min[k]) min[k] = v[k], min_line[k] = line;
            if (empty || v[k] > max[k]) max[k] = v[k], max_line[k] = line;
        }
        empty = false;
    }
};

/// Degrees at the operator's screen, radians inside.
constexpr double kPi = 3.141592653589793238462643383279502884;
constexpr double deg_to_rad(double deg) {
    return deg * kPi / 180.0;
}
constexpr double rad_to_deg(double rad) {
    return rad * 180.0 / kPi;
}
constexpr double rad_to_arcsec(double rad) {
    return rad * 180.0 / kPi * 3600.0;
}

/// Thrown by analysis functions for inputs they cannot answer (degenerate layouts, singular
/// configurations the caller asked to be strict about, inconsistent sizes). The message names the
/// problem in the operator's terms.
class AnalysisError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

}  // namespace ballbar::analysis
