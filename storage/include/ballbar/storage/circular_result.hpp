// SPDX-License-Identifier: MIT
// The stored result of a circular test (results table, kind "circular", format "ballbar circular/1"):
// the JSON that `circle analyze --json` prints and `--store` keeps with the session, and that the
// session report reads back (docs/circular.md, docs/report.md).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/circular.hpp"
#include "ballbar/storage/trace_file.hpp"

namespace ballbar::storage {

/// The result as one JSON object (text), in docs/cli.md's vocabulary: test, runs[] (direction,
/// circularity_um, radial_deviation_um, feed-in and data-arc times, the diagnosed model's curve),
/// bidirectional_circularity_um, hysteresis_um, radial_deviation_um, diagnostics[] ({key, unit, value, value_std,
/// share_percent, rank}, ranked first), not_detected, unseparable groups, residual RMS, mean radius, the test
/// conditions (from the trace: temperatures, instrument) and the tolerance's verdict on G (null without a tolerance).
/// Results stored before the vocabulary hold the diagnostics as maps (diagnostics, uncertainties, shares_percent,
/// ranking); the report reads both.
std::string circular_result_json(const analysis::circular::CircularResult& result, const TraceFile& trace,
                                 std::optional<double> tolerance_um);

/// One run of a stored result.
struct StoredCircularRun {
    std::string direction;                                        ///< "ccw" or "cw"
    double start_deg = 0, overshoot_deg = 0, data_arc_deg = 360;  ///< the test header's run
    double circularity_um = 0;                                    ///< G
    std::optional<double> radial_max_um, radial_min_um;
    std::optional<double> feed_in_end_s, feed_in_lag_ms, data_start_s, data_end_s, samples;
    /// The diagnosed model's curve (analysis's RunResult::model_*); empty in results stored before it.
    std::vector<double> model_arc_deg, model_deviation_um;
};

/// One diagnostic of a stored result, in the stored order (ranked ones first).
struct StoredCircularDiagnostic {
    std::string key;  ///< e.g. "backlash_x_um": the unit is the key's suffix
    double value = 0;
    std::optional<double> value_std, share_percent;
    std::optional<int> rank;  ///< 1 = largest share; none: not ranked (a pitch, a frequency)
};

/// Effects the test cannot tell apart, and their combined value.
struct StoredUnseparable {
    std::vector<std::string> keys;
    std::string reason, combined_key;
    std::optional<double> combined_value, combined_value_std;
};

/// A stored circular result, typed: what circular_result_json writes, and what it wrote before docs/cli.md's
/// vocabulary (the diagnostics as maps with a ranking; the mean radius and combined values as objects).
struct CircularRecord {
    std::string plane;  ///< "XY", "YZ", "ZX"
    double radius_mm = 0, feed_mm_min = 0, feed_in_mm = 0;
    std::array<double, 3> centre_mm{};
    std::vector<StoredCircularRun> runs;
    std::optional<double> bidirectional_um;  ///< G(b)
    std::optional<double> hysteresis_um;     ///< H (ISO 230-4); empty: one direction, or stored before H
    std::optional<double> radial_max_um, radial_min_um;
    std::vector<StoredCircularDiagnostic> diagnostics;
    std::vector<std::string> not_detected;
    std::vector<StoredUnseparable> unseparable;
    std::optional<double> residual_rms_um, mean_radius_um, mean_radius_um_std;
    std::optional<double> sample_rate_hz, samples_used;
    std::optional<double> bar_temp_min_C, bar_temp_max_C, air_temp_min_C, air_temp_max_C;
    std::string instrument;              ///< the trace's instrument header, as text
    std::optional<double> tolerance_um;  ///< the G allowed when it was analysed
};

/// Reads a stored result. FormatError naming the key ("runs[1].circularity_um is missing") for a
/// payload that is not a circular result: not JSON, no runs, a number that is not one.
CircularRecord circular_result_from_json(std::string_view text);

}  // namespace ballbar::storage
