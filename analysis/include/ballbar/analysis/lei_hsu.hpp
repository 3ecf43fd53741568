// SPDX-License-Identifier: MIT
// The X'Y'ZA'C' machine of Lei & Hsu (2003), the second seed: nominal forward kinematics, the
// first-order inverse-Jacobian correction and an exact (Gauss–Newton) correction, as corrected in
// docs/compensation.md (which also names what the paper printed wrong).
//
// u = (x_m, y_m, z_m, θa, θc) (mm, rad); v = (x_w, y_w, z_w, i_w, j_w, k_w) in workpiece coordinates:
//   P = R·(x_m, y_m, z_m) − (X_w0, Y_w0, Z3 + Z_w0),  Q = R·e_z,  R = Rz(−θc)·Rx(−θa)·diag(−1, −1, 1).
// dv = ideal − actual pose (the paper's Eq. 16); du is added to the commanded axes.
#pragma once

#include <Eigen/Core>

namespace ballbar::analysis {

using Vec5 = Eigen::Matrix<double, 5, 1>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using LeiHsuJacobian = Eigen::Matrix<double, 6, 5>;

struct LeiHsuOffsets {
    double Xw0_mm = 0, Yw0_mm = 0, Zw0_mm = 0, Z3_mm = 0;
};

/// Eqs. (10)–(15).
Vec6 lei_hsu_forward(const LeiHsuOffsets& offsets, const Vec5& u);
/// ∂v/∂u of the forward kinematics (does not depend on the offsets).
LeiHsuJacobian lei_hsu_jacobian(const Vec5& u);

struct LeiHsuCorrection {
    Vec5 du = Vec5::Zero();
    bool singular = false;  ///< |sin θa| below the tolerance: no C correction (dθc = 0)
    bool converged = true;  ///< exact solution only
    int iterations = 0;     ///< exact solution only
};

/// First order, closed form: dθa = C_a(S_c di + C_c dj) − S_a dk, dθc = (C_c di − S_c dj)/S_a
/// (least squares over i, j, k) and the corrected compact dx_m, dy_m, dz_m (Eqs. 18, 20 and the
/// corrected 19). At |S_a| < singular_tolerance: dθc = 0 and the seed-math θa = 0 forms.
LeiHsuCorrection lei_hsu_first_order(const Vec5& u, const Vec6& dv, double singular_tolerance = 1e-9);

/// Exact: du with F(u + du) = F(u) + dv, the orientation in the least-squares sense (the target
/// Q + dQ need not be a unit vector), by Gauss–Newton; θc held when |S_a| < singular_tolerance.
LeiHsuCorrection lei_hsu_exact(const LeiHsuOffsets& offsets, const Vec5& u, const Vec6& dv,
                               double singular_tolerance = 1e-9, int max_iterations = 50);

}  // namespace ballbar::analysis
