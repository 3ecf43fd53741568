// SPDX-License-Identifier: MIT
// The NC program that drives the machine through a plan (or through some of its points: a retry): G90,
// a rapid to the first point and a program stop (M0) to mount the bar, then for every point feed moves
// that keep the bar inside its ±1 mm range (the tool ball follows the sphere around the datum ball in
// short G1 segments, the rotary axes turning with it), the point's code (point_code.hpp: short dwells
// at tag lengths along the bar's axis) and the measuring G4 dwell. A new socket position gets a program
// stop to remove the bar, a rapid, and a program stop to mount it again.
//
// The writer also returns the program's timing model (`ProgramEntry`): what comes before each
// measuring dwell, so the acquisition knows how long to wait for each point (docs/procedure.md).
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ballbar/acquisition/plan.hpp"
#include "ballbar/acquisition/point_code.hpp"
#include "ballbar/analysis/nc_program.hpp"

namespace ballbar::acquisition {

struct NcOptions {
    double max_arc_step_rad = 0.0873;     ///< 5°: chord sag 0.095 mm on a 100 mm bar
    double max_rotary_step_rad = 0.0349;  ///< 2° of a rotary axis per G1 segment
    PointCodeSpec code;
};

/// A program stop (M0) and what the operator does there.
struct ProgramStop {
    std::string what;
    /// Set when the operator moves the socket here (table frame) at this stop.
    std::optional<analysis::Vec3> socket_mm;
};

/// One measuring dwell of a program and what the machine does before it.
struct ProgramEntry {
    std::size_t point = 0;                  ///< index into Plan::points
    std::vector<ProgramStop> stops_before;  ///< program stops before this point's approach
    double feed_s = 0;                      ///< G1 time before the dwell (approach and code) at 100 % feed override
    double rapid_mm = 0;                    ///< G0 distance before it (linear axes)
    double dwell_s = 0;                     ///< G4 time before it (code tags) plus the measuring dwell
};

struct MeasuringProgram {
    analysis::NcProgram nc;
    std::vector<ProgramEntry> entries;  ///< in program order
};

/// The program for `points` (plan indices, visited in the order given). Throws PlanError when an
/// intermediate pose leaves the travel or `points` is empty.
MeasuringProgram make_measuring_program(const Plan& plan, std::span<const std::size_t> points,
                                        const NcOptions& options = {});

/// The plan's points from `from_point` on.
std::vector<std::size_t> points_from(const Plan& plan, std::size_t from_point);

/// The program for the plan's points from `from_point` on (--dry-run --from-point).
analysis::NcProgram make_nc_program(const Plan& plan, std::size_t from_point = 0, const NcOptions& options = {});

/// The program's text in the machine's dialect.
std::string write_plan_program(const Plan& plan, std::size_t from_point = 0);
std::string write_program(const Plan& plan, std::span<const std::size_t> points);

/// Is this block a program stop (M0/M00/M1/M01)?
bool is_program_stop(const analysis::NcBlock& block);

}  // namespace ballbar::acquisition
