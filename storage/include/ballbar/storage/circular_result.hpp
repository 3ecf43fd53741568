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

/// The result as one JSON object (text): test, runs[] (direction, circularity_um, radial_deviation_um,
/// feed-in and data-arc times), bidirectional_circularity_um, radial_deviation_um, diagnostics with
/// uncertainties, shares and ranking, unseparable groups, residual RMS, mean radius, the test
/// conditions (from the trace: temperatures, instrument) and, with a tolerance, its verdict on G.
std::string circular_result_json(const analysis::circular::CircularResult& result, const TraceFile& trace,
                                 std::optional<double> tolerance_um);

}  // namespace ballbar::storage
