// SPDX-License-Identifier: MIT
// The orientation errors' propagated uncertainty against a Monte Carlo of the same test: ΔV1 and ΔV2
// drawn with the stated covariances (strongly correlated components, as an ill-conditioned SSM
// layout gives), solved exactly, the spread compared.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>

#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/acquisition/plan.hpp"
#include "ballbar/acquisition/verdict.hpp"

namespace ballbar::acquisition {
namespace {

using analysis::MachineType;
using analysis::Mat3;
using analysis::Vec3;

/// A covariance with standard uncertainties `std` (mm) and correlation `rho` between every pair.
Mat3 covariance(const Vec3& std, double rho) {
    Mat3 c;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) c(i, j) = (i == j ? 1.0 : rho) * std[i] * std[j];
    return c;
}

class OrientationUncertainty : public ::testing::TestWithParam<MachineType> {};

TEST_P(OrientationUncertainty, AgreesWithAMonteCarloOfTheSameTest) {
    const MachineFile m = seed_machine(GetParam());
    const Plan plan = make_plan(m, default_plan(m));
    const auto truth = true_values(plan, demo_errors(GetParam()));
    const Mat3 cov1 = covariance(Vec3(0.4e-3, 0.3e-3, 0.5e-3), 0.8);
    const Mat3 cov2 = covariance(Vec3(0.5e-3, 0.4e-3, 0.3e-3), -0.45);
    const Mat3 l1 = cov1.llt().matrixL(), l2 = cov2.llt().matrixL();
    std::mt19937_64 rng(11);
    std::normal_distribution<double> n01;
    for (int t = 0; t < plan.test_count(); ++t) {
        const Vec3 dV1 = truth[static_cast<std::size_t>(t)].result.dV1_mm;
        const Vec3 dV2 = truth[static_cast<std::size_t>(t)].result.dV2_mm;
        const TestResult r = compute_test(plan, t, dV1, dV2, cov1, cov2);
        ASSERT_TRUE(r.orientation.exact && r.std_rad) << "test " << t + 1;
        EXPECT_FALSE(compute_test(plan, t, dV1, dV2).std_rad) << "no uncertainty without the inputs'";

        constexpr int kDraws = 4000;
        double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
        for (int k = 0; k < kDraws; ++k) {
            const Vec3 n1 = l1 * Vec3(n01(rng), n01(rng), n01(rng));
            const Vec3 n2 = l2 * Vec3(n01(rng), n01(rng), n01(rng));
            const auto e = compute_test(plan, t, dV1 + n1, dV2 + n2).orientation.exact;
            ASSERT_TRUE(e);
            const double v[3] = {e->d_alpha_rad, e->d_beta_rad, e->d_gamma_rad};
            for (int a = 0; a < 3; ++a) {
                sum[a] += v[a];
                sum2[a] += v[a] * v[a];
            }
        }
        const double prop[3] = {r.std_rad->d_alpha_rad, r.std_rad->d_beta_rad, r.std_rad->d_gamma_rad};
        int measured = 0;
        for (int a = 0; a < 3; ++a) {
            const double mean = sum[a] / kDraws;
            const double mc = std::sqrt(std::max(sum2[a] / kDraws - mean * mean, 0.0));
            if (prop[a] == 0) {
                EXPECT_LT(mc, 1e-15) << "test " << t + 1 << " angle " << a << ": not measured by this test";
                continue;
            }
            ++measured;
            // 4000 draws: the sample standard deviation is within ±5 % (4σ) of the true one.
            EXPECT_NEAR(mc, prop[a], 0.05 * prop[a]) << "test " << t + 1 << " angle " << a;
            EXPECT_GT(prop[a], 1e-7) << "a few µm over ~100 mm is some µrad";
        }
        EXPECT_GE(measured, 1) << "test " << t + 1;
    }
}

INSTANTIATE_TEST_SUITE_P(AllTypes, OrientationUncertainty,
                         ::testing::Values(MachineType::RRTTT, MachineType::TTTRR, MachineType::RTTTR),
                         [](const auto& p) { return std::string(analysis::to_string(p.param)); });

}  // namespace
}  // namespace ballbar::acquisition

namespace ballbar::acquisition {
namespace {

TEST(SsmVerdict, EachLocationAndMeasuredAngleIsJudgedAsMeasuredAndTheSummaryNamesWhatFailed) {
    TestResult t;
    t.test = 1;  // the second test: "test 2" on the screen
    t.kind = TestKind::BothAxes;
    t.dV1_mm = analysis::Vec3(0.012, 0.0, 0.0);          // 12 µm
    t.dV2_mm = analysis::Vec3(0.0, 0.018, 0.024);        // 30 µm: at the tolerance, within it
    t.dV1_std_mm = analysis::Vec3(0.005, 0.005, 0.005);  // not subtracted: the value is judged
    analysis::OrientationErrors e;
    e.d_alpha_rad = analysis::deg_to_rad(-41.0 / 3600);  // |Δα| 41″ > 30″
    e.d_beta_rad = analysis::deg_to_rad(500.0 / 3600);   // not measured on a TTTRR: not judged
    e.d_gamma_rad = analysis::deg_to_rad(29.0 / 3600);
    t.orientation.exact = e;

    Tolerances none;
    EXPECT_FALSE(judge_ssm(analysis::MachineType::TTTRR, none, {}, {t}).judged());
    EXPECT_EQ(judge_ssm(analysis::MachineType::TTTRR, none, {}, {t}).summary(), "");

    Tolerances tol;
    tol.location_um = 30;
    tol.angle_arcsec = 30;
    const SsmVerdict v = judge_ssm(analysis::MachineType::TTTRR, tol, {}, {t});
    ASSERT_EQ(v.checks.size(), 4u);  // |ΔV1|, |ΔV2|, Δα, Δγ
    EXPECT_FALSE(v.pass());
    EXPECT_EQ(v.summary(), "FAIL: 1 of 4 beyond tolerance — test 2 Δα 41.00″ > 30″");

    tol.angle_arcsec = 45;
    const SsmVerdict ok = judge_ssm(analysis::MachineType::TTTRR, tol, {}, {t});
    EXPECT_TRUE(ok.pass());
    EXPECT_EQ(ok.summary(), "PASS: |ΔV| within 30 µm at both locations; both orientation errors within 45″");

    // A singular orientation has no angle to judge; its locations still are.
    TestResult singular = t;
    singular.orientation.exact.reset();
    EXPECT_EQ(judge_ssm(analysis::MachineType::TTTRR, tol, {}, {singular}).checks.size(), 2u);

    // A test's own tolerances (the plan's tests[].tolerances) replace the machine's for it alone.
    TestResult first = t;
    first.test = 0;
    std::vector<TestSpec> plan(2);
    plan[1].tolerances.location_um = 10;  // the second test's: its 12 µm and 30 µm fail; the first keeps 30 µm
    const SsmVerdict own = judge_ssm(analysis::MachineType::TTTRR, tol, plan, {first, t});
    ASSERT_EQ(own.checks.size(), 8u);
    EXPECT_EQ(own.summary(),
              "FAIL: 2 of 8 beyond tolerance — test 2 |ΔV1| 12.00 µm > 10 µm; test 2 |ΔV2| 30.00 µm > 10 µm");
    plan[1].tolerances.location_um = 35;
    plan[0].tolerances.angle_arcsec = 50;
    EXPECT_EQ(judge_ssm(analysis::MachineType::TTTRR, tol, plan, {first, t}).summary(),
              "PASS: |ΔV| within each test's tolerance (30 to 35 µm) at all 4 locations; all 4 orientation errors "
              "within each test's tolerance (45 to 50″)");
}

}  // namespace
}  // namespace ballbar::acquisition
