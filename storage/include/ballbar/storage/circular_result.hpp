// SPDX-License-Identifier: MIT
// The stored result of a circular test (results table, kind "circular", format "ballbar circular/1"):
// the JSON that `circle analyze --json` prints and `--store` keeps with the session, and that the
// session report reads back (docs/circular.md, docs/report.md).
#pragma once

#include <optional>
#include <string>

#include "ballbar/analysis/circular.hpp"
#include "ballbar/storage/trace_file.hpp"

namespace ballbar::storage {

/// The result as one JSON object (text), in docs/cli.md's vocabulary: test, runs[] (direction,
/// circularity_um, radial_deviation_um, feed-in and data-arc times), bidirectional_circularity_um,
/// radial_deviation_um, diagnostics[] ({key, unit, value, value_std, share_percent, rank}, ranked first),
/// not_detected, unseparable groups, residual RMS, mean radius, the test conditions (from the trace:
/// temperatures, instrument) and the tolerance's verdict on G (null without a tolerance). Results
/// stored before the vocabulary hold the diagnostics as maps (diagnostics, uncertainties,
/// shares_percent, ranking); the report reads both.
std::string circular_result_json(const analysis::circular::CircularResult& result, const TraceFile& trace,
                                 std::optional<double> tolerance_um);

}  // namespace ballbar::storage
