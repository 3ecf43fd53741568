// SPDX-License-Identifier: MIT
// Single socket method (SSM): the total position error vector `e` of one location from n ≥ 3 bar
// readings taken from one socket (seed P1 Eq. (1), and the exact relation of seed-math.md).
//
// With d_i = P_i − X0 (nominal point minus socket), l_i = |d_i| (nominal length) and Δl_i the measured
// minus nominal length, the exact relation is
//     d_i·e = l_i·Δl_i + (Δl_i² − |e|²)/2.
// Eq. (1) drops the bracket. Both are solved here in the row-normalised form u_i·e = Δl_i + …/l_i with
// the unit bar directions u_i = d_i/l_i: identical to Eq. (1) for n = 3, and the unweighted least-squares
// estimate for equal reading noise when n > 3. docs/analysis.md derives it and explains the limits.
//
// Nothing here allocates: every step is a 3×3 system accumulated over the points.
#pragma once

#include <cstddef>
#include <optional>
#include <span>

#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

/// Layouts with a larger condition number (of the matrix of unit bar directions) are refused: at 30
/// a 0.5 µm reading noise already becomes ~15 µm of noise in e, the size of the errors being measured.
constexpr double kSsmMaxCondition = 30.0;

/// Reading standard uncertainty assumed when the caller gives none: the ball-bar's resolution class.
constexpr double kSsmDefaultReadingStd_mm = 0.0005;

struct SsmOptions {
    double max_condition = kSsmMaxCondition;           ///< refuse layouts above this condition number
    double reading_std_mm = kSsmDefaultReadingStd_mm;  ///< standard uncertainty of one reading
    int max_iterations = 50;                           ///< fixed-point plus Gauss–Newton steps, in total
};

struct SsmResult {
    Vec3 linear_mm = Vec3::Zero();          ///< Eq. (1) (least squares for n > 3)
    Vec3 exact_mm = Vec3::Zero();           ///< exact nonlinear solution (root nearest zero)
    double condition_number = 0;            ///< 2-norm condition number of the unit bar directions
    Vec3 std_mm = Vec3::Zero();             ///< propagated standard uncertainty of each component of e
    Mat3 cov_mm2 = Mat3::Zero();            ///< their covariance (std_mm is the root of its diagonal)
    std::optional<double> residual_rms_mm;  ///< RMS of the reading residuals; only for n > 3
    int iterations = 0;                     ///< iterations of the exact solver
    std::size_t n = 0;                      ///< number of readings used
};

/// Condition number (2-norm) of the n×3 matrix of unit directions from the socket to the points.
/// 1.0 for mutually orthogonal directions; +infinity for a degenerate (coplanar through the socket)
/// set. Throws AnalysisError if a point coincides with the socket or fewer than 3 points are given.
double ssm_condition_number(const Vec3& socket_mm, std::span<const Vec3> points_mm);

/// Solves one location. `delta_l_mm[i]` is measured minus nominal length of point i; the nominal
/// length is |points_mm[i] − socket_mm| unless `nominal_mm` is non-empty (then it must have one entry
/// per point). Throws AnalysisError for fewer than 3 points, mismatched sizes, non-finite input, a point
/// at the socket, a layout above `options.max_condition`, or readings with no solution near the nominal
/// points (inconsistent lengths).
SsmResult solve_ssm(const Vec3& socket_mm, std::span<const Vec3> points_mm, std::span<const double> delta_l_mm,
                    std::span<const double> nominal_mm = {}, const SsmOptions& options = {});

}  // namespace ballbar::analysis
