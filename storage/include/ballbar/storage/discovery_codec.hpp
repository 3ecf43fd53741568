// SPDX-License-Identifier: MIT
// The stored result of the discovery workflow (results table, kind "discovery", docs/discovery.md): the
// JSON `ballbar discover --json` prints and, with the residual analysis and the model it made, stores
// with each input session. One owner: the writer and the typed reader the report and `sessions show`
// read it with.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/discovery.hpp"

namespace ballbar::storage {

inline constexpr std::string_view kDiscoveryResultKind = "discovery";

/// What the stored result holds besides the printed one: the inputs' names and the model version made.
struct DiscoveryStored {
    std::vector<std::string> inputs;
    std::string model_name;
    std::int64_t model_id = 0;
    int model_version = 0;
};

/// The result as `discover --json` prints it (docs/cli.md's vocabulary).
std::string discovery_to_json(const analysis::DiscoveryResult& result);
/// The result as it is stored: the printed one, "details" (the criterion, the final model, the learned
/// terms, the residual trends before and after, each step's own trend) and "model".
std::string discovery_to_json(const analysis::DiscoveryResult& result, const DiscoveryStored& stored);

/// A binned residual trend against one variable.
struct DiscoveryTrend {
    std::string variable;
    std::vector<double> x;                    ///< bin centres, in the variable's stored unit (NaN: an empty bin)
    std::vector<double> before_um, after_um;  ///< a step's trend: before and after it; a run's: before only
    std::optional<std::string> x_unit;        ///< a learned step's own display units (then y_label, y_unit too)
    std::string y_label, y_unit;
};

/// One step of the search: a library effect added, or a term learned.
struct DiscoveryStepRecord {
    std::string effect, iso;
    std::string kind;  ///< "library", "empirical", or "" (older results)
    std::string unit;  ///< of value, as the analysis writes units (mm, rad, mm_per_mm, …)
    std::optional<double> value, value_std;
    std::optional<double> rms_before_um, rms_after_um;
    std::optional<bool> accepted;  ///< false: withdrawn once the learned terms were in
    std::string explained_by;      ///< the variable that explains it
    std::string where;             ///< a learned step: where it acts
    std::string note;
    /// An older producer's per-reading residuals against the variable, before and after the step.
    bool per_reading = false;
    std::string variable, variable_unit;
    std::vector<double> x, before_um, after_um;
};

/// A verdict on the residual against the noise floor.
struct DiscoveryVerdict {
    std::string result;
    std::optional<double> rms_um, ratio, chi2, dof, p_value;
};

struct DiscoveryRecord {
    std::vector<DiscoveryStepRecord> steps;
    std::optional<double> rms_initial_um, rms_final_um;
    std::optional<double> noise_floor_um;
    std::optional<std::string> noise_source;  ///< where the floor came from; absent (null) when the result does not say
    std::optional<DiscoveryVerdict> verdict_before_search, verdict;
    std::string unlocated;
    std::vector<DiscoveryTrend> step_trends;  ///< one per step, in the steps' order (details.step_trends)
    std::vector<DiscoveryTrend> residuals_initial, residuals_final;  ///< bin_mean_um in before_um
    std::string model_name;
    std::optional<int> model_version;
};

/// Reads a stored (or printed) discovery result. FormatError naming the key for one that is not: not
/// JSON, no list of steps, a number or text where the other is.
DiscoveryRecord discovery_from_json(std::string_view text);

}  // namespace ballbar::storage
