// SPDX-License-Identifier: MIT
#include "ballbar/analysis/lei_hsu.hpp"

#include <Eigen/Cholesky>
#include <cmath>

namespace ballbar::analysis {

Vec6 lei_hsu_forward(const LeiHsuOffsets& o, const Vec5& u) {
    const double x = u[0], y = u[1], z = u[2];
    const double sa = std::sin(u[3]), ca = std::cos(u[3]), sc = std::sin(u[4]), cc = std::cos(u[4]);
    Vec6 v;
    v << z * sc * sa - y * sc * ca - x * cc - o.Xw0_mm,  // (10)
        z * cc * sa - y * cc * ca + x * sc - o.Yw0_mm,   // (11)
        z * ca + y * sa - o.Z3_mm - o.Zw0_mm,            // (12)
        sa * sc, sa * cc, ca;                            // (13)–(15)
    return v;
}

LeiHsuJacobian lei_hsu_jacobian(const Vec5& u) {
    const double x = u[0], y = u[1], z = u[2];
    const double sa = std::sin(u[3]), ca = std::cos(u[3]), sc = std::sin(u[4]), cc = std::cos(u[4]);
    LeiHsuJacobian j;
    // columns: x_m, y_m, z_m, θa, θc
    j.row(0) << -cc, -sc * ca, sc * sa, z * sc * ca + y * sc * sa, z * cc * sa - y * cc * ca + x * sc;
    j.row(1) << sc, -cc * ca, cc * sa, z * cc * ca + y * cc * sa, -z * sc * sa + y * sc * ca + x * cc;
    j.row(2) << 0, sa, ca, -z * sa + y * ca, 0;
    j.row(3) << 0, 0, 0, ca * sc, sa * cc;
    j.row(4) << 0, 0, 0, ca * cc, -sa * sc;
    j.row(5) << 0, 0, 0, -sa, 0;
    return j;
}

LeiHsuCorrection lei_hsu_first_order(const Vec5& u, const Vec6& dv, double singular_tolerance) {
    const double xm = u[0], ym = u[1], zm = u[2];
    const double sa = std::sin(u[3]), ca = std::cos(u[3]), sc = std::sin(u[4]), cc = std::cos(u[4]);
    const double dx = dv[0], dy = dv[1], dz = dv[2], di = dv[3], dj = dv[4], dk = dv[5];
    LeiHsuCorrection out;
    out.singular = std::abs(sa) <= singular_tolerance;
    const double dta = ca * (sc * di + cc * dj) - sa * dk;
    const double dtc = out.singular ? 0.0 : (cc * di - sc * dj) / sa;
    out.du[0] = -cc * dx + sc * dy + (sa * zm - ca * ym) * dtc;
    out.du[1] = -sc * ca * dx - cc * ca * dy + sa * dz + zm * dta + ca * xm * dtc;
    out.du[2] = sc * sa * dx + cc * sa * dy + ca * dz - ym * dta - sa * xm * dtc;
    out.du[3] = dta;
    out.du[4] = dtc;
    return out;
}

LeiHsuCorrection lei_hsu_exact(const LeiHsuOffsets& o, const Vec5& u, const Vec6& dv, double singular_tolerance,
                               int max_iterations) {
    const Vec6 target = lei_hsu_forward(o, u) + dv;
    LeiHsuCorrection out;
    out.singular = std::abs(std::sin(u[3])) <= singular_tolerance;
    const int n = out.singular ? 4 : 5;  // θc is the last unknown: held when singular
    out.converged = false;
    for (out.iterations = 0; out.iterations < max_iterations; ++out.iterations) {
        const Vec5 cur = u + out.du;
        const Vec6 r = target - lei_hsu_forward(o, cur);
        const Eigen::MatrixXd j = lei_hsu_jacobian(cur).leftCols(n);
        const Eigen::VectorXd step = (j.transpose() * j).ldlt().solve(j.transpose() * r);
        out.du.head(n) += step;
        if (step.cwiseAbs().maxCoeff() <= 1e-13 * (1.0 + out.du.cwiseAbs().maxCoeff())) {
            out.converged = true;
            ++out.iterations;
            break;
        }
    }
    return out;
}

}  // namespace ballbar::analysis
