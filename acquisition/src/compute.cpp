// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/compute.hpp"

#include <algorithm>
#include <cmath>

#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::acquisition {

using namespace ballbar::analysis;

double dv_sign(const Plan& plan, int test) {
    const TestKind kind = plan.spec.tests[static_cast<std::size_t>(test)].kind;
    if (plan.machine.geometry.type == MachineType::TTTRR || kind == TestKind::TableAlpha) return -1.0;
    return 1.0;
}

LocationResult compute_location(const Plan& plan, int test, int step, std::span<const CapturedPoint> points) {
    if (points.size() != static_cast<std::size_t>(plan.points_per_step))
        throw AnalysisError("test " + std::to_string(test + 1) + " step " + std::to_string(step) + ": " +
                            std::to_string(points.size()) + " points captured, " +
                            std::to_string(plan.points_per_step) + " planned");
    std::vector<Vec3> pts;
    std::vector<double> dl, nominal;
    double noise = 0;
    for (const CapturedPoint& p : points) {
        pts.push_back(p.planned.tool_ball_mm);
        dl.push_back(p.measured_mm - p.planned.nominal_mm);
        nominal.push_back(p.planned.nominal_mm);
        if (p.n > 0) noise = std::max(noise, p.std_mm / std::sqrt(static_cast<double>(p.n)));
    }
    SsmOptions opt;
    opt.max_condition = std::max(plan.spec.max_condition, 1.5);
    opt.reading_std_mm = std::max(noise, 1e-6);
    LocationResult r;
    r.test = test;
    r.step = step;
    r.datum_mm = points.front().planned.datum_mm;
    r.ssm = solve_ssm(r.datum_mm, pts, dl, nominal, opt);
    r.dV_mm = dv_sign(plan, test) * r.ssm.exact_mm;
    return r;
}

namespace {

OrientationSolution solve_test(const Plan& plan, int test, const Vec3& dV1, const Vec3& dV2) {
    const MachineGeometry& g = plan.machine.geometry;
    const TestSpec& t = plan.spec.tests[static_cast<std::size_t>(test)];
    // The pivot of step 2's first point: every point of the step gives the same relation.
    const PlannedPoint& p2 = plan.points[plan.index(test, 2, 0)];
    switch (g.type) {
        case MachineType::RRTTT: {
            RrtttInput in;
            in.pivot_mm = p2.pose.linear_mm();
            in.z_r_mm = g.tool_ball_mm.z();
            in.alpha_rad = t.first_rad;
            in.beta_rad = t.second_rad;
            in.dV1_mm = dV1;
            in.dV2_mm = dV2;
            return solve_orientation(in);
        }
        case MachineType::TTTRR: {
            TtttrrInput in;
            in.a_pivot_mm = g.a_pivot_mm;
            in.z_ag_mm = g.c_offset_mm.z();
            in.socket_mm = t.socket_mm;
            in.alpha_rad = t.first_rad;
            in.gamma_rad = t.second_rad;
            in.dV1_mm = dV1;
            in.dV2_mm = dV2;
            return solve_orientation(in);
        }
        case MachineType::RTTTR:
            if (t.kind == TestKind::SpindleBeta) {
                RtttrSpindleInput in;
                in.pivot_mm = p2.pose.linear_mm();
                in.z_r_mm = g.tool_ball_mm.z();
                in.beta_rad = t.second_rad;
                in.dV1_mm = dV1;
                in.dV2_mm = dV2;
                return solve_orientation(in);
            } else {
                RtttrTableInput in;
                in.a_pivot_mm = g.a_pivot_mm;
                in.socket_mm = t.socket_mm;
                in.alpha_rad = t.first_rad;
                in.dV1_mm = dV1;
                in.dV2_mm = dV2;
                return solve_orientation(in);
            }
    }
    throw AnalysisError("unknown machine type");
}

/// First-order propagation: the Jacobian of the exact solution with respect to the six ΔV components
/// by central differences (a step of one standard uncertainty: the solution is linear over a few µm
/// to ~1e-4), then J·diag(Σ1, Σ2)·Jᵀ.
std::optional<OrientationErrors> propagated_std(const Plan& plan, int test, const Vec3& dV1, const Vec3& dV2,
                                                const Mat3& cov1, const Mat3& cov2) {
    Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
    cov.topLeftCorner<3, 3>() = cov1;
    cov.bottomRightCorner<3, 3>() = cov2;
    if (!cov.allFinite() || !(cov.diagonal().maxCoeff() > 0)) return std::nullopt;
    Eigen::Matrix<double, 3, 6> jac = Eigen::Matrix<double, 3, 6>::Zero();
    for (int i = 0; i < 6; ++i) {
        const double h = std::sqrt(std::max(cov(i, i), 0.0));
        if (!(h > 0)) continue;
        Vec3 up1 = dV1, up2 = dV2, down1 = dV1, down2 = dV2;
        (i < 3 ? up1[i] : up2[i - 3]) += h;
        (i < 3 ? down1[i] : down2[i - 3]) -= h;
        const auto up = solve_test(plan, test, up1, up2).exact;
        const auto down = solve_test(plan, test, down1, down2).exact;
        if (!up || !down) return std::nullopt;  // singular within one uncertainty
        jac.col(i) = Vec3(up->d_alpha_rad - down->d_alpha_rad, up->d_beta_rad - down->d_beta_rad,
                          up->d_gamma_rad - down->d_gamma_rad) /
                     (2 * h);
    }
    const Mat3 out = jac * cov * jac.transpose();
    return OrientationErrors{std::sqrt(std::max(out(0, 0), 0.0)), std::sqrt(std::max(out(1, 1), 0.0)),
                             std::sqrt(std::max(out(2, 2), 0.0))};
}

}  // namespace

TestResult compute_test(const Plan& plan, int test, const Vec3& dV1, const Vec3& dV2, const Mat3& cov1,
                        const Mat3& cov2) {
    TestResult r;
    r.test = test;
    r.kind = plan.spec.tests[static_cast<std::size_t>(test)].kind;
    r.dV1_mm = dV1;
    r.dV2_mm = dV2;
    r.orientation = solve_test(plan, test, dV1, dV2);
    if (r.orientation.exact) r.std_rad = propagated_std(plan, test, dV1, dV2, cov1, cov2);
    return r;
}

std::vector<TrueTest> true_values(const Plan& plan, const ErrorParams& e, const Vec3& socket_offset_mm) {
    const MachineGeometry& g = plan.machine.geometry;
    std::vector<TrueTest> out;
    for (int t = 0; t < plan.test_count(); ++t) {
        TrueTest tt;
        for (int step = 1; step <= 2; ++step) {
            const PlannedPoint& p = plan.points[plan.index(t, step, 0)];
            const BallCentres act = actual_balls(g, e, p.pose, p.socket_mm + socket_offset_mm);
            const BallCentres nom = nominal_balls(g, p.pose, p.socket_mm);
            (step == 1 ? tt.e1_mm : tt.e2_mm) = (act.tool - act.table) - (nom.tool - nom.table);
        }
        const double s = dv_sign(plan, t);
        tt.result = compute_test(plan, t, s * tt.e1_mm, s * tt.e2_mm);
        out.push_back(tt);
    }
    return out;
}

}  // namespace ballbar::acquisition

namespace ballbar::acquisition {

ErrorParams demo_errors(MachineType type) {
    ErrorParams e;
    e[Param::tool_length] = 0.008;
    if (type == MachineType::RRTTT || type == MachineType::TTTRR || type == MachineType::RTTTR) {
        e[Param::Y0A] = 0.015;
        e[Param::Z0A] = -0.012;
        e[Param::B0A] = 25e-6;
        e[Param::C0A] = -35e-6;
        e[Param::A_zero] = deg_to_rad(-0.015);
    }
    if (type == MachineType::RRTTT || type == MachineType::RTTTR) {
        e[Param::X0B] = 0.02;
        e[Param::Z0B] = -0.015;
        e[Param::A0B] = 40e-6;
        e[Param::C0B] = -30e-6;
        e[Param::B_zero] = deg_to_rad(0.02);
    }
    if (type == MachineType::TTTRR) {
        e[Param::X0C] = 0.03;
        e[Param::Y0C] = -0.02;
        e[Param::A0C] = 30e-6;
        e[Param::B0C] = -25e-6;
        e[Param::C_zero] = deg_to_rad(-0.03);
    }
    return e;
}

}  // namespace ballbar::acquisition
