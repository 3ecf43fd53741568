// SPDX-License-Identifier: MIT
// Orientation errors: the seed's Table 1 at full precision, round trips through the actual kinematics
// for all three machine types, and the documented singular configurations.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/orientation.hpp"

namespace ba = ballbar::analysis;
using ba::Vec3;

namespace {

constexpr double kRelTol = 1e-10;        // Table 1 golden values, relative
constexpr double kExactTol_rad = 1e-12;  // exact inversion on model-consistent data

nlohmann::json load_table1_orientation() {
    std::ifstream in(std::string(BALLBAR_TEST_DATA_DIR) + "/table1.json");
    EXPECT_TRUE(in.good()) << "tests/data/table1.json missing";
    return nlohmann::json::parse(in);
}

void expect_rel(double got, double want, const std::string& what) {
    EXPECT_NEAR(got, want, kRelTol * std::abs(want) + 1e-16) << what;
}

Vec3 v3(const nlohmann::json& c, const char* x, const char* y, const char* z) {
    return {c[x].get<double>(), c[y].get<double>(), c[z].get<double>()};
}

void expect_all_finite(const ba::OrientationSolution& s) {
    for (const auto* e : {&s.first_order, &s.exact}) {
        if (!e->has_value()) continue;
        EXPECT_TRUE(std::isfinite((*e)->d_alpha_rad) && std::isfinite((*e)->d_beta_rad) &&
                    std::isfinite((*e)->d_gamma_rad));
    }
    EXPECT_TRUE(s.nominal_after_mm.allFinite());
}

}  // namespace

TEST(Orientation, EachTestDeterminesTheAnglesOfItsType) {
    const auto is = [](ba::MeasuredAngles m, bool a, bool b, bool g) {
        return m.alpha == a && m.beta == b && m.gamma == g;
    };
    EXPECT_TRUE(is(ba::measured_angles(ba::MachineType::RRTTT, false), true, true, false));
    EXPECT_TRUE(is(ba::measured_angles(ba::MachineType::TTTRR, false), true, false, true));
    EXPECT_TRUE(is(ba::measured_angles(ba::MachineType::RTTTR, true), false, true, false));   // spindle: B
    EXPECT_TRUE(is(ba::measured_angles(ba::MachineType::RTTTR, false), true, false, false));  // table (or both): A
}

TEST(Orientation, Table1AllFiveCasesFirstOrderAndExact) {
    const auto table = load_table1_orientation();
    ASSERT_EQ(table.size(), 5u);
    for (const auto& c : table) {
        const std::string name = "case " + std::to_string(c["case"].get<int>());
        ba::RrtttInput in;
        in.pivot_mm = v3(c, "x1", "y1", "z1");
        in.z_r_mm = c["zr"];
        in.alpha_rad = c["alpha_rad"];
        in.beta_rad = c["beta_rad"];
        in.dV1_mm = v3(c, "dxV1", "dyV1", "dzV1");
        in.dV2_mm = v3(c, "dxV2", "dyV2", "dzV2");
        const auto s = ba::solve_orientation(in);
        ASSERT_TRUE(s.first_order) << name << ": " << s.singular;
        ASSERT_TRUE(s.exact) << name << ": " << s.singular;
        EXPECT_TRUE(s.singular.empty());
        expect_rel(s.nominal_after_mm.x(), c["x2"], name + " x2");
        expect_rel(s.nominal_after_mm.y(), c["y2"], name + " y2");
        expect_rel(s.nominal_after_mm.z(), c["z2"], name + " z2");
        expect_rel(s.first_order->d_beta_rad, c["eq6_dbeta_rad"], name + " Eq. (6)");
        expect_rel(s.first_order->d_alpha_rad, c["eq7_dalpha_rad"], name + " Eq. (7)");
        expect_rel(s.exact->d_alpha_rad, c["exact_dalpha_rad"], name + " exact Δα");
        expect_rel(s.exact->d_beta_rad, c["exact_dbeta_rad"], name + " exact Δβ");
        // The exact inversion returns the assumed errors, and Eq. (7) is tan Δα.
        EXPECT_NEAR(s.exact->d_alpha_rad, c["dalpha_rad"].get<double>(), kExactTol_rad) << name;
        EXPECT_NEAR(s.exact->d_beta_rad, c["dbeta_rad"].get<double>(), kExactTol_rad) << name;
        EXPECT_NEAR(std::atan(s.first_order->d_alpha_rad), c["dalpha_rad"].get<double>(), kExactTol_rad) << name;
        EXPECT_LT(s.exact_residual_mm, 1e-12) << name;
    }
}

TEST(Orientation, Table1PrintedCalculatedErrorsAtFiveDigits) {
    // The seed prints Δβ' = 0°, 0.07995°, 0.09985°, 0.08992°, 0.09985°: Eq. (6)'s second-order bias.
    const auto table = load_table1_orientation();
    const double printed_dbeta_deg[5] = {0, 0.07995, 0.09985, 0.08992, 0.09985};
    const double printed_dalpha_deg[5] = {0.1, 0, 0.12, 0.15, 0.1};
    for (std::size_t i = 0; i < 5; ++i) {
        const auto& c = table[i];
        ba::RrtttInput in{
            v3(c, "x1", "y1", "z1"),      c["zr"], c["alpha_rad"], c["beta_rad"], v3(c, "dxV1", "dyV1", "dzV1"),
            v3(c, "dxV2", "dyV2", "dzV2")};
        const auto s = ba::solve_orientation(in);
        ASSERT_TRUE(s.first_order);
        EXPECT_NEAR(ba::rad_to_deg(s.first_order->d_beta_rad), printed_dbeta_deg[i], 0.5e-5) << "case " << i + 1;
        EXPECT_NEAR(ba::rad_to_deg(s.first_order->d_alpha_rad), printed_dalpha_deg[i], 0.5e-5) << "case " << i + 1;
    }
}

// ---- Round trips through the lead's actual kinematics: A_zero/B_zero/C_zero are the seed's angle
// errors, ΔV1 a translation of the moving part. Exact must recover them; first order to second order.

namespace {

struct Draw {
    std::mt19937_64 rng{2024};
    double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
    Vec3 vec(double r) { return {uniform(-r, r), uniform(-r, r), uniform(-r, r)}; }
};

/// The first-order formulas drop second-order terms in the angle errors (the ΔV terms cancel exactly
/// on model data): bound their error by `factor`·(Σ|Δ|)². The factors are geometric (tan β for Eq. 6,
/// cot ψ and 1/S0 for Eqs. 11/12) and hold over the sampled domains; a first-order mistake such as the
/// misprinted Eq. (12) (ΔxV1 dropped, ΔV1 up to 0.5 mm here) exceeds them by orders of magnitude.
double second_order_bound(double sum_abs_angles, double factor) {
    return factor * sum_abs_angles * sum_abs_angles + 1e-13;
}

}  // namespace

TEST(Orientation, RrtttRoundTripOverRandomPoses) {
    Draw d;
    int first_order_checked = 0;
    for (int i = 0; i < 300; ++i) {
        ba::MachineGeometry g;
        g.type = ba::MachineType::RRTTT;
        const double zr = d.uniform(-300, -100);
        g.tool_ball_mm = {0, 0, zr};
        const ba::Pose pose{d.uniform(-300, 300), d.uniform(-300, 300), d.uniform(100, 600),
                            d.uniform(-1.4, 1.4), d.uniform(-1.4, 1.4), 0};
        const double da = d.uniform(-0.004, 0.004), db = d.uniform(-0.004, 0.004);
        const Vec3 dv1 = d.vec(0.5);
        ba::ErrorParams e;
        e[ba::Param::A_zero] = da;
        e[ba::Param::B_zero] = db;
        ba::Pose moved = pose;
        moved.X_mm += dv1.x();
        moved.Y_mm += dv1.y();
        moved.Z_mm += dv1.z();
        const Vec3 actual = ba::actual_tool_ball(g, e, moved, ba::ReadingConditions{});
        const Vec3 nominal = ba::nominal_tool_ball(g, pose);

        const auto s =
            ba::solve_orientation(ba::RrtttInput{pose.linear_mm(), zr, pose.A_rad, pose.B_rad, dv1, actual - nominal});
        expect_all_finite(s);
        ASSERT_TRUE(s.exact) << s.singular;
        EXPECT_NEAR(s.exact->d_alpha_rad, da, kExactTol_rad);
        EXPECT_NEAR(s.exact->d_beta_rad, db, kExactTol_rad);
        EXPECT_LT(s.exact_residual_mm, 1e-9);
        EXPECT_LT((s.nominal_after_mm - nominal).norm(), 1e-12);
        if (s.first_order) {
            ++first_order_checked;
            // Eq. (6)'s bias is (Δβ²/2)·tan β; Eq. (7) is tan Δα.
            const double bound =
                second_order_bound(std::abs(da) + std::abs(db), 0.5 * std::abs(std::tan(pose.B_rad)) + 1.0);
            EXPECT_NEAR(s.first_order->d_alpha_rad, da, bound);
            EXPECT_NEAR(s.first_order->d_beta_rad, db, bound);
        }
    }
    EXPECT_EQ(first_order_checked, 300);
}

TEST(Orientation, TttrrRoundTripOverRandomPoses) {
    Draw d;
    int first_order_checked = 0, exact_checked = 0;
    for (int i = 0; i < 300; ++i) {
        const Vec3 a_pivot = d.vec(200);
        const double zag = d.uniform(-150, 0);
        const Vec3 socket{d.uniform(-150, 150), d.uniform(-150, 150), d.uniform(-100, 100)};
        const double alpha = d.uniform(-1.5, 1.5), gamma = d.uniform(-3.1, 3.1);
        const double da = d.uniform(-0.004, 0.004), dg = d.uniform(-0.004, 0.004);
        const Vec3 dv1 = d.vec(0.5);

        ba::MachineGeometry nom;
        nom.type = ba::MachineType::TTTRR;
        nom.a_pivot_mm = a_pivot;
        nom.c_offset_mm = {0, 0, zag};
        ba::MachineGeometry act = nom;
        act.a_pivot_mm += dv1;  // the table frame is translated by ΔV1
        ba::ErrorParams e;
        e[ba::Param::A_zero] = da;
        e[ba::Param::C_zero] = dg;
        ba::Pose pose;
        pose.A_rad = alpha;
        pose.C_rad = gamma;
        const Vec3 actual = ba::actual_table_ball<double>(act, e, pose, socket);
        const Vec3 nominal = ba::nominal_table_ball(nom, pose, socket);

        const auto s =
            ba::solve_orientation(ba::TtttrrInput{a_pivot, zag, socket, alpha, gamma, dv1, actual - nominal});
        expect_all_finite(s);
        EXPECT_LT((s.nominal_after_mm - nominal).norm(), 1e-12);
        if (s.exact) {
            ++exact_checked;
            EXPECT_NEAR(s.exact->d_alpha_rad, da, 1e-11) << "iterations " << s.exact_iterations;
            EXPECT_NEAR(s.exact->d_gamma_rad, dg, 1e-11);
            EXPECT_LT(s.exact_residual_mm, 1e-9);
            // Quadratic convergence away from S0 = 0 (near it the two rotations nearly coincide).
            const double s0r =
                (socket.y() * std::cos(gamma) + socket.x() * std::sin(gamma)) / std::hypot(socket.x(), socket.y());
            if (std::abs(s0r) > 0.1) {
                EXPECT_LE(s.exact_iterations, 6) << "S0/r " << s0r;
            }
        }
        // First order only where the configuration is well away from its singularities.
        const double r = std::hypot(socket.x(), socket.y());
        const double s0 = socket.y() * std::cos(gamma) + socket.x() * std::sin(gamma);
        const double dz = nominal.z() - a_pivot.z();
        if (s.first_order && std::abs(s0) > 0.3 * r && std::abs(dz) > 0.3 * r) {
            ++first_order_checked;
            const double bound = second_order_bound(std::abs(da) + std::abs(dg), 6.0);
            EXPECT_NEAR(s.first_order->d_alpha_rad, da, bound);
            EXPECT_NEAR(s.first_order->d_gamma_rad, dg, bound);
        }
    }
    EXPECT_GE(exact_checked, 295);
    EXPECT_GE(first_order_checked, 60);
}

TEST(Orientation, RtttrRoundTripSpindleAndTable) {
    Draw d;
    for (int i = 0; i < 300; ++i) {
        // Spindle set-up: Δβ.
        ba::MachineGeometry g;
        g.type = ba::MachineType::RTTTR;
        const double zr = d.uniform(-300, -100);
        g.tool_ball_mm = {0, 0, zr};
        const ba::Pose pose{
            d.uniform(-300, 300), d.uniform(-300, 300), d.uniform(100, 600), 0, d.uniform(-1.4, 1.4), 0};
        const double db = d.uniform(-0.004, 0.004);
        const Vec3 dv1 = d.vec(0.5);
        ba::ErrorParams e;
        e[ba::Param::B_zero] = db;
        ba::Pose moved = pose;
        moved.X_mm += dv1.x();
        moved.Y_mm += dv1.y();
        moved.Z_mm += dv1.z();
        const Vec3 b_act = ba::actual_tool_ball(g, e, moved, ba::ReadingConditions{});
        const Vec3 b_nom = ba::nominal_tool_ball(g, pose);
        const auto s =
            ba::solve_orientation(ba::RtttrSpindleInput{pose.linear_mm(), zr, pose.B_rad, dv1, b_act - b_nom});
        expect_all_finite(s);
        ASSERT_TRUE(s.exact && s.first_order) << s.singular;
        EXPECT_NEAR(s.exact->d_beta_rad, db, kExactTol_rad);
        EXPECT_NEAR(s.first_order->d_beta_rad, db,
                    second_order_bound(std::abs(db), 0.5 * std::abs(std::tan(pose.B_rad)) + 0.5));

        // Table set-up: Δα.
        ba::MachineGeometry t;
        t.type = ba::MachineType::RTTTR;
        t.a_pivot_mm = d.vec(200);
        ba::MachineGeometry t_act = t;
        t_act.a_pivot_mm += dv1;
        const Vec3 socket{d.uniform(-150, 150), d.uniform(-150, 150), d.uniform(-150, 150)};
        ba::Pose tp;
        tp.A_rad = d.uniform(-1.5, 1.5);
        const double da = d.uniform(-0.004, 0.004);
        ba::ErrorParams et;
        et[ba::Param::A_zero] = da;
        const Vec3 s_act = ba::actual_table_ball<double>(t_act, et, tp, socket);
        const Vec3 s_nom = ba::nominal_table_ball(t, tp, socket);
        const auto st = ba::solve_orientation(ba::RtttrTableInput{t.a_pivot_mm, socket, tp.A_rad, dv1, s_act - s_nom});
        expect_all_finite(st);
        ASSERT_TRUE(st.exact) << st.singular;
        EXPECT_NEAR(st.exact->d_alpha_rad, da, kExactTol_rad);
        const double rho = std::hypot(socket.y(), socket.z());
        if (st.first_order && std::abs(s_nom.z() - t.a_pivot_mm.z()) > 0.3 * rho) {
            const double dz = std::abs(s_nom.z() - t.a_pivot_mm.z());
            EXPECT_NEAR(st.first_order->d_alpha_rad, da, second_order_bound(std::abs(da), 0.5 * rho / dz + 0.5));
        }
    }
}

// ---- Singular configurations: reported with a reason, never NaN or a huge number.

TEST(OrientationSingular, RrtttCosBetaZero) {
    ba::RrtttInput in{{-50, -15, 500}, -250, 0.3, ba::kPi / 2, Vec3::Zero(), Vec3::Zero()};
    const auto s = ba::solve_orientation(in);
    expect_all_finite(s);
    EXPECT_FALSE(s.first_order);
    EXPECT_FALSE(s.exact);  // the tool lies along the A axis: α is not observable
    EXPECT_NE(s.singular.find("cos β = 0"), std::string::npos) << s.singular;
    EXPECT_NE(s.singular.find("exact"), std::string::npos) << s.singular;
}

TEST(OrientationSingular, RrtttToolBallAtPivot) {
    const auto s = ba::solve_orientation(ba::RrtttInput{{0, 0, 0}, 0.0, 0.2, 0.3, Vec3::Zero(), Vec3::Zero()});
    EXPECT_FALSE(s.first_order);
    EXPECT_FALSE(s.exact);
    EXPECT_NE(s.singular.find("z_r = 0"), std::string::npos) << s.singular;
}

TEST(OrientationSingular, TttrrS0Zero) {
    // Socket with y_r = 0 at γ = 0: S0 = 0, a true singularity of both forms.
    ba::TtttrrInput in{{0, 0, 0}, -100, {80, 0, -50}, 0.2, 0.0, Vec3::Zero(), {0.01, 0.02, 0.0}};
    const auto s = ba::solve_orientation(in);
    expect_all_finite(s);
    EXPECT_FALSE(s.first_order);
    EXPECT_FALSE(s.exact);
    EXPECT_NE(s.singular.find("S0 = 0"), std::string::npos) << s.singular;
}

TEST(OrientationSingular, TttrrZ2EqualsZ1FirstOrderOnlyExactStillAnswers) {
    // z2 − z1 = sin α·S0 + cos α·Z = 0 at α = atan2(−Z, S0): Eq. (12) is singular, the fit is not.
    const Vec3 socket{30, 40, -50};
    const double zag = -100, gamma = 0.4;
    const double s0 = socket.y() * std::cos(gamma) + socket.x() * std::sin(gamma);
    const double alpha = std::atan2(-(socket.z() + zag), s0);
    ba::MachineGeometry g;
    g.type = ba::MachineType::TTTRR;
    g.c_offset_mm = {0, 0, zag};
    ba::Pose pose;
    pose.A_rad = alpha;
    pose.C_rad = gamma;
    ba::ErrorParams e;
    e[ba::Param::A_zero] = 0.002;
    e[ba::Param::C_zero] = -0.003;
    const Vec3 dv2 = ba::actual_table_ball<double>(g, e, pose, socket) - ba::nominal_table_ball(g, pose, socket);
    const auto s = ba::solve_orientation(ba::TtttrrInput{{0, 0, 0}, zag, socket, alpha, gamma, Vec3::Zero(), dv2});
    expect_all_finite(s);
    EXPECT_NEAR(s.nominal_after_mm.z(), 0.0, 1e-12);
    EXPECT_FALSE(s.first_order);
    EXPECT_NE(s.singular.find("z2 = z1"), std::string::npos) << s.singular;
    ASSERT_TRUE(s.exact);
    EXPECT_NEAR(s.exact->d_alpha_rad, 0.002, 1e-11);
    EXPECT_NEAR(s.exact->d_gamma_rad, -0.003, 1e-11);
}

TEST(OrientationSingular, TttrrSocketOnTheCAxis) {
    const auto s =
        ba::solve_orientation(ba::TtttrrInput{{0, 0, 0}, -100, {0, 0, -50}, 0.2, 0.5, Vec3::Zero(), Vec3::Zero()});
    EXPECT_FALSE(s.first_order);
    EXPECT_FALSE(s.exact);
    EXPECT_NE(s.singular.find("C axis"), std::string::npos) << s.singular;
}

TEST(OrientationSingular, RtttrSpindleCosBetaZeroExactStillAnswers) {
    ba::MachineGeometry g;
    g.type = ba::MachineType::RTTTR;
    g.tool_ball_mm = {0, 0, -200};
    ba::Pose pose{10, 20, 300, 0, ba::kPi / 2, 0};
    ba::ErrorParams e;
    e[ba::Param::B_zero] = 0.001;
    const Vec3 dv2 = ba::actual_tool_ball(g, e, pose, ba::ReadingConditions{}) - ba::nominal_tool_ball(g, pose);
    const auto s = ba::solve_orientation(ba::RtttrSpindleInput{pose.linear_mm(), -200, pose.B_rad, Vec3::Zero(), dv2});
    expect_all_finite(s);
    EXPECT_FALSE(s.first_order);
    EXPECT_NE(s.singular.find("cos β = 0"), std::string::npos) << s.singular;
    ASSERT_TRUE(s.exact);
    EXPECT_NEAR(s.exact->d_beta_rad, 0.001, kExactTol_rad);
}

TEST(OrientationSingular, RtttrTableZt2EqualsZt1) {
    // z_t2 − z_t1 = z_tr cos α + y_tr sin α = 0 at α = atan2(−z_tr, y_tr).
    const Vec3 socket{20, 60, 80};
    const double alpha = std::atan2(-socket.z(), socket.y());
    ba::MachineGeometry g;
    g.type = ba::MachineType::RTTTR;
    ba::Pose pose;
    pose.A_rad = alpha;
    ba::ErrorParams e;
    e[ba::Param::A_zero] = -0.0025;
    const Vec3 dv2 = ba::actual_table_ball<double>(g, e, pose, socket) - ba::nominal_table_ball(g, pose, socket);
    const auto s = ba::solve_orientation(ba::RtttrTableInput{{0, 0, 0}, socket, alpha, Vec3::Zero(), dv2});
    expect_all_finite(s);
    EXPECT_FALSE(s.first_order);
    EXPECT_NE(s.singular.find("z_t2 = z_t1"), std::string::npos) << s.singular;
    ASSERT_TRUE(s.exact);
    EXPECT_NEAR(s.exact->d_alpha_rad, -0.0025, kExactTol_rad);
}

TEST(OrientationSingular, RtttrTableSocketOnTheAAxis) {
    const auto s = ba::solve_orientation(ba::RtttrTableInput{{0, 0, 0}, {50, 0, 0}, 0.3, Vec3::Zero(), Vec3::Zero()});
    EXPECT_FALSE(s.first_order);
    EXPECT_FALSE(s.exact);
    EXPECT_NE(s.singular.find("A axis"), std::string::npos) << s.singular;
}

TEST(OrientationSingular, NonFiniteInputIsRefused) {
    ba::RrtttInput in{{0, 0, 0}, -250, std::nan(""), 0.1, Vec3::Zero(), Vec3::Zero()};
    EXPECT_THROW(ba::solve_orientation(in), ba::AnalysisError);
}
