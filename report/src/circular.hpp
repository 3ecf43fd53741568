// SPDX-License-Identifier: MIT
// The circular test's content: the stored result (kind "circular") into CircularTest, the runs' polar
// plot points from the trace's samples, and the pages that show them.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <span>
#include <string_view>

#include "ballbar/report/report.hpp"
#include "document.hpp"

namespace ballbar::report {

/// A "circular" result payload (what `circle analyze --json` prints) into `report.circular`, replacing
/// any earlier one. Throws ReportError naming the key when the payload is malformed.
void add_circular(Report& report, std::string_view kind, const nlohmann::json& payload);

/// One bar sample of a circular trace (time s, bar length mm).
struct CircularSample {
    double time_s = 0, measured_mm = 0;
};

/// Fills each run's polar plot: the samples of its data arc at the axes' angle (the commanded angle
/// less the feed-ins' mean lag phase), their radial deviation from one least-squares circle fitted to
/// every run's data (centre and radius removed, as for G(b)), reduced to min/max per angle column.
/// Also sets the plot's half range `plot_deviation_um`.
void circular_polar(CircularTest& test, std::span<const CircularSample> samples, std::size_t columns);

/// The plot's half range: a 1-2-5 step at or above the largest |deviation| and half the tolerance.
double circular_plot_range(const CircularTest& test);

/// The circular test's sections: conditions, ISO figures against the tolerance, polar plot,
/// ranked diagnostics, unseparable effects.
void circular_sections(Document& doc, const Report& report);

}  // namespace ballbar::report
