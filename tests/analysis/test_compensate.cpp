// SPDX-License-Identifier: MIT
// Compensation: the fast machine model against kinematics.hpp, exact round trips, first-order gain,
// singular poses, and the corrected Lei & Hsu equations.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>

#include "ballbar/analysis/compensate.hpp"
#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/lei_hsu.hpp"

namespace ballbar::analysis {
namespace {

constexpr double kRoundTripMm = 1e-9;
constexpr double kRoundTripRad = 1e-12;

MachineGeometry machine(MachineType type) {
    MachineGeometry g;
    g.type = type;
    switch (type) {
        case MachineType::TTTRR:
            g.a_pivot_mm = Vec3(10, -20, 30);
            g.c_offset_mm = Vec3(0, 0, -100);
            g.tool_ball_mm = Vec3(0, 0, 5);
            break;
        case MachineType::RRTTT:
            g.tool_ball_mm = Vec3(0, 0, -150);
            break;
        case MachineType::RTTTR:
            g.tool_ball_mm = Vec3(0, 0, -150);
            g.a_pivot_mm = Vec3(0, 20, -250);
            break;
    }
    return g;
}

// Seed-like: rotary location errors of tens of µm and tens of µrad, smaller linear-axis errors.
ErrorParams random_errors(MachineType type, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(-1, 1);
    ErrorParams e;
    for (Param p : params_for(type)) {
        switch (param_info(p).unit) {
            case ParamUnit::mm:
                e[p] = 0.05 * u(rng);
                break;
            case ParamUnit::rad:
                e[p] = 1e-4 * u(rng);
                break;
            case ParamUnit::mm_per_mm:
                e[p] = 3e-5 * u(rng);
                break;
            default:
                break;  // growth and bar terms do not move the tool
        }
    }
    return e;
}

Pose random_pose(MachineType type, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> lin(-200, 200), a(0.1, 1.4), c(-3.1, 3.1), b(-1.2, 1.2);
    Pose p;
    p.X_mm = lin(rng);
    p.Y_mm = lin(rng);
    p.Z_mm = lin(rng);
    p.A_rad = (rng() % 2 ? 1 : -1) * a(rng);
    if (type == MachineType::TTTRR)
        p.C_rad = c(rng);
    else
        p.B_rad = b(rng);
    return p;
}

TEST(MachineModel, AgreesWithTheActualKinematics) {
    std::mt19937_64 rng(1);
    for (MachineType type : {MachineType::TTTRR, MachineType::RRTTT, MachineType::RTTTR}) {
        const MachineGeometry g = machine(type);
        for (int trial = 0; trial < 50; ++trial) {
            const ErrorParams e = random_errors(type, rng);
            const Pose pose = random_pose(type, rng);
            const ToolPose tp = MachineModel(g, e).tool_pose(pose);
            // Table frame from table points, tool axis from a tool one unit longer.
            const Vec3 s0 = actual_table_ball<double>(g, e, pose, Vec3::Zero());
            Mat3 rt;
            for (int k = 0; k < 3; ++k) rt.col(k) = actual_table_ball<double>(g, e, pose, Vec3::Unit(k)) - s0;
            const Vec3 b = actual_tool_ball<double>(g, e, pose, {});
            MachineGeometry longer = g;
            longer.tool_ball_mm += Vec3::UnitZ();
            const Vec3 dir = actual_tool_ball<double>(longer, e, pose, {}) - b;
            EXPECT_LT((tp.position_mm - rt.transpose() * (b - s0)).norm(), 1e-10) << to_string(type);
            EXPECT_LT((tp.direction - rt.transpose() * dir).norm(), 1e-12) << to_string(type);
        }
    }
}

TEST(Compensator, ExactRoundTripEveryType) {
    std::mt19937_64 rng(2);
    for (MachineType type : {MachineType::TTTRR, MachineType::RRTTT, MachineType::RTTTR}) {
        const MachineGeometry g = machine(type);
        for (int trial = 0; trial < 100; ++trial) {
            const ErrorParams e = random_errors(type, rng);
            const Compensator comp(g, e);
            const Pose u = random_pose(type, rng);
            const Correction c = comp.exact(u);
            ASSERT_TRUE(c.converged) << to_string(type);
            EXPECT_FALSE(c.singular);
            // Checked independently of the compensator's own bookkeeping.
            const ToolPose want = MachineModel(g, ErrorParams{}).tool_pose(u);
            const ToolPose got = MachineModel(g, e).tool_pose(c.commanded);
            EXPECT_LT((got.position_mm - want.position_mm).norm(), kRoundTripMm) << to_string(type);
            EXPECT_LT((got.direction - want.direction).norm(), kRoundTripRad) << to_string(type);
            EXPECT_LE(c.iterations, 8);
        }
    }
}

TEST(Compensator, FirstOrderLeavesOnlySecondOrderError) {
    std::mt19937_64 rng(3);
    for (MachineType type : {MachineType::TTTRR, MachineType::RRTTT, MachineType::RTTTR}) {
        const MachineGeometry g = machine(type);
        double worst_ratio = 0;
        for (int trial = 0; trial < 100; ++trial) {
            const ErrorParams e = random_errors(type, rng);
            const Compensator comp(g, e);
            const Pose u = random_pose(type, rng);
            const double before = (comp.actual(u).position_mm - comp.nominal(u).position_mm).norm();
            const Correction c = comp.first_order(u);
            const double after = (comp.actual(c.commanded).position_mm - comp.nominal(u).position_mm).norm();
            worst_ratio = std::max(worst_ratio, after / before);
            // And the exact solution differs from the first order by a second-order amount: the rotary
            // correction squared times a lever arm of ~400 mm, plus the error times the model's errors.
            const Correction x = comp.exact(u);
            const double rot = std::max(std::abs(c.du[3]), std::abs(c.du[4]));
            const double second_order = rot * rot * 400.0 + 3e-4 * before;
            for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(c.du[k], x.du[k], 3 * second_order) << to_string(type);
        }
        EXPECT_LT(worst_ratio, 1e-2) << to_string(type);
    }
}

TEST(Compensator, SingularPoseSuppressesTheAxisAndStillMatchesPosition) {
    std::mt19937_64 rng(4);
    // TTTRR at A = 0: C parallel to the tool axis. RRTTT at B = 90°: A parallel to the tool axis.
    struct Case {
        MachineType type;
        Pose pose;
        int suppressed;
    };
    Pose t;
    t.X_mm = 50;
    t.Y_mm = -30;
    t.Z_mm = 80;
    t.C_rad = 0.7;
    Pose r = t;
    r.C_rad = 0;
    r.A_rad = 0.3;
    r.B_rad = kPi / 2;
    for (const Case& k : {Case{MachineType::TTTRR, t, 4}, Case{MachineType::RRTTT, r, 3}}) {
        const MachineGeometry g = machine(k.type);
        const ErrorParams e = random_errors(k.type, rng);
        const Compensator comp(g, e);
        const Correction fo = comp.first_order(k.pose);
        EXPECT_TRUE(fo.singular);
        EXPECT_EQ(fo.suppressed_axis, k.suppressed);
        EXPECT_EQ(fo.du[static_cast<std::size_t>(k.suppressed)], 0.0);
        const Correction ex = comp.exact(k.pose);
        EXPECT_TRUE(ex.converged);
        EXPECT_TRUE(ex.singular);
        EXPECT_EQ(ex.du[static_cast<std::size_t>(k.suppressed)], 0.0);
        EXPECT_LT(ex.position_error_mm, kRoundTripMm);
        const ToolPose got = comp.actual(ex.commanded);
        EXPECT_LT((got.position_mm - comp.nominal(k.pose).position_mm).norm(), kRoundTripMm);
        // The direction is as good as the remaining axis can make it: no worse than uncorrected.
        EXPECT_LE(ex.direction_error_rad,
                  std::acos(std::min(1.0, comp.actual(k.pose).direction.dot(comp.nominal(k.pose).direction))) + 1e-12);
    }
    // Just outside the tolerance the axis is corrected again.
    Pose near = t;
    near.A_rad = 2e-3;
    EXPECT_FALSE(
        Compensator(machine(MachineType::TTTRR), random_errors(MachineType::TTTRR, rng)).first_order(near).singular);
}

// --- Lei & Hsu -----------------------------------------------------------------------------------

Vec5 lh_u(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> lin(-300, 300), a(0.2, 1.5), c(-3, 3);
    Vec5 u;
    u << lin(rng), lin(rng), lin(rng), a(rng), c(rng);
    return u;
}

Vec6 lh_dv(std::mt19937_64& rng, double scale) {
    std::uniform_real_distribution<double> d(-1, 1);
    Vec6 dv;
    dv << 0.05 * d(rng), 0.05 * d(rng), 0.05 * d(rng), 1e-4 * d(rng), 1e-4 * d(rng), 1e-4 * d(rng);
    return dv * scale;
}

TEST(LeiHsu, JacobianMatchesTheForwardKinematics) {
    std::mt19937_64 rng(5);
    const LeiHsuOffsets o{12, -7, 3, 150};
    for (int trial = 0; trial < 20; ++trial) {
        const Vec5 u = lh_u(rng);
        const LeiHsuJacobian j = lei_hsu_jacobian(u);
        for (int k = 0; k < 5; ++k) {
            const double h = k < 3 ? 1e-4 : 1e-7;
            Vec5 up = u, dn = u;
            up[k] += h;
            dn[k] -= h;
            const Vec6 num = (lei_hsu_forward(o, up) - lei_hsu_forward(o, dn)) / (2 * h);
            EXPECT_LT((num - j.col(k)).cwiseAbs().maxCoeff(), 1e-6);
        }
    }
}

TEST(LeiHsu, ClosedFormIsTheLeastSquaresJacobianSolution) {
    std::mt19937_64 rng(6);
    for (int trial = 0; trial < 50; ++trial) {
        const Vec5 u = lh_u(rng);
        const Vec6 dv = lh_dv(rng, 1.0);
        const LeiHsuJacobian j = lei_hsu_jacobian(u);
        // Orientation rows solve for (θa, θc) in the least-squares sense; position rows are then exact.
        const Eigen::Matrix<double, 3, 2> jq = j.bottomRightCorner<3, 2>();
        const Eigen::Vector2d dt = (jq.transpose() * jq).ldlt().solve(jq.transpose() * dv.tail<3>());
        const Eigen::Vector3d dp = j.topLeftCorner<3, 3>().inverse() * (dv.head<3>() - j.topRightCorner<3, 2>() * dt);
        const LeiHsuCorrection c = lei_hsu_first_order(u, dv);
        EXPECT_FALSE(c.singular);
        EXPECT_LT((c.du.head<3>() - dp).cwiseAbs().maxCoeff(), 1e-10);
        EXPECT_LT((c.du.tail<2>() - dt).cwiseAbs().maxCoeff(), 1e-13);
    }
}

TEST(LeiHsu, PrintedEquation19IsWrong) {
    // Eq. (19) as printed, against the corrected compact form, at a generic pose.
    std::mt19937_64 rng(7);
    const Vec5 u = lh_u(rng);
    const Vec6 dv = lh_dv(rng, 1.0);
    const double xm = u[0], zm = u[2], sa = std::sin(u[3]), ca = std::cos(u[3]), sc = std::sin(u[4]),
                 cc = std::cos(u[4]);
    const double printed =
        (-dv[0] * sc * ca * ca - dv[1] * cc * ca * ca + dv[2] * ca * sa + dv[3] * sa * sa * sc * zm +
         dv[3] * cc * sa * ca * ca * xm - dv[4] * sc * sa * ca * ca * xm + dv[4] * cc * sa * sa * zm) /
        ca;
    EXPECT_GT(std::abs(printed - lei_hsu_first_order(u, dv).du[1]), 1e-6);
}

TEST(LeiHsu, FirstOrderAgreesWithExactToSecondOrder) {
    std::mt19937_64 rng(8);
    const LeiHsuOffsets o{12, -7, 3, 150};
    for (int trial = 0; trial < 20; ++trial) {
        const Vec5 u = lh_u(rng);
        const Vec6 dv1 = lh_dv(rng, 1.0);
        double prev = 0;
        for (double h : {1.0, 0.5, 0.25}) {
            const Vec6 dv = dv1 * h;
            const LeiHsuCorrection ex = lei_hsu_exact(o, u, dv);
            ASSERT_TRUE(ex.converged);
            // Exact: the forward kinematics moved by dv (position exactly).
            const Vec6 moved = lei_hsu_forward(o, u + ex.du) - lei_hsu_forward(o, u);
            EXPECT_LT((moved.head<3>() - dv.head<3>()).norm(), 1e-9);
            const double diff = (lei_hsu_first_order(u, dv).du - ex.du).norm();
            if (prev > 0) {
                EXPECT_GT(prev / diff, 3.5);  // halving dv quarters the difference
                EXPECT_LT(prev / diff, 4.5);
            }
            prev = diff;
        }
    }
}

TEST(LeiHsu, SingularCasesFollowSeedMath) {
    std::mt19937_64 rng(9);
    const Vec6 dv = lh_dv(rng, 1.0);
    const double dx = dv[0], dy = dv[1], dz = dv[2], di = dv[3], dj = dv[4], dk = dv[5];
    Vec5 u;
    u << 40, -25, 120, 0.0, 0.8;
    const double sc = std::sin(u[4]), cc = std::cos(u[4]), xm = u[0], ym = u[1], zm = u[2];
    // θa = 0: no C correction.
    LeiHsuCorrection c = lei_hsu_first_order(u, dv);
    EXPECT_TRUE(c.singular);
    EXPECT_EQ(c.du[4], 0.0);
    const double dta = sc * di + cc * dj;
    EXPECT_NEAR(c.du[3], dta, 1e-15);
    EXPECT_NEAR(c.du[0], -cc * dx + sc * dy, 1e-12);
    EXPECT_NEAR(c.du[1], -sc * dx - cc * dy + zm * dta, 1e-12);
    EXPECT_NEAR(c.du[2], dz - ym * dta, 1e-12);
    const LeiHsuCorrection ex = lei_hsu_exact({}, u, dv);
    EXPECT_TRUE(ex.converged && ex.singular);
    EXPECT_EQ(ex.du[4], 0.0);
    const Vec6 moved = lei_hsu_forward({}, u + ex.du) - lei_hsu_forward({}, u);
    EXPECT_LT((moved.head<3>() - dv.head<3>()).norm(), 1e-9);
    // θa = 90°: not singular; the seed-math forms.
    u[3] = kPi / 2;
    c = lei_hsu_first_order(u, dv);
    EXPECT_FALSE(c.singular);
    const double dta90 = -dk, dtc90 = cc * di - sc * dj;
    EXPECT_NEAR(c.du[3], dta90, 1e-15);
    EXPECT_NEAR(c.du[4], dtc90, 1e-15);
    EXPECT_NEAR(c.du[0], -cc * dx + sc * dy + zm * dtc90, 1e-12);
    EXPECT_NEAR(c.du[1], dz + zm * dta90, 1e-12);
    EXPECT_NEAR(c.du[2], sc * dx + cc * dy - ym * dta90 - xm * dtc90, 1e-12);
}

}  // namespace
}  // namespace ballbar::analysis
