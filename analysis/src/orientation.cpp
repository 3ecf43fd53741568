// SPDX-License-Identifier: MIT
#include "ballbar/analysis/orientation.hpp"

#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::analysis {
namespace {

constexpr double kTol = kOrientationSingularTol;
constexpr double kMinLever_mm = 1e-6;  // a tool ball closer than 1 nm to its pivot is "at the pivot"

double wrap(double a) {
    return std::remainder(a, 2.0 * kPi);
}

void require_finite(bool ok, const char* what) {
    if (!ok) throw AnalysisError(std::string("orientation: ") + what + " is not finite");
}

void add_reason(std::string& reasons, const char* which, const std::string& why) {
    if (!reasons.empty()) reasons += "; ";
    reasons += which;
    reasons += ": ";
    reasons += why;
}

/// Eq. (6) = Eq. (17): Δβ = −sec β·(x1 − x2 + ΔxV1 − ΔxV2 + z_r sin β)/z_r, singular at cos β = 0.
std::optional<double> eq6_dbeta(double x1, double x2, double dx1, double dx2, double z_r, double beta,
                                std::string& why) {
    const double cb = std::cos(beta);
    if (std::abs(cb) <= kTol) {
        why = "cos β = 0: the tool axis is parallel to X, Eq. (6)/(17) divides by cos β";
        return std::nullopt;
    }
    return -(x1 - x2 + dx1 - dx2 + z_r * std::sin(beta)) / (z_r * cb);
}

/// Model residual of the RRTTT/RTTTR tool ball: Rx(α')·Ry(β')·[0, 0, z_r] − w.
double head_residual(double a, double b, double z_r, const Vec3& w) {
    return (rot_x(a) * rot_y(b) * Vec3(0, 0, z_r) - w).norm();
}

}  // namespace

MeasuredAngles measured_angles(MachineType type, bool rtttr_spindle_test) {
    switch (type) {
        case MachineType::RRTTT:
            return {true, true, false};
        case MachineType::TTTRR:
            return {true, false, true};
        case MachineType::RTTTR:
            return rtttr_spindle_test ? MeasuredAngles{false, true, false} : MeasuredAngles{true, false, false};
    }
    return {};
}

OrientationSolution solve_orientation(const RrtttInput& in) {
    require_finite(in.pivot_mm.allFinite() && std::isfinite(in.z_r_mm) && std::isfinite(in.alpha_rad) &&
                       std::isfinite(in.beta_rad) && in.dV1_mm.allFinite() && in.dV2_mm.allFinite(),
                   "an RRTTT input");
    MachineGeometry g;
    g.type = MachineType::RRTTT;
    g.tool_ball_mm = {0, 0, in.z_r_mm};
    const Pose pose{in.pivot_mm.x(), in.pivot_mm.y(), in.pivot_mm.z(), in.alpha_rad, in.beta_rad, 0};
    const Vec3 p1 = in.pivot_mm, p2 = nominal_tool_ball(g, pose);
    const Vec3 &v1 = in.dV1_mm, &v2 = in.dV2_mm;

    OrientationSolution out;
    out.nominal_after_mm = p2;
    if (std::abs(in.z_r_mm) < kMinLever_mm) {
        out.singular = "z_r = 0: the tool ball is at the pivot, no rotation moves it";
        return out;
    }
    // First order: Eq. (6) and Eq. (7), both correct as printed.
    std::string why;
    if (auto dbeta = eq6_dbeta(p1.x(), p2.x(), v1.x(), v2.x(), in.z_r_mm, in.beta_rad, why)) {
        const double ca = std::cos(in.alpha_rad), sa = std::sin(in.alpha_rad);
        const double dy = -p1.y() + p2.y() - v1.y() + v2.y();
        const double dz = -p1.z() + p2.z() - v1.z() + v2.z();
        const double num = dy * ca + dz * sa;
        const double den = -dz * ca + dy * sa;
        if (std::abs(den) <= kTol * std::abs(in.z_r_mm)) {
            add_reason(out.singular, "first order", "Eq. (7) denominator vanishes (the tool is parallel to X)");
        } else {
            out.first_order = OrientationErrors{num / den, *dbeta, 0};
        }
    } else {
        add_reason(out.singular, "first order", why);
    }
    // Exact: u = (P2 + ΔV2 − P1 − ΔV1)/z_r = Rx(α')·Ry(β')·ẑ.
    const Vec3 w = p2 + v2 - p1 - v1;
    const Vec3 u = w / in.z_r_mm;
    const double h = std::hypot(u.y(), u.z());
    if (h <= kTol * u.norm()) {
        add_reason(out.singular, "exact", "cos β' = 0: the tool lies along the A axis, α is not observable");
    } else {
        const double a = std::atan2(-u.y(), u.z()), b = std::atan2(u.x(), h);
        out.exact = OrientationErrors{wrap(a - in.alpha_rad), wrap(b - in.beta_rad), 0};
        out.exact_iterations = 1;
        out.exact_residual_mm = head_residual(a, b, in.z_r_mm, w);
    }
    return out;
}

OrientationSolution solve_orientation(const RtttrSpindleInput& in) {
    require_finite(in.pivot_mm.allFinite() && std::isfinite(in.z_r_mm) && std::isfinite(in.beta_rad) &&
                       in.dV1_mm.allFinite() && in.dV2_mm.allFinite(),
                   "an RTTTR spindle input");
    MachineGeometry g;
    g.type = MachineType::RTTTR;
    g.tool_ball_mm = {0, 0, in.z_r_mm};
    const Pose pose{in.pivot_mm.x(), in.pivot_mm.y(), in.pivot_mm.z(), 0, in.beta_rad, 0};
    const Vec3 p1 = in.pivot_mm, p2 = nominal_tool_ball(g, pose);
    const Vec3 &v1 = in.dV1_mm, &v2 = in.dV2_mm;

    OrientationSolution out;
    out.nominal_after_mm = p2;
    if (std::abs(in.z_r_mm) < kMinLever_mm) {
        out.singular = "z_r = 0: the tool ball is at the pivot, no rotation moves it";
        return out;
    }
    std::string why;
    if (auto dbeta = eq6_dbeta(p1.x(), p2.x(), v1.x(), v2.x(), in.z_r_mm, in.beta_rad, why))
        out.first_order = OrientationErrors{0, *dbeta, 0};
    else
        add_reason(out.singular, "first order", why);
    // Exact: the x and z rows are z_r·(sin β', cos β').
    const Vec3 w = p2 + v2 - p1 - v1;
    const double b = std::atan2(w.x() / in.z_r_mm, w.z() / in.z_r_mm);
    out.exact = OrientationErrors{0, wrap(b - in.beta_rad), 0};
    out.exact_iterations = 1;
    out.exact_residual_mm = head_residual(0, b, in.z_r_mm, w);
    return out;
}

OrientationSolution solve_orientation(const RtttrTableInput& in) {
    require_finite(in.a_pivot_mm.allFinite() && in.socket_mm.allFinite() && std::isfinite(in.alpha_rad) &&
                       in.dV1_mm.allFinite() && in.dV2_mm.allFinite(),
                   "an RTTTR table input");
    MachineGeometry g;
    g.type = MachineType::RTTTR;
    g.a_pivot_mm = in.a_pivot_mm;
    Pose pose;
    pose.A_rad = in.alpha_rad;
    const Vec3 p1 = in.a_pivot_mm, p2 = nominal_table_ball(g, pose, in.socket_mm);
    const Vec3 &v1 = in.dV1_mm, &v2 = in.dV2_mm;
    const double ytr = in.socket_mm.y(), ztr = in.socket_mm.z();
    const double rho = std::hypot(ytr, ztr);

    OrientationSolution out;
    out.nominal_after_mm = p2;
    if (rho <= kTol * in.socket_mm.norm() || rho == 0.0) {
        out.singular = "the socket is on the A axis (y_tr = z_tr = 0): no A rotation moves it";
        return out;
    }
    // Eq. (18): its denominator z_tr cos α + y_tr sin α is z_t2 − z_t1.
    const double ca = std::cos(in.alpha_rad), sa = std::sin(in.alpha_rad);
    const double den = ztr * ca + ytr * sa;
    if (std::abs(den) <= kTol * rho) {
        add_reason(out.singular, "first order", "z_t2 = z_t1: the socket's lever is horizontal, Eq. (18) divides by 0");
    } else {
        const double dalpha = (p1.y() - p2.y() + v1.y() - v2.y() + ytr * ca - ztr * sa) / den;
        out.first_order = OrientationErrors{dalpha, 0, 0};
    }
    // Exact: (d_y, d_z) = Rx(α')·(y_tr, z_tr).
    const Vec3 d = p2 + v2 - p1 - v1;
    const double a = std::atan2(d.z(), d.y()) - std::atan2(ztr, ytr);
    out.exact = OrientationErrors{wrap(a - in.alpha_rad), 0, 0};
    out.exact_iterations = 1;
    out.exact_residual_mm = (rot_x(a) * in.socket_mm - d).norm();
    return out;
}

OrientationSolution solve_orientation(const TtttrrInput& in) {
    require_finite(in.a_pivot_mm.allFinite() && std::isfinite(in.z_ag_mm) && in.socket_mm.allFinite() &&
                       std::isfinite(in.alpha_rad) && std::isfinite(in.gamma_rad) && in.dV1_mm.allFinite() &&
                       in.dV2_mm.allFinite(),
                   "a TTTRR input");
    MachineGeometry g;
    g.type = MachineType::TTTRR;
    g.a_pivot_mm = in.a_pivot_mm;
    g.c_offset_mm = {0, 0, in.z_ag_mm};
    Pose pose;
    pose.A_rad = in.alpha_rad;
    pose.C_rad = in.gamma_rad;
    const Vec3 p1 = in.a_pivot_mm, p2 = nominal_table_ball(g, pose, in.socket_mm);
    const Vec3 &v1 = in.dV1_mm, &v2 = in.dV2_mm;
    const double xr = in.socket_mm.x(), yr = in.socket_mm.y();
    const double cg = std::cos(in.gamma_rad), sg = std::sin(in.gamma_rad);
    const double ca = std::cos(in.alpha_rad), sa = std::sin(in.alpha_rad);
    const double s0 = yr * cg + xr * sg, c0 = xr * cg - yr * sg;
    const double zz = in.socket_mm.z() + in.z_ag_mm;
    const double r2 = xr * xr + yr * yr, r = std::sqrt(r2);
    const double lever = std::hypot(r, zz);

    OrientationSolution out;
    out.nominal_after_mm = p2;
    if (r <= kTol * lever || r == 0.0) {
        out.singular = "the socket is on the C axis (x_r = y_r = 0): no C rotation moves it";
        return out;
    }
    const bool s0_zero = std::abs(s0) <= kTol * r;
    // First order: Eq. (11) with erratum E2 and Eq. (12) corrected (E1, E3).
    if (s0_zero) {
        add_reason(out.singular, "first order", "S0 = y_r cos γ + x_r sin γ = 0: Eqs. (11)/(12) divide by S0");
    } else if (std::abs(p2.z() - p1.z()) <= kTol * lever) {
        add_reason(out.singular, "first order", "z2 = z1: the denominator of Eq. (12) vanishes");
    } else {
        const double dd = p1.x() - p2.x() + v1.x() - v2.x();
        const double dgamma = (dd + c0) / s0;
        const double q = r2 + dd * c0;
        const double num = (p1.y() - p2.y() + v1.y() - v2.y() - zz * sa) * s0 + ca * q;
        const double den = zz * ca * s0 + sa * q;
        if (std::abs(den) <= kTol * lever * r)
            add_reason(out.singular, "first order", "the denominator of Eq. (12) vanishes on these data");
        else
            out.first_order = OrientationErrors{num / den, 0, dgamma};
    }
    if (s0_zero) {
        add_reason(out.singular, "exact",
                   "S0 = 0: an A and a C rotation move the socket the same way, Δα and Δγ cannot be separated");
        return out;
    }
    // Exact: Gauss–Newton of (α', γ') on Rx(α')·([0,0,z_αγ] + Rz(γ')·p) = P2 + ΔV2 − P1 − ΔV1.
    const Vec3 v = p2 + v2 - p1 - v1;
    double a = in.alpha_rad, c = in.gamma_rad;
    Vec3 res = Vec3::Zero();
    bool converged = false;
    int it = 0;
    double prev_step = std::numeric_limits<double>::infinity();
    for (; it < 30 && !converged; ++it) {
        const double cc = std::cos(c), sc = std::sin(c), cA = std::cos(a), sA = std::sin(a);
        const Vec3 wv(xr * cc - yr * sc, xr * sc + yr * cc, zz);  // [0,0,z_αγ] + Rz(γ')·p
        const Vec3 model(wv.x(), cA * wv.y() - sA * wv.z(), sA * wv.y() + cA * wv.z());
        res = model - v;
        const Vec3 ja(0, -sA * wv.y() - cA * wv.z(), cA * wv.y() - sA * wv.z());
        const Vec3 dw(-wv.y(), wv.x(), 0);
        const Vec3 jc(dw.x(), cA * dw.y(), sA * dw.y());
        Eigen::Matrix2d jtj;
        jtj << ja.dot(ja), ja.dot(jc), ja.dot(jc), jc.dot(jc);
        const Eigen::Vector2d jtr(ja.dot(res), jc.dot(res));
        const Eigen::Vector2d step = jtj.inverse() * jtr;
        if (!step.allFinite()) break;
        a -= step.x();
        c -= step.y();
        // Done at the rounding floor: a tiny step, or a small one that no longer shrinks.
        const double sn = step.norm();
        converged = sn <= 1e-15 || (sn <= 1e-11 && sn > 0.25 * prev_step);
        prev_step = sn;
    }
    if (!converged) {
        add_reason(out.singular, "exact", "the Gauss–Newton fit of (α', γ') did not converge");
        return out;
    }
    out.exact = OrientationErrors{wrap(a - in.alpha_rad), 0, wrap(c - in.gamma_rad)};
    out.exact_iterations = it;
    out.exact_residual_mm = res.norm();
    return out;
}

}  // namespace ballbar::analysis
