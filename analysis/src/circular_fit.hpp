// SPDX-License-Identifier: MIT
// Internal to the circular analysis: the data-arc samples handed to the diagnosis fit.
#pragma once

#include <vector>

#include "ballbar/analysis/circular.hpp"

namespace ballbar::analysis::circular::detail {

struct FitPoint {
    double t = 0.0;          ///< trace time, s
    double y_um = 0.0;       ///< measured − programmed radius
    double theta = 0.0;      ///< commanded angle, rad (from +p towards +q)
    double cos_theta = 1.0;  ///< cos θ and sin θ, computed once for the fit and G
    double sin_theta = 0.0;
    double travelled = 0.0;  ///< commanded angle travelled since the run's arc began, rad (≥ 0)
    int dir = 1;             ///< +1 ccw, −1 cw
    int run = 0;
};

struct FitInput {
    TestSpec test;
    std::vector<FitPoint> points;
    std::vector<double> run_lag_s;      ///< lag found in each run's feed-in
    std::vector<double> run_start_rad;  ///< each run's start angle
    double omega_rad_s = 0.0;           ///< angular speed of the arcs
    double sample_rate_hz = 0.0;
    bool both_directions = false;
};

struct FitOutput {
    std::vector<DiagnosticResult> diagnostics;  // unranked; shares filled
    std::vector<UnseparableGroup> unseparable;
    double residual_rms_um = 0.0;
    double mean_radius_um = 0.0;
    double mean_radius_std_um = 0.0;
    double lag_mean_s = 0.0;  ///< the servo lag the fit used (mean of the axes)
    /// What the fit explains at each of the input's points (µm, the same order), the vibration left out:
    /// the centre, the mean radius, the lag and every diagnosis of the machine's path together.
    std::vector<double> fitted_um;
};

FitOutput fit_diagnostics(const FitInput& input, const AnalysisOptions& options);

}  // namespace ballbar::analysis::circular::detail
