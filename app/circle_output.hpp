// SPDX-License-Identifier: MIT
// What `circle analyze` prints: the result as text and JSON, the volumetric summary, and the
// measured backlash and scale in a controller's own terms (docs/circular.md, "Back to the controller").
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>

#include "ballbar/analysis/circular.hpp"
#include "ballbar/storage/trace_file.hpp"

namespace ballbar::app {

nlohmann::ordered_json circle_result_json(const analysis::circular::CircularResult& r, const storage::TraceFile& trace,
                                          std::optional<double> tolerance_um);
void print_circle_result(std::ostream& os, const analysis::circular::CircularResult& r, const storage::TraceFile& trace,
                         std::optional<double> tolerance_um);
nlohmann::ordered_json volumetric_json(const analysis::circular::VolumetricResult& v);
void print_volumetric(std::ostream& os, const analysis::circular::VolumetricResult& v);
/// controller: linuxcnc, marlin, smoothieware, grblhal.
nlohmann::ordered_json controller_json(const analysis::circular::CircularResult& r, const std::string& controller);
void print_controller(std::ostream& os, const analysis::circular::CircularResult& r, const std::string& controller);

}  // namespace ballbar::app
