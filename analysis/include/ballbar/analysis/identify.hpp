// SPDX-License-Identifier: MIT
// Identification of a machine's error parameters from ball-bar readings: nonlinear least squares
// (Levenberg–Marquardt) of measured − predicted bar lengths over a chosen subset of `Param` plus the
// set-up offset (x, y, z) of every distinct socket position the readings use.
//
// Observability (docs/identification.md): before fitting, the Jacobian's columns are scaled to unit
// norm and taken in priority order (socket offsets first, then the free parameters in the caller's
// order); a column whose component orthogonal to the columns already accepted is below
// `FitOptions::min_independence` is a direction the data cannot determine: that parameter is reported
// unobservable, excluded from the fit and held at its fixed value. For the accepted ones, the
// reported `independence` is sqrt(1 − R²) of the column against all other accepted columns (1: the
// data determine it alone; → 0: only in combination), i.e. 1/sqrt of its variance inflation factor.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/reading.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

struct FitOptions {
    /// Parameters to estimate. Every other parameter is held at `fixed`.
    std::vector<Param> free_params;
    /// Values of the parameters not estimated, and start values of the free ones.
    ErrorParams fixed{};
    /// Estimate the set-up offset of every socket position (recommended: a socket is never placed
    /// exactly where the nominal says). When false, sockets sit at their nominal places.
    bool fit_socket_offsets = true;
    int max_iterations = 50;
    /// Below this independence (0..1) a parameter is unobservable and excluded.
    double min_independence = 1e-4;
    /// Below this RMS sensitivity (mm per unit of the parameter) a parameter has no effect on these
    /// readings at all (e.g. spindle growth when every reading has time 0).
    double min_sensitivity = 1e-12;
    /// Converged when a step changes the predicted readings by less than this fraction of the reading
    /// noise (root-sum-square over readings of the change ≤ step_tolerance · σ): parameter steps of
    /// about this fraction of their standard uncertainty or less.
    double step_tolerance = 1e-2;
    /// The least reading noise the uncertainties assume (see FitSummary::noise_floor_mm): the 1 nm step
    /// in which displacements are stored.
    double min_reading_sigma_mm = 1e-6;

    /// Empty when valid, else what is wrong (a Param listed twice, limits out of range).
    std::string validate() const;
};

/// A distinct socket position used by the readings (readings whose nominal sockets agree to 1e-6 mm).
struct SocketPosition {
    Vec3 nominal_mm = Vec3::Zero();
    Vec3 offset_mm = Vec3::Zero();  ///< estimated set-up offset (actual − nominal, table frame)
    std::size_t readings = 0;
};

/// One estimated quantity: an error parameter or one component of a socket offset.
struct ParamEstimate {
    std::string name;            ///< ISO name ("X0C") or "socket<k>.x" (k from 0)
    std::optional<Param> param;  ///< empty for a socket offset
    int socket = -1;             ///< socket index for a socket offset
    int axis = -1;               ///< 0, 1, 2 = x, y, z for a socket offset
    double estimate = 0;         ///< in the parameter's unit (mm, rad, ...)
    double std = 0;              ///< standard uncertainty; 0 when unobservable
    double sensitivity = 0;      ///< RMS over readings of |∂reading/∂parameter| (mm per unit)
    double independence = 0;     ///< 0..1, see the file comment
    bool observable = false;     ///< false: excluded from the fit, held at its fixed value
    /// An unobservable parameter whose effect this estimate carries: the data determine only the
    /// combination, so the estimate is the machine's value plus `per_unit` (this estimate's unit per
    /// the held parameter's) times what the held parameter really is beyond its fixed value.
    struct Carried {
        std::string name;
        double per_unit = 0;
        double share = 0;  ///< the same, unit-scaled (both columns of norm 1): 1 = carried whole
    };
    /// The held parameters whose unit-scaled effect this estimate carries by 0.001 or more (observable
    /// estimates only; docs/identification.md, Observability). `std` is the uncertainty given them.
    std::vector<Carried> carries;
};

struct FitSummary {
    bool converged = false;
    int iterations = 0;
    int jacobian_evaluations = 0;
    std::string message;  ///< why the iteration stopped
    /// Free parameters in the caller's order, then socket offsets (socket 0 x, y, z, socket 1 ...).
    std::vector<ParamEstimate> estimates;
    /// Indices into `estimates` of the observable ones; `correlation` is over these, in this order.
    std::vector<std::size_t> fitted;
    Eigen::MatrixXd correlation;
    double residual_rms_mm = 0;    ///< sqrt(Σr²/readings)
    double residual_sigma_mm = 0;  ///< sqrt(Σr²/degrees of freedom): the estimated reading noise
    /// The least reading noise the readings allow: the RMS of each reading's own standard uncertainty
    /// (std_mm/√n, where given), and never below FitOptions::min_reading_sigma_mm. Uncertainties use
    /// max(residual_sigma_mm, this): readings that agree to round-off (copies, a simulation without
    /// noise) fit with no residual, which is no evidence of a parameter known to 1e-12 µm.
    double noise_floor_mm = 0;
    bool uncertainty_from_floor = false;  ///< residual_sigma_mm was below noise_floor_mm
    double initial_rms_mm = 0;            ///< RMS of measured − predicted at the start values
    std::size_t readings = 0;
    std::size_t degrees_of_freedom = 0;  ///< readings − fitted unknowns
    ErrorParams model{};                 ///< fixed values with the estimates written in
    std::vector<SocketPosition> sockets;

    std::vector<std::string> unobservable() const;
    const ParamEstimate* find(std::string_view name) const;
    /// A few lines for a log or the terminal.
    std::string brief_report() const;
};

/// Distinct socket positions of `readings` in first-seen order, and each reading's socket index.
std::vector<SocketPosition> socket_positions(const ReadingSet& readings, std::vector<int>* reading_socket = nullptr);

/// Merges several reading sets of one machine: the same type and geometry (to 1e-6 mm; the first set's
/// name is kept). Throws AnalysisError naming what differs: a set of another geometry would otherwise be
/// fitted with the first set's, silently wrong.
ReadingSet merge_readings(std::span<const ReadingSet> sets);
/// The same, taking the sets: their readings are moved, never held twice (a readings file of 250 MiB
/// is about 330 MB in memory).
ReadingSet merge_readings(std::vector<ReadingSet>&& sets);

/// The conditions the actual model needs for one reading (bar temperature 20 °C when not measured).
ReadingConditions conditions_of(const Reading& reading);

/// measured − predicted per reading, for parameters `e` and socket offsets (indexed as returned by
/// `socket_positions`; empty: all zero).
Eigen::VectorXd reading_residuals(const ReadingSet& readings, const ErrorParams& e,
                                  std::span<const Vec3> socket_offsets_mm = {});

/// The fit. Throws AnalysisError for invalid options or fewer readings than unknowns.
FitSummary fit_error_model(const ReadingSet& readings, const FitOptions& options);

/// Exact Jacobian ∂predicted/∂(free params, socket offsets) at `e` (closed form, reading_model.hpp), rows per
/// reading; columns: `free` in order, then 3 per socket. Used by the fit and the planner.
Eigen::MatrixXd reading_jacobian(const ReadingSet& readings, const ErrorParams& e, std::span<const Param> free,
                                 std::span<const Vec3> socket_offsets_mm, bool with_socket_offsets);

/// The greedy independence test shared by the fit and the planner. `unit_gram` is the Gram matrix of
/// unit-norm columns (zero rows/columns for columns without effect); columns are taken in `order`;
/// returns each column's independence from the columns accepted before it (0 for a zero column) and
/// appends the accepted ones (independence >= min_independence) to `accepted`.
Eigen::VectorXd sequential_independence(const Eigen::MatrixXd& unit_gram, std::span<const int> order,
                                        double min_independence, std::vector<int>& accepted);

}  // namespace ballbar::analysis
