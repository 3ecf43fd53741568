// SPDX-License-Identifier: MIT
// Empirical terms: what the discovery workflow learns when the readings hold structure no effect of
// its library explains (docs/discovery.md, "Beyond the library").
//
// Each term is one coefficient of a shape in one variable, entered through the kinematics:
//  - `rotary_angular`: an error of a rotary axis's rotation angle as a function of its own angle,
//    ε(θ) = Σ aₖ cos kθ + bₖ sin kθ (rad): the axis turns by θ + zero offset + ε(θ). What a
//    controller's rotary pitch-error table compensates. Name `C_angular_h1_cos`.
//  - `rotary_backlash`: half the reversal error of a rotary axis (rad): the axis turns by +b after a
//    move in the positive sense, −b after a negative one. Name `C_backlash`.
//  - `linear_positioning`: a non-linear positioning error of a linear axis, δX = c·(X / 100 mm)ᵏ (mm,
//    k = 2, 3: the part a linear scale error cannot take). Name `X_positioning_p2`.
//  - `location_drift`: a location error of a rotary axis drifting linearly during the test (unit per
//    hour of session time). Name `X0C_drift`.
//  - `pivot_drift`: the spindle pivot drifting along machine X or Y (mm/h). Name `pivot_drift_x`.
//  - `bar_temp_pivot`, `air_temp_pivot`: the pivot displaced in proportion to the bar (or air)
//    temperature − 20 °C (mm/K). Names `bar_temp_pivot_x`, `air_temp_pivot_z`.
//  - `bar_temp_quadratic`: the reading grows by L·q·(T_bar − 20 °C)² (1/K²). Name `bar_temp_quadratic`.
//  - `tool_offset`: a constant offset of the tool ball in the machine frame (mm). Name `tool_offset_x`.
// The reading's change is the reading model's gradient times the term (first order: for errors of
// tens of µrad or µm the second-order part is below 1 nm).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/reading.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

enum class EmpiricalKind {
    rotary_angular,
    rotary_backlash,
    linear_positioning,
    location_drift,
    pivot_drift,
    bar_temp_pivot,
    air_temp_pivot,
    bar_temp_quadratic,
    tool_offset
};

struct EmpiricalTerm {
    EmpiricalKind kind = EmpiricalKind::rotary_angular;
    char axis = 'C';              ///< rotary 'A'/'B'/'C', linear 'X'/'Y'/'Z', or the pivot/tool direction 'x'/'y'/'z'
    int order = 1;                ///< harmonic order (angular) or polynomial power (positioning)
    bool sine = false;            ///< angular: the sin kθ coefficient
    Param location = Param::X0C;  ///< location_drift: the drifting location error

    std::string name() const;
    std::string unit()
        const;  ///< "rad", "mm", "mm_per_h", "rad_per_h", "mm_per_K", "per_K2" (docs/cli.md's unit names)
    bool operator==(const EmpiricalTerm&) const = default;
};

/// Parses a name as written by EmpiricalTerm::name(); nullopt when it is not one.
std::optional<EmpiricalTerm> parse_empirical_term(std::string_view name);

/// A learned term with its value.
struct LearnedTerm {
    EmpiricalTerm term;
    double value = 0;
    double std_error = 0;
};

/// A family of terms the search tests together: the shapes of one variable. `groups` partition the
/// terms into what is added or left out together (a harmonic's cos and sin).
struct EmpiricalFamily {
    std::string id;        ///< "C_angular", "X_positioning", "time", "bar_temperature", ...
    std::string variable;  ///< the variable in the user's terms: "C", "X", "time", "C approach direction", ...
    std::vector<EmpiricalTerm> terms;
    std::vector<std::vector<std::size_t>> groups;  ///< indices into `terms`
};

/// The families that can change a reading on this machine type (air temperature only when the
/// readings have it; backlash only when an axis is approached from both senses).
std::vector<EmpiricalFamily> empirical_families(const ReadingSet& readings);

/// The sense of the last move of a rotary axis before each reading (readings in time order): +1, −1,
/// or 0 before the axis has moved.
std::vector<double> approach_direction(const ReadingSet& readings, char axis);

/// The reading model's gradient pieces the terms' columns are made of, at one model.
struct TermBasis {
    Eigen::MatrixXd grad;  ///< per reading: ∂reading/∂(A_zero, B_zero, C_zero, the location errors…)
    std::vector<Param> grad_params;
    Eigen::MatrixXd u;                        ///< per reading: the nominal bar direction (machine frame)
    std::vector<double> dir_a, dir_b, dir_c;  ///< approach directions
};
TermBasis term_basis(const ReadingSet& readings, const ErrorParams& e, std::span<const Vec3> socket_offsets_mm);

/// ∂reading/∂(term coefficient) for every reading (the term's Jacobian column).
Eigen::VectorXd term_column(const ReadingSet& readings, const TermBasis& basis, const EmpiricalTerm& t);

/// ε(θ) of a rotary axis from the learned angular and backlash terms (`approach` the sense of the
/// last move, 0 for none).
double rotary_angle_error(std::span<const LearnedTerm> terms, char axis, double angle_rad, double approach = 0);
/// δ of a linear axis ('X', 'Y', 'Z') at its commanded position from the learned positioning terms.
double linear_positioning_error(std::span<const LearnedTerm> terms, char axis, double position_mm);

/// The learned terms' contribution to each reading (Σ value · column).
Eigen::VectorXd empirical_contribution(const ReadingSet& readings, const TermBasis& basis,
                                       std::span<const LearnedTerm> terms);

}  // namespace ballbar::analysis
