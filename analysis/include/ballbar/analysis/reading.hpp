// SPDX-License-Identifier: MIT
// A reading: one averaged bar length at one commanded pose, with its set-up. One row of the
// `ballbar-readings/1` interchange file; the input of SSM, identification and discovery.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

struct Reading {
    Pose pose;                      ///< commanded axes (rotary in radians)
    Vec3 socket_mm = Vec3::Zero();  ///< table-ball centre in the table frame (nominal place)
    double measured_mm = 0;         ///< measured bar length, centre to centre
    double time_s = 0;              ///< since the session started
    std::optional<double> bar_temp_C, air_temp_C, machine_temp_C;
    int location = -1;             ///< SSM location (readings of one location share one total position error); -1: none
    int point = -1;                ///< index of the point within its location
    int step = 0;                  ///< SSM step: 1 after the translations, 2 after the rotations; 0: not given
    int n = 0;                     ///< samples averaged into the reading (0: not given)
    std::optional<double> std_mm;  ///< standard deviation of those samples
};

/// Readings of one machine, as a readings file or a session holds them.
struct ReadingSet {
    MachineGeometry machine;
    std::vector<Reading> readings;
};

}  // namespace ballbar::analysis
