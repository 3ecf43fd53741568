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

/// First-order propagation: each ΔV component moved by ± its standard uncertainty (the solution is
/// linear over a few µm to ~1e-4), the half differences added in quadrature.
std::optional<OrientationErrors> propagated_std(const Plan& plan, int test, const Vec3& dV1, const Vec3& dV2,
                                                const Vec3& std1, const Vec3& std2) {
    double var[3] = {0, 0, 0};
    bool any = false;
    for (int i = 0; i < 6; ++i) {
        const double h = i < 3 ? std1[i] : std2[i - 3];
        if (!(h > 0) || !std::isfinite(h)) continue;
        Vec3 up1 = dV1, up2 = dV2, down1 = dV1, down2 = dV2;
        (i < 3 ? up1[i] : up2[i - 3]) += h;
        (i < 3 ? down1[i] : down2[i - 3]) -= h;
        const auto up = solve_test(plan, test, up1, up2).exact;
        const auto down = solve_test(plan, test, down1, down2).exact;
        if (!up || !down) return std::nullopt;  // singular within one uncertainty
        const double d[3] = {up->d_alpha_rad - down->d_alpha_rad, up->d_beta_rad - down->d_beta_rad,
                             up->d_gamma_rad - down->d_gamma_rad};
        for (int k = 0; k < 3; ++k) var[k] += 0.25 * d[k] * d[k];
        any = true;
    }
    if (!any) return std::nullopt;
    return OrientationErrors{std::sqrt(var[0]), std::sqrt(var[1]), std::sqrt(var[2])};
}

}  // namespace

TestResult compute_test(const Plan& plan, int test, const Vec3& dV1, const Vec3& dV2, const Vec3& std1,
                        const Vec3& std2) {
    TestResult r;
    r.test = test;
    r.kind = plan.spec.tests[static_cast<std::size_t>(test)].kind;
    r.dV1_mm = dV1;
    r.dV2_mm = dV2;
    r.orientation = solve_test(plan, test, dV1, dV2);
    if (r.orientation.exact) r.std_rad = propagated_std(plan, test, dV1, dV2, std1, std2);
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
