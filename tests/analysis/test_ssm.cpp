// SPDX-License-Identifier: MIT
// SSM: exact recovery from synthetic readings, the bound on Eq. (1)'s error, conditioning, refusals,
// and the propagated uncertainty against Monte Carlo.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <vector>

#include "ballbar/analysis/layout.hpp"
#include "ballbar/analysis/ssm.hpp"

namespace ba = ballbar::analysis;
using ba::Vec3;

namespace {

constexpr double kRecoverTol_mm = 1e-9;

/// Exact readings: measured minus nominal length for a common error e.
std::vector<double> readings(const Vec3& socket, const std::vector<Vec3>& pts, const Vec3& e) {
    std::vector<double> dl;
    for (const auto& p : pts) dl.push_back((p + e - socket).norm() - (p - socket).norm());
    return dl;
}

/// Three points 120° apart on a cone of half-angle θ around +Z.
std::vector<Vec3> cone3(const Vec3& socket, double length, double theta) {
    std::vector<Vec3> pts;
    for (int k = 0; k < 3; ++k) {
        const double az = 2.0 * ba::kPi / 3.0 * k;
        pts.push_back(socket +
                      length * Vec3(std::sin(theta) * std::cos(az), std::sin(theta) * std::sin(az), std::cos(theta)));
    }
    return pts;
}

double smallest_singular_value(const Vec3& socket, const std::vector<Vec3>& pts) {
    ba::Mat3 n = ba::Mat3::Zero();
    for (const auto& p : pts) {
        const Vec3 u = (p - socket).normalized();
        n += u * u.transpose();
    }
    Eigen::SelfAdjointEigenSolver<ba::Mat3> es(n);
    return std::sqrt(es.eigenvalues()(0));
}

const ba::LayoutKind kAllKinds[] = {ba::LayoutKind::CubeCorner, ba::LayoutKind::FourPoint, ba::LayoutKind::SixPoint};

}  // namespace

// ---- Layouts

TEST(SsmLayout, ConditionNumbersAndGeometry) {
    const Vec3 socket{120, -40, 15};
    for (const Vec3& approach : {Vec3(0, 0, 1), Vec3(-1, 0, 0), Vec3(0.3, -0.5, 0.8)}) {
        for (auto kind : kAllKinds) {
            const auto lay = ba::make_layout(kind, socket, 150.0, approach * 3.0);
            const std::size_t n = kind == ba::LayoutKind::CubeCorner ? 3u : kind == ba::LayoutKind::FourPoint ? 4u : 6u;
            ASSERT_EQ(lay.points_mm.size(), n) << ba::to_string(kind);
            EXPECT_NEAR(lay.condition_number, 1.0, 1e-12) << ba::to_string(kind);
            for (const auto& p : lay.points_mm) {
                EXPECT_NEAR((p - socket).norm(), 150.0, 1e-12);
                EXPECT_GT((p - socket).dot(approach), 0.0) << "every point on the tool side";
            }
        }
        // Cube corner: mutually orthogonal bar directions at 54.7356° from the approach axis.
        const auto cc = ba::make_layout(ba::LayoutKind::CubeCorner, socket, 100.0, approach);
        const Vec3 ax = approach.normalized();
        for (int i = 0; i < 3; ++i) {
            const Vec3 ui = (cc.points_mm[i] - socket).normalized();
            EXPECT_NEAR(std::acos(ui.dot(ax)), ba::deg_to_rad(54.7356103), 1e-9);
            for (int j = i + 1; j < 3; ++j) EXPECT_NEAR(ui.dot((cc.points_mm[j] - socket).normalized()), 0.0, 1e-12);
        }
        // 4-point: one on the axis, three at 70.5288°.
        const auto f = ba::make_layout(ba::LayoutKind::FourPoint, socket, 100.0, approach);
        EXPECT_LT(((f.points_mm[0] - socket).normalized() - ax).norm(), 1e-12);
        for (int i = 1; i < 4; ++i)
            EXPECT_NEAR(std::acos((f.points_mm[i] - socket).normalized().dot(ax)), ba::deg_to_rad(70.5287794), 1e-9);
    }
}

TEST(SsmLayout, NamesAndBadInput) {
    for (auto kind : kAllKinds) EXPECT_EQ(ba::parse_layout_kind(ba::to_string(kind)), kind);
    EXPECT_FALSE(ba::parse_layout_kind("5-point"));
    EXPECT_THROW(ba::make_layout(ba::LayoutKind::CubeCorner, Vec3::Zero(), 0.0, Vec3::UnitZ()), ba::AnalysisError);
    EXPECT_THROW(ba::make_layout(ba::LayoutKind::CubeCorner, Vec3::Zero(), 100.0, Vec3::Zero()), ba::AnalysisError);
}

TEST(SsmCondition, ThreePointConeMatchesSqrt2CotTheta) {
    // seed-math.md: cond = √2·cot θ (27 at 3°, 8 at 10°, 2.45 at 30°, 1.0 at 54.7356°).
    const Vec3 socket{0, 0, 0};
    for (double deg : {3.0, 10.0, 30.0, 54.7356103172}) {
        const double th = ba::deg_to_rad(deg);
        EXPECT_NEAR(ba::ssm_condition_number(socket, cone3(socket, 100, th)), std::sqrt(2.0) / std::tan(th), 1e-9)
            << deg << "°";
    }
    // "A target point plus two neighbours h apart": cond ≈ 3L/h, 30 for h = 10 mm at L = 100 mm.
    const std::vector<Vec3> cluster{{0, 0, 100}, {10, 0, 100}, {0, 10, 100}};
    EXPECT_NEAR(ba::ssm_condition_number(socket, cluster), 30.0, 3.0);
}

// ---- Exact solver

TEST(SsmSolve, ExactRecoversKnownErrorForEveryLayout) {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> u(-1, 1);
    for (auto kind : kAllKinds) {
        for (int trial = 0; trial < 50; ++trial) {
            const Vec3 socket{200 * u(rng), 200 * u(rng), 100 * u(rng)};
            const double length = 100 + 200 * std::abs(u(rng));
            const Vec3 approach{u(rng), u(rng), 1.0};
            const auto lay = ba::make_layout(kind, socket, length, approach, u(rng));
            Vec3 e{u(rng), u(rng), u(rng)};
            e *= 0.5 / e.norm() * std::abs(u(rng));  // |e| up to 0.5 mm
            const auto dl = readings(socket, lay.points_mm, e);
            const auto r = ba::solve_ssm(socket, lay.points_mm, dl);
            EXPECT_LT((r.exact_mm - e).norm(), kRecoverTol_mm) << ba::to_string(kind) << " trial " << trial;
            EXPECT_NEAR(r.condition_number, 1.0, 1e-9);
            EXPECT_LE(r.iterations, 12);
            EXPECT_EQ(r.n, lay.points_mm.size());
            if (lay.points_mm.size() > 3) {
                ASSERT_TRUE(r.residual_rms_mm);
                EXPECT_LT(*r.residual_rms_mm, 1e-12);
            } else {
                EXPECT_FALSE(r.residual_rms_mm);
            }
        }
    }
}

TEST(SsmSolve, LinearEquationOneErrorIsBoundedAsDocumented) {
    // Eq. (1) drops (Δl² − |e|²)/2 per row, at most |e|²/(2L) after dividing by l: 1.25 µm for
    // |e| = 0.5 mm, L = 100 mm. The solution error is then at most √n·|e|²/(2L)/σ_min(U).
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    const Vec3 socket{10, 20, 30};
    const double length = 100;
    for (auto kind : kAllKinds) {
        const auto lay = ba::make_layout(kind, socket, length, Vec3::UnitZ());
        const double n = static_cast<double>(lay.points_mm.size());
        const double smin = smallest_singular_value(socket, lay.points_mm);
        for (int trial = 0; trial < 100; ++trial) {
            Vec3 e{u(rng), u(rng), u(rng)};
            e *= 0.5 / e.norm();
            const auto dl = readings(socket, lay.points_mm, e);
            for (std::size_t i = 0; i < dl.size(); ++i) {
                const Vec3 d = lay.points_mm[i] - socket;
                EXPECT_LE(std::abs(d.dot(e) / length - dl[i]), 1.25e-3 * 1.01);  // the dropped bracket
            }
            const auto r = ba::solve_ssm(socket, lay.points_mm, dl);
            const double err = (r.linear_mm - e).norm();
            EXPECT_LE(err, std::sqrt(n) * 0.25 / (2 * length) / smin * 1.01) << ba::to_string(kind);
            EXPECT_GT(err, 1e-5) << "the bracket matters at |e| = 0.5 mm";  // and the exact solver removes it
            EXPECT_LT((r.exact_mm - e).norm(), kRecoverTol_mm);
        }
    }
}

TEST(SsmSolve, NominalLengthsOverrideTheGeometricOnes) {
    const Vec3 socket{0, 0, 0};
    const auto lay = ba::make_layout(ba::LayoutKind::FourPoint, socket, 150, Vec3::UnitZ());
    const Vec3 e{0.01, -0.02, 0.03};
    auto dl = readings(socket, lay.points_mm, e);
    std::vector<double> nominal;
    for (std::size_t i = 0; i < dl.size(); ++i) {
        nominal.push_back(150.0 + 0.1 * static_cast<double>(i));  // readings relative to another nominal
        dl[i] -= 0.1 * static_cast<double>(i);
    }
    const auto r = ba::solve_ssm(socket, lay.points_mm, dl, nominal);
    EXPECT_LT((r.exact_mm - e).norm(), kRecoverTol_mm);
}

TEST(SsmSolve, StillWorksOnAModeratelyConditionedCone) {
    // 10° cone: cond 8. Accepted, and still exact.
    const Vec3 socket{0, 0, 0};
    const auto pts = cone3(socket, 100, ba::deg_to_rad(10));
    const Vec3 e{0.2, -0.1, 0.3};
    const auto r = ba::solve_ssm(socket, pts, readings(socket, pts, e));
    EXPECT_NEAR(r.condition_number, 8.02, 0.01);
    EXPECT_LT((r.exact_mm - e).norm(), kRecoverTol_mm);
}

// ---- Refusals

TEST(SsmRefuse, DegenerateAndBadlyConditionedLayouts) {
    const Vec3 socket{0, 0, 0};
    // All bar directions in one plane through the socket: rank 2.
    const std::vector<Vec3> planar{{100, 0, 0}, {0, 100, 0}, {70.7, 70.7, 0}};
    try {
        ba::solve_ssm(socket, planar, std::vector<double>{0, 0, 0});
        FAIL() << "a planar layout must be refused";
    } catch (const ba::AnalysisError& e) {
        EXPECT_NE(std::string(e.what()).find("condition number infinite"), std::string::npos) << e.what();
    }
    // A 2° cone: cond ≈ 40.5 > 30.
    const auto narrow = cone3(socket, 100, ba::deg_to_rad(2));
    try {
        ba::solve_ssm(socket, narrow, std::vector<double>{0, 0, 0});
        FAIL() << "a 2° cone must be refused";
    } catch (const ba::AnalysisError& e) {
        EXPECT_NE(std::string(e.what()).find("exceeds the limit 30"), std::string::npos) << e.what();
    }
    // The limit is an option.
    ba::SsmOptions loose;
    loose.max_condition = 50;
    EXPECT_NO_THROW(ba::solve_ssm(socket, narrow, std::vector<double>{0, 0, 0}, {}, loose));
    EXPECT_NO_THROW(ba::solve_ssm(socket, cone3(socket, 100, ba::deg_to_rad(3)), std::vector<double>{0, 0, 0}));
}

TEST(SsmRefuse, MalformedInput) {
    const Vec3 socket{0, 0, 0};
    const auto lay = ba::make_layout(ba::LayoutKind::CubeCorner, socket, 100, Vec3::UnitZ());
    const std::vector<double> dl{0, 0, 0};
    EXPECT_THROW(ba::solve_ssm(socket, std::span(lay.points_mm).first(2), std::span(dl).first(2)), ba::AnalysisError);
    EXPECT_THROW(ba::solve_ssm(socket, lay.points_mm, std::span(dl).first(2)), ba::AnalysisError);
    EXPECT_THROW(ba::solve_ssm(socket, lay.points_mm, dl, std::vector<double>{100, 100}), ba::AnalysisError);
    auto at_socket = lay.points_mm;
    at_socket[1] = socket;
    EXPECT_THROW(ba::solve_ssm(socket, at_socket, dl), ba::AnalysisError);
    EXPECT_THROW(ba::solve_ssm(socket, lay.points_mm, std::vector<double>{0, std::nan(""), 0}), ba::AnalysisError);
    EXPECT_THROW(ba::solve_ssm(Vec3(0, INFINITY, 0), lay.points_mm, dl), ba::AnalysisError);
}

TEST(SsmRefuse, InconsistentReadingsHaveNoNearbySolution) {
    const Vec3 socket{0, 0, 0};
    const auto lay = ba::make_layout(ba::LayoutKind::CubeCorner, socket, 100, Vec3::UnitZ());
    try {
        ba::solve_ssm(socket, lay.points_mm, std::vector<double>{40.0, -30.0, 45.0});
        FAIL() << "readings 30–45 mm off a 100 mm bar must be refused";
    } catch (const ba::AnalysisError& e) {
        EXPECT_NE(std::string(e.what()).find("no solution near"), std::string::npos) << e.what();
    }
}

// ---- Uncertainty

TEST(SsmUncertainty, PropagatedStdMatchesMonteCarlo) {
    // 2000 noisy solves per layout; each component's sample std within 10 % of the propagated one, and
    // for n > 3 the mean squared residual near σ²·(n − 3)/n.
    constexpr int kDraws = 2000;
    constexpr double kSigma = 0.0005;
    std::mt19937_64 rng(1234);
    std::normal_distribution<double> noise(0.0, kSigma);
    const Vec3 socket{50, 0, -20};
    const Vec3 e{0.12, -0.3, 0.05};
    struct Case {
        std::vector<Vec3> pts;
        const char* name;
    };
    const Case cases[] = {
        {ba::make_layout(ba::LayoutKind::CubeCorner, socket, 100, Vec3::UnitZ()).points_mm, "cube corner"},
        {ba::make_layout(ba::LayoutKind::SixPoint, socket, 100, Vec3::UnitZ()).points_mm, "6-point"},
        {cone3(socket, 100, ba::deg_to_rad(10)), "10° cone"},  // anisotropic: lateral std ≫ axial
    };
    for (const auto& c : cases) {
        const auto exact = readings(socket, c.pts, e);
        ba::SsmOptions opt;
        opt.reading_std_mm = kSigma;
        const auto ref = ba::solve_ssm(socket, c.pts, exact, {}, opt);
        Vec3 sum = Vec3::Zero(), sum2 = Vec3::Zero();
        double ss_res = 0;
        for (int k = 0; k < kDraws; ++k) {
            auto dl = exact;
            for (auto& v : dl) v += noise(rng);
            const auto r = ba::solve_ssm(socket, c.pts, dl, {}, opt);
            const Vec3 dev = r.exact_mm - e;
            sum += dev;
            sum2 += dev.cwiseProduct(dev);
            if (r.residual_rms_mm) ss_res += *r.residual_rms_mm * *r.residual_rms_mm;
        }
        const Vec3 mean = sum / kDraws;
        const Vec3 sd = (sum2 / kDraws - mean.cwiseProduct(mean)).cwiseSqrt();
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(sd[i], ref.std_mm[i], 0.1 * ref.std_mm[i]) << c.name << " component " << i;
            EXPECT_GT(ref.std_mm[i], 0.0);
        }
        if (c.pts.size() > 3) {
            const double n = static_cast<double>(c.pts.size());
            EXPECT_NEAR(ss_res / kDraws, kSigma * kSigma * (n - 3) / n, 0.1 * kSigma * kSigma * (n - 3) / n) << c.name;
        }
    }
}
