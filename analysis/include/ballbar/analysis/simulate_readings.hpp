// SPDX-License-Identifier: MIT
// Synthetic readings for tests and benchmarks: an SSM-like plan (locations = a socket position and a
// rotary angle pair; at each, the tool ball visits one point above the socket and six on the 54.74°
// cone around it), a session timeline with a drifting bar temperature, and a machine with error
// parameters, socket set-up offsets and reading noise — all through predicted_reading().
// Deterministic for a given generator state.
#pragma once

#include <random>
#include <span>
#include <vector>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/reading.hpp"

namespace ballbar::analysis {

struct SimulationPlan {
    MachineGeometry machine;
    double bar_length_mm = 100.0;
    std::vector<Vec3> sockets_mm;                   ///< nominal socket places (table frame)
    std::vector<std::pair<double, double>> rotary;  ///< (first, second) rotary angles, rad
    double seconds_per_reading = 12.0;              ///< session timeline
};

/// A plan for the type: the seed-like geometry, three socket positions and 12 rotary pairs
/// (7 points each: 252 readings, about 50 minutes of session).
SimulationPlan default_plan(MachineType type);

/// What the simulated machine and room do.
struct SimulatedMachine {
    ErrorParams errors;                   ///< the truth
    std::vector<Vec3> socket_offsets_mm;  ///< set-up offset of each socket of the plan (table frame)
    double noise_mm = 0.0005;             ///< standard deviation of a reading's noise
    double bar_temp_start_C = 20.5;       ///< bar temperature at t = 0
    double bar_temp_drift_K_per_h = 1.0;  ///< slow drift
    double bar_temp_wave_K = 0.4;         ///< amplitude of the room's cycle
    double bar_temp_period_s = 1500.0;    ///< period of the room's cycle
};

/// Readings of the plan on the machine. `repeat` runs the plan that many times in one session.
ReadingSet simulate_readings(const SimulationPlan& plan, const SimulatedMachine& machine, std::mt19937_64& rng,
                             int repeat = 1);

/// A machine with random base errors (the type's rotary location errors and zero offsets, socket
/// set-up offsets) of typical size, and nothing else.
SimulatedMachine random_base_machine(const SimulationPlan& plan, std::mt19937_64& rng);

/// A typical, clearly visible size of the parameter's effect, with a random sign (e.g. 5–20 µm of
/// bar length offset, 20–60 µm/m of scale).
double random_effect_value(Param p, std::mt19937_64& rng);

}  // namespace ballbar::analysis
