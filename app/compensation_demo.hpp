// SPDX-License-Identifier: MIT
// `ballbar demo --compensate`'s printing: the compensation proof (workflow/compensation_demo.hpp) as text
// or as the JSON object of docs/compensation.md.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "ballbar/workflow/compensation_demo.hpp"

namespace ballbar::app {

/// The demo's report for the operator.
std::string compensation_demo_text(const workflow::CompensationDemo& demo, double noise_um);

/// The demo's JSON object (docs/cli.md's vocabulary).
nlohmann::ordered_json compensation_demo_json(const workflow::CompensationDemo& demo,
                                              const workflow::CompensationDemoOptions& options);

}  // namespace ballbar::app
