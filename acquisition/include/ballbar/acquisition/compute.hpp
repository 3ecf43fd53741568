// SPDX-License-Identifier: MIT
// From captured points to results: SSM per step (ΔV with its uncertainty) and the orientation model of
// the test (first order and exact). Also the "true" values of a simulated machine, computed the same
// way from its exact kinematics, so a measurement can be compared with the truth (docs/procedure.md).
#pragma once

#include <span>
#include <vector>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/analysis/error_params.hpp"

namespace ballbar::acquisition {

/// +1 when SSM's e (tool ball minus table ball error) is the seed's ΔV (the tool ball is the moving
/// element: RRTTT, RTTTR Δβ), −1 when the table ball is (TTTRR, RTTTR Δα).
double dv_sign(const Plan& plan, int test);

/// SSM of one step from its captured points (all of the step's points, in order).
LocationResult compute_location(const Plan& plan, int test, int step, std::span<const CapturedPoint> points);

/// Orientation of a test from its two ΔV (seed sign convention). With the covariances of the two ΔV
/// (SSM's cov_mm2; the two locations are measured independently), also the propagated standard
/// uncertainty of the exact solution (TestResult::std_rad).
TestResult compute_test(const Plan& plan, int test, const analysis::Vec3& dV1_mm, const analysis::Vec3& dV2_mm,
                        const analysis::Mat3& dV1_cov_mm2 = analysis::Mat3::Zero(),
                        const analysis::Mat3& dV2_cov_mm2 = analysis::Mat3::Zero());

/// The truth of a simulated machine with errors `e` and a socket set-up offset: per test, the exact
/// total position error (b − s)_actual − (b − s)_nominal at the step's points (common to them when the
/// errors are those of rotary axes and tool), and the orientation errors the same model returns for it.
struct TrueTest {
    analysis::Vec3 e1_mm = analysis::Vec3::Zero(), e2_mm = analysis::Vec3::Zero();  ///< SSM's e, steps 1 and 2
    TestResult result;  ///< dV1/dV2 and the orientation of the exact errors
};
std::vector<TrueTest> true_values(const Plan& plan, const analysis::ErrorParams& e,
                                  const analysis::Vec3& socket_offset_mm = analysis::Vec3::Zero());

}  // namespace ballbar::acquisition

namespace ballbar::acquisition {
/// Known, non-zero errors of a seed-like machine for the demo and the tests: location errors, tilts and
/// zero offsets of the type's rotary axes (tens of µm, tens of µrad, a few hundredths of a degree) and a
/// tool length error. They are common to the points of a location, as SSM assumes.
analysis::ErrorParams demo_errors(analysis::MachineType type);
}  // namespace ballbar::acquisition
