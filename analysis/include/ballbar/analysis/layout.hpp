// SPDX-License-Identifier: MIT
// SSM point layouts around one socket: where to put the tool ball so the bar directions are well
// conditioned (seed-math.md, "SSM, Eq. (1)"; docs/analysis.md).
#pragma once

#include <optional>
#include <string_view>
#include <vector>

#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

enum class LayoutKind {
    CubeCorner,  ///< 3 points, mutually orthogonal bar directions: a cone of half-angle 54.7356°
    FourPoint,   ///< 1 point on the approach axis + 3 at 70.5288° (tetrahedron directions)
    SixPoint,    ///< 6 points 60° apart on the 54.7356° cone, solved by least squares
};

std::string_view to_string(LayoutKind kind);
std::optional<LayoutKind> parse_layout_kind(std::string_view text);  ///< "cube-corner", "4-point", "6-point"

/// Cone half-angle (from the approach axis) of the cube-corner and 6-point layouts: acos(1/√3).
constexpr double kCubeCornerHalfAngle_rad = 0.9553166181245092;
/// Half-angle of the three side points of the 4-point layout: acos(1/3) = 70.5288° from the approach
/// axis. With the axis direction reversed these are the four corners of a regular tetrahedron, and a
/// direction's sign does not matter to UᵀU = (4/3)·I: condition number 1.
constexpr double kFourPointHalfAngle_rad = 1.2309594173407747;

struct Layout {
    LayoutKind kind = LayoutKind::CubeCorner;
    Vec3 socket_mm = Vec3::Zero();
    std::vector<Vec3> points_mm;  ///< tool-ball centres, each bar_length from the socket
    double condition_number = 0;  ///< of the unit bar directions (ssm_condition_number)
};

/// The points of a layout. `approach` is the direction from the socket toward the tool side (need not
/// be unit length, e.g. +Z); the cone is built around it. The first side point lies at azimuth
/// `azimuth_rad` measured from the projection of machine +X onto the plane normal to `approach` (+Y if
/// `approach` is parallel to X), turning right-handed about `approach`.
/// Throws AnalysisError for a non-positive bar length or a zero/non-finite approach direction.
Layout make_layout(LayoutKind kind, const Vec3& socket_mm, double bar_length_mm, const Vec3& approach,
                   double azimuth_rad = 0.0);

}  // namespace ballbar::analysis
