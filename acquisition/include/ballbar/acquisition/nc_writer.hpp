// SPDX-License-Identifier: MIT
// The NC program that drives the machine through a plan: G90, a rapid to the first point, then feed
// moves that keep the bar inside its ±1 mm range (the tool ball follows the sphere around the datum
// ball in short G1 segments, the rotary axes turning with it) and a G4 dwell at every point.
#pragma once

#include <cstddef>

#include "ballbar/acquisition/plan.hpp"
#include "ballbar/analysis/nc_program.hpp"

namespace ballbar::acquisition {

struct NcOptions {
    double max_arc_step_rad = 0.0873;     ///< 5°: chord sag 0.095 mm on a 100 mm bar
    double max_rotary_step_rad = 0.0349;  ///< 2° of a rotary axis per G1 segment
};

/// The program for the plan's points from `from_point` on (a resumed session starts where it stopped).
/// Throws PlanError when an intermediate pose leaves the travel.
analysis::NcProgram make_nc_program(const Plan& plan, std::size_t from_point = 0, const NcOptions& options = {});

/// The program's text in the machine's dialect.
std::string write_plan_program(const Plan& plan, std::size_t from_point = 0);

}  // namespace ballbar::acquisition
