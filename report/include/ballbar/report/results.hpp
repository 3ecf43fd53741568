// SPDX-License-Identifier: MIT
// Stored analysis results (kind + JSON payload, as the results table holds them) into report content.
// The kinds and payload keys are listed in docs/report.md; unknown keys are ignored, so producers can
// add fields without breaking reports.
#pragma once

#include <nlohmann/json.hpp>
#include <string_view>

#include "ballbar/report/report.hpp"

namespace ballbar::report {

/// Adds one result to `report` (its machine type must be set: it decides which angles a test has).
/// Returns false for a kind the report does not show. Throws ReportError naming the kind and the key
/// when a payload of a known kind is malformed.
bool add_result(Report& report, std::string_view kind, const nlohmann::json& payload);

/// Known kinds: "ssm" (ΔV of one location), "orientation" (the angle errors of one test),
/// "identification" (an identified model), "discovery" (the steps of the discovery workflow),
/// "compensation" (before/after per axis), "procedure" (one step of the guided procedure), "circular"
/// (the result of `circle analyze --store`).
bool is_known_result_kind(std::string_view kind);

}  // namespace ballbar::report
