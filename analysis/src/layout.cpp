// SPDX-License-Identifier: MIT
#include "ballbar/analysis/layout.hpp"

#include <cmath>

#include "ballbar/analysis/ssm.hpp"

namespace ballbar::analysis {
namespace {

/// Unit vectors (x̂, ŷ) spanning the plane normal to the unit `axis`, right-handed with it.
void plane_basis(const Vec3& axis, Vec3& xh, Vec3& yh) {
    Vec3 ref = Vec3::UnitX();
    if (std::abs(axis.dot(ref)) > 0.9) ref = Vec3::UnitY();
    xh = (ref - axis * axis.dot(ref)).normalized();
    yh = axis.cross(xh);
}

}  // namespace

std::string_view to_string(LayoutKind kind) {
    switch (kind) {
        case LayoutKind::CubeCorner:
            return "cube-corner";
        case LayoutKind::FourPoint:
            return "4-point";
        case LayoutKind::SixPoint:
            return "6-point";
    }
    return "?";
}

std::optional<LayoutKind> parse_layout_kind(std::string_view text) {
    for (auto k : {LayoutKind::CubeCorner, LayoutKind::FourPoint, LayoutKind::SixPoint})
        if (text == to_string(k)) return k;
    return std::nullopt;
}

Layout make_layout(LayoutKind kind, const Vec3& socket_mm, double bar_length_mm, const Vec3& approach,
                   double azimuth_rad) {
    if (!socket_mm.allFinite()) throw AnalysisError("layout: socket position is not finite");
    if (!(std::isfinite(bar_length_mm) && bar_length_mm > 0))
        throw AnalysisError("layout: bar length must be a positive number of mm");
    if (!std::isfinite(azimuth_rad)) throw AnalysisError("layout: azimuth is not finite");
    const double an = approach.norm();
    if (!(std::isfinite(an) && an > 0)) throw AnalysisError("layout: approach direction must be a non-zero vector");
    const Vec3 axis = approach / an;
    Vec3 xh, yh;
    plane_basis(axis, xh, yh);

    auto on_cone = [&](double half_angle, double azimuth) -> Vec3 {
        const Vec3 dir =
            axis * std::cos(half_angle) + (xh * std::cos(azimuth) + yh * std::sin(azimuth)) * std::sin(half_angle);
        return socket_mm + bar_length_mm * dir;
    };
    Layout out;
    out.kind = kind;
    out.socket_mm = socket_mm;
    const double third = 2.0 * kPi / 3.0;
    switch (kind) {
        case LayoutKind::CubeCorner:
            for (int k = 0; k < 3; ++k)
                out.points_mm.push_back(on_cone(kCubeCornerHalfAngle_rad, azimuth_rad + k * third));
            break;
        case LayoutKind::FourPoint:
            out.points_mm.push_back(socket_mm + bar_length_mm * axis);
            for (int k = 0; k < 3; ++k)
                out.points_mm.push_back(on_cone(kFourPointHalfAngle_rad, azimuth_rad + k * third));
            break;
        case LayoutKind::SixPoint:
            for (int k = 0; k < 6; ++k)
                out.points_mm.push_back(on_cone(kCubeCornerHalfAngle_rad, azimuth_rad + k * kPi / 3.0));
            break;
    }
    out.condition_number = ssm_condition_number(socket_mm, out.points_mm);
    return out;
}

}  // namespace ballbar::analysis
