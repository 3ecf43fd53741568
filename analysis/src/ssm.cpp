// SPDX-License-Identifier: MIT
#include "ballbar/analysis/ssm.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace ballbar::analysis {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kMinLength_mm = 1e-6;  // a point closer to the socket than this is "at the socket"
/// |e| above this fraction of the shortest bar is not a small error: the readings are inconsistent
/// (or the iteration found the mirror root), and the answer would be noise.
constexpr double kMaxErrorFraction = 0.1;

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

void check_finite(const Vec3& v, const char* what, std::size_t i) {
    if (!v.allFinite()) throw AnalysisError(std::string("SSM: ") + what + " " + std::to_string(i) + " is not finite");
}

/// Condition number of U from its normal matrix N = UᵀU: sqrt(λmax/λmin).
double condition_from_normal(const Mat3& normal) {
    Eigen::SelfAdjointEigenSolver<Mat3> es;
    es.computeDirect(normal, Eigen::EigenvaluesOnly);
    const Vec3 ev = es.eigenvalues();  // ascending
    // Below ~1e-12 of λmax the smallest eigenvalue is rounding noise: the directions are degenerate.
    if (!(ev(0) > ev(2) * 1e-12)) return std::numeric_limits<double>::infinity();
    return std::sqrt(ev(2) / ev(0));
}

Vec3 direction(const Vec3& socket, const Vec3& p, double& length) {
    const Vec3 d = p - socket;
    length = d.norm();
    return d / length;
}

}  // namespace

double ssm_condition_number(const Vec3& socket_mm, std::span<const Vec3> points_mm) {
    if (points_mm.size() < 3)
        throw AnalysisError("SSM needs at least 3 points, got " + std::to_string(points_mm.size()));
    check_finite(socket_mm, "socket", 0);
    Mat3 normal = Mat3::Zero();
    for (std::size_t i = 0; i < points_mm.size(); ++i) {
        check_finite(points_mm[i], "point", i);
        double l = 0;
        const Vec3 u = direction(socket_mm, points_mm[i], l);
        if (!(l >= kMinLength_mm))
            throw AnalysisError("SSM: point " + std::to_string(i) + " coincides with the socket");
        normal.noalias() += u * u.transpose();
    }
    return condition_from_normal(normal);
}

namespace {

/// The per-point quantities, computed once: unit directions u_i, geometric lengths l_i, and effective
/// length errors Δ_i = (nominal_i + Δl_i) − l_i. The relation is u_i·e = Δ_i + (Δ_i² − |e|²)/(2 l_i).
/// MaxRows = 16 keeps them on the stack (no allocation); Eigen::Dynamic serves larger sets.
template <int MaxRows>
struct Rows {
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor, MaxRows, 3> u;
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, MaxRows, 1> l, dl;
};

template <int MaxRows>
SsmResult solve_impl(const Vec3& socket_mm, std::span<const Vec3> points_mm, std::span<const double> delta_l_mm,
                     std::span<const double> nominal_mm, const SsmOptions& options) {
    const std::size_t n = points_mm.size();
    const auto rows_n = static_cast<Eigen::Index>(n);
    Rows<MaxRows> rows;
    rows.u.resize(rows_n, 3);
    rows.l.resize(rows_n);
    rows.dl.resize(rows_n);
    Mat3 normal = Mat3::Zero();
    Vec3 rhs_linear = Vec3::Zero();
    double l_min = std::numeric_limits<double>::infinity();
    double l_max = 0;
    for (std::size_t i = 0; i < n; ++i) {
        check_finite(points_mm[i], "point", i);
        if (!std::isfinite(delta_l_mm[i]))
            throw AnalysisError("SSM: length error " + std::to_string(i) + " is not finite");
        if (!nominal_mm.empty() && !(std::isfinite(nominal_mm[i]) && nominal_mm[i] > 0))
            throw AnalysisError("SSM: nominal length " + std::to_string(i) + " must be a positive number");
        double l = 0;
        const Vec3 u = direction(socket_mm, points_mm[i], l);
        if (!(l >= kMinLength_mm))
            throw AnalysisError("SSM: point " + std::to_string(i) + " coincides with the socket");
        const double dl = (nominal_mm.empty() ? l : nominal_mm[i]) + delta_l_mm[i] - l;
        if (!(l + dl > 0))
            throw AnalysisError("SSM: reading " + std::to_string(i) + " gives a non-positive bar length");
        const auto k = static_cast<Eigen::Index>(i);
        rows.u.row(k) = u.transpose();
        rows.l(k) = l;
        rows.dl(k) = dl;
        normal.noalias() += u * u.transpose();
        rhs_linear += u * dl;
        l_min = std::min(l_min, l);
        l_max = std::max(l_max, l);
    }

    SsmResult res;
    res.n = n;
    res.condition_number = condition_from_normal(normal);
    if (!(res.condition_number <= options.max_condition)) {
        throw AnalysisError("SSM: layout refused, condition number " +
                            (std::isinf(res.condition_number) ? std::string("infinite (degenerate directions)")
                                                              : num(res.condition_number)) +
                            " exceeds the limit " + num(options.max_condition) +
                            ": spread the points (cube corner, 4- or 6-point layout)");
    }
    const Mat3 normal_inv = normal.inverse();
    res.linear_mm = normal_inv * rhs_linear;

    // Exact solution, step 1: fixed-point iteration on the bracket, from the Eq. (1) solution.
    const double tol = 4 * kEps * l_max;
    const double e_max = kMaxErrorFraction * l_min;
    Vec3 e = res.linear_mm;
    int it = 0;
    bool converged = false;
    while (it < options.max_iterations) {
        const double e2 = e.squaredNorm();
        Vec3 rhs = Vec3::Zero();
        for (Eigen::Index i = 0; i < rows_n; ++i) {
            const double dl = rows.dl(i);
            rhs += rows.u.row(i).transpose() * (dl + (dl * dl - e2) / (2 * rows.l(i)));
        }
        const Vec3 next = normal_inv * rhs;
        const double step = (next - e).norm();
        e = next;
        ++it;
        if (!e.allFinite() || e.norm() > e_max) break;
        if (step <= tol) {
            converged = true;
            break;
        }
    }
    // Step 2 (n > 3): Gauss–Newton on the reading residuals r_i = |d_i + e| − (l_i + Δ_i).
    Mat3 jtj = Mat3::Zero();
    Vec3 jtr = Vec3::Zero();
    double ss = 0;
    auto linearise = [&]() {
        jtj.setZero();
        jtr.setZero();
        ss = 0;
        for (Eigen::Index i = 0; i < rows_n; ++i) {
            const Vec3 a = rows.u.row(i).transpose() * rows.l(i) + e;  // actual bar vector
            const double la = a.norm();
            const Vec3 j = a / la;
            const double r = la - (rows.l(i) + rows.dl(i));
            jtj.noalias() += j * j.transpose();
            jtr += j * r;
            ss += r * r;
        }
    };
    if (converged && n > 3) {
        converged = false;
        while (it < options.max_iterations) {
            linearise();
            const Vec3 step = jtj.inverse() * jtr;
            e -= step;
            ++it;
            if (!e.allFinite() || e.norm() > e_max) break;
            if (step.norm() <= tol) {
                converged = true;
                break;
            }
        }
    }
    if (!converged || !e.allFinite() || e.norm() > e_max) {
        throw AnalysisError(
            "SSM: the readings have no solution near the nominal points (length errors too large or "
            "inconsistent for a " +
            num(l_min) + " mm bar)");
    }
    linearise();  // Jacobian at the solution, for the uncertainty and the residual
    res.exact_mm = e;
    res.iterations = it;
    res.cov_mm2 = options.reading_std_mm * options.reading_std_mm * jtj.inverse();
    res.std_mm = res.cov_mm2.diagonal().cwiseSqrt();
    if (n > 3) res.residual_rms_mm = std::sqrt(ss / static_cast<double>(n));
    return res;
}

}  // namespace

SsmResult solve_ssm(const Vec3& socket_mm, std::span<const Vec3> points_mm, std::span<const double> delta_l_mm,
                    std::span<const double> nominal_mm, const SsmOptions& options) {
    const std::size_t n = points_mm.size();
    if (n < 3) throw AnalysisError("SSM needs at least 3 points, got " + std::to_string(n));
    if (delta_l_mm.size() != n)
        throw AnalysisError("SSM: " + std::to_string(delta_l_mm.size()) + " length errors for " + std::to_string(n) +
                            " points");
    if (!nominal_mm.empty() && nominal_mm.size() != n)
        throw AnalysisError("SSM: " + std::to_string(nominal_mm.size()) + " nominal lengths for " + std::to_string(n) +
                            " points");
    if (!(options.max_condition >= 1.0) || !(options.reading_std_mm >= 0.0) || options.max_iterations < 1)
        throw AnalysisError("SSM: invalid options (max_condition >= 1, reading_std_mm >= 0, max_iterations >= 1)");
    check_finite(socket_mm, "socket", 0);
    if (n <= 16) return solve_impl<16>(socket_mm, points_mm, delta_l_mm, nominal_mm, options);
    return solve_impl<Eigen::Dynamic>(socket_mm, points_mm, delta_l_mm, nominal_mm, options);
}

}  // namespace ballbar::analysis
