// SPDX-License-Identifier: MIT
// The result of kind "identification" (docs/identification.md): what `identify --json` prints and what is
// stored with each session the model was fitted to. One writer (from the fit) and one strict reader, used
// by the report, `sessions show` and any other front end.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/identify.hpp"
#include "ballbar/storage/model_codec.hpp"

namespace ballbar::storage {

inline constexpr std::string_view kIdentificationResultKind = "identification";

/// One estimated unknown as the result holds it, in the analysis' units (`unit`: mm, rad, mm/mm, …).
struct IdentifiedEstimate {
    std::string name;  ///< ISO name ("X0C") or a socket offset ("socket0.x")
    double estimate = 0;
    double std = 0;  ///< standard uncertainty; 0 when unobservable
    double sensitivity = 0;
    double independence = 0;
    bool observable = false;
    std::string unit;
};

struct IdentificationRecord {
    bool converged = false;
    int iterations = 0;
    std::string message;
    int readings = 0;
    int degrees_of_freedom = 0;
    double residual_rms_um = 0;
    double residual_sigma_um = 0;
    std::optional<double> initial_rms_um;  ///< of the readings before the fit
    std::optional<double> noise_floor_um;  ///< results stored before the noise floor have none
    std::optional<bool> uncertainty_from_noise_floor;
    std::vector<IdentifiedEstimate> estimates;
    std::vector<std::string> correlation_names;
    std::vector<std::vector<double>> correlation;  ///< over correlation_names; NaN where not defined
    std::optional<ErrorModel> model;               ///< the model the fit made
};

std::string identification_to_json(const analysis::FitSummary& fit, const ErrorModel& model);

/// Strict on what is there (an unknown key, a value of the wrong type, a count that is not a
/// non-negative integer, a correlation that is not square over its names: FormatError naming the key);
/// `converged`, `residual_rms_um` and `estimates` are required, the rest as older results may lack them.
IdentificationRecord identification_from_json(std::string_view json);

}  // namespace ballbar::storage
