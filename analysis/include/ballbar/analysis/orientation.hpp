// SPDX-License-Identifier: MIT
// Orientation errors of the rotary axes from two SSM results (before and after the rotation): the seed
// P1's first-order Eqs. (6), (7), (11), (12), (17), (18) with the misprints corrected (seed-math.md,
// errata E1–E3), and the exact inversion of the same models. docs/analysis.md lists the formulas.
//
// Sign and frame conventions are the seed's: ΔV1 is the total position error measured before the
// rotation, ΔV2 after it, both machine-frame components; an angle error is actual minus commanded.
#pragma once

#include <optional>
#include <string>

#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

/// A configuration counts as singular when the quantity that vanishes there (cos β, S0/r, (z2 − z1)/L,
/// …) is below this, relative to its scale: a sine of 1e-6 is 0.2 arc-seconds from the singularity.
constexpr double kOrientationSingularTol = 1e-6;

/// Angle errors, radians. Each solver fills only the angles its machine type has (see below); the
/// others stay zero.
struct OrientationErrors {
    double d_alpha_rad = 0;
    double d_beta_rad = 0;
    double d_gamma_rad = 0;
};

/// Which of Δα, Δβ, Δγ one two-step test determines — the one rule every screen, JSON output and
/// report follows: an RRTTT test Δα and Δβ (the head's A and B), a TTTRR test Δα and Δγ (the table's A
/// and C), an RTTTR test Δβ when it turns the spindle's B and Δα otherwise (the table's A; the solver
/// takes every RTTTR test that is not a spindle test as a table test).
struct MeasuredAngles {
    bool alpha = false;
    bool beta = false;
    bool gamma = false;
};
MeasuredAngles measured_angles(MachineType type, bool rtttr_spindle_test);

struct OrientationSolution {
    std::optional<OrientationErrors> first_order;  ///< the corrected seed formulas; empty if singular
    std::optional<OrientationErrors> exact;        ///< exact inversion of the model; empty if singular
    /// Why first_order and/or exact is empty ("first order: cos β = 0 …; exact: …"); empty otherwise.
    std::string singular;
    Vec3 nominal_after_mm = Vec3::Zero();  ///< nominal position after the rotation (x2, y2, z2)
    int exact_iterations = 0;              ///< Gauss–Newton iterations (TTTRR); 1 for closed forms
    double exact_residual_mm = 0;          ///< |model(exact angles) − measured|: 0 on consistent data
};

/// RRTTT: tool ball b = P1 + Rx(α)·Ry(β)·[0, 0, z_r] (B carried by A). Fills d_alpha_rad, d_beta_rad.
struct RrtttInput {
    Vec3 pivot_mm = Vec3::Zero();  ///< (x1, y1, z1): the spindle pivot after the translations
    double z_r_mm = 0;             ///< tool ball from the pivot along the spindle axis (Table 1: −250)
    double alpha_rad = 0, beta_rad = 0;
    Vec3 dV1_mm = Vec3::Zero(), dV2_mm = Vec3::Zero();
};
OrientationSolution solve_orientation(const RrtttInput& in);

/// TTTRR: reference point s = P1 + Rx(α)·([0, 0, z_αγ] + Rz(γ)·[x_r, y_r, z_r]) (C carried by A).
/// Fills d_alpha_rad, d_gamma_rad. The exact inversion is a Gauss–Newton fit of (α', γ') to all three
/// rows: it has no z2 = z1 singularity, but S0 = 0 is a true one (an A and a C rotation then move the
/// point the same way at first order).
struct TtttrrInput {
    Vec3 a_pivot_mm = Vec3::Zero();  ///< (x1, y1, z1): a point of the A axis
    double z_ag_mm = 0;              ///< z_αγ: the C frame's origin along the A frame's Z
    Vec3 socket_mm = Vec3::Zero();   ///< (x_r, y_r, z_r) in the C frame
    double alpha_rad = 0, gamma_rad = 0;
    Vec3 dV1_mm = Vec3::Zero(), dV2_mm = Vec3::Zero();
};
OrientationSolution solve_orientation(const TtttrrInput& in);

/// RTTTR spindle set-up: b = P1 + Ry(β)·[0, 0, z_r]. Fills d_beta_rad (Eq. 17).
struct RtttrSpindleInput {
    Vec3 pivot_mm = Vec3::Zero();
    double z_r_mm = 0;
    double beta_rad = 0;
    Vec3 dV1_mm = Vec3::Zero(), dV2_mm = Vec3::Zero();
};
OrientationSolution solve_orientation(const RtttrSpindleInput& in);

/// RTTTR table set-up: s = Pt1 + Rx(α)·[x_tr, y_tr, z_tr]. Fills d_alpha_rad (Eq. 18).
struct RtttrTableInput {
    Vec3 a_pivot_mm = Vec3::Zero();  ///< (x_t1, y_t1, z_t1): a point of the A axis
    Vec3 socket_mm = Vec3::Zero();   ///< (x_tr, y_tr, z_tr) in the table frame
    double alpha_rad = 0;
    Vec3 dV1_mm = Vec3::Zero(), dV2_mm = Vec3::Zero();
};
OrientationSolution solve_orientation(const RtttrTableInput& in);

}  // namespace ballbar::analysis
