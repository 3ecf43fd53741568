// SPDX-License-Identifier: MIT
#include "ballbar/analysis/simulate_readings.hpp"

#include <cmath>

#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::analysis {
namespace {

/// Bar directions of one location: one along +Z, six on the 54.74° cone around it (the seed-math
/// layouts: mutually near-orthogonal directions condition the socket's position best).
std::vector<Vec3> location_directions() {
    std::vector<Vec3> dirs{Vec3::UnitZ()};
    const double cone = std::acos(1.0 / std::sqrt(3.0));
    for (int k = 0; k < 6; ++k) {
        const double az = kPi / 3.0 * k;
        dirs.emplace_back(std::sin(cone) * std::cos(az), std::sin(cone) * std::sin(az), std::cos(cone));
    }
    return dirs;
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
}

double random_sign(std::mt19937_64& rng) {
    return std::bernoulli_distribution(0.5)(rng) ? 1.0 : -1.0;
}

}  // namespace

SimulationPlan default_plan(MachineType type) {
    SimulationPlan plan;
    plan.machine.type = type;
    plan.machine.name = std::string("simulated-") + std::string(to_string(type));
    const double d = deg_to_rad(1.0);
    switch (type) {
        case MachineType::TTTRR:
            plan.machine.a_pivot_mm = Vec3(0, 0, 0);
            plan.machine.c_offset_mm = Vec3(0, 0, -100);
            plan.machine.tool_ball_mm = Vec3(0, 0, 0);
            plan.sockets_mm = {Vec3(120, 0, 40), Vec3(-60, 100, 40), Vec3(-60, -100, 70)};
            plan.rotary = {{0, 0},
                           {0, 90 * d},
                           {0, 180 * d},
                           {0, 270 * d},
                           {30 * d, 0},
                           {30 * d, 120 * d},
                           {30 * d, 240 * d},
                           {-30 * d, 60 * d},
                           {-30 * d, 200 * d},
                           {60 * d, 45 * d},
                           {60 * d, 225 * d},
                           {-60 * d, 300 * d}};
            break;
        case MachineType::RRTTT:
            plan.machine.tool_ball_mm = Vec3(0, 0, -150);
            plan.sockets_mm = {Vec3(0, 0, -400), Vec3(150, 100, -420), Vec3(-150, -80, -380)};
            plan.rotary = {{0, 0},
                           {20 * d, 0},
                           {-20 * d, 0},
                           {0, 20 * d},
                           {0, -20 * d},
                           {30 * d, 30 * d},
                           {-30 * d, 30 * d},
                           {30 * d, -30 * d},
                           {-30 * d, -30 * d},
                           {45 * d, 10 * d},
                           {-10 * d, 45 * d},
                           {10 * d, -45 * d}};
            break;
        case MachineType::RTTTR:
            plan.machine.tool_ball_mm = Vec3(0, 0, -150);
            plan.machine.a_pivot_mm = Vec3(0, 0, 0);
            plan.sockets_mm = {Vec3(0, 120, 40), Vec3(100, -60, 40), Vec3(-100, -60, 70)};
            // (first, second) = (A table, B spindle).
            plan.rotary = {
                {0, 0},           {30 * d, 0},       {-30 * d, 0},       {60 * d, 0},       {0, 30 * d},
                {0, -30 * d},     {30 * d, 30 * d},  {-30 * d, -30 * d}, {45 * d, -20 * d}, {-45 * d, 20 * d},
                {15 * d, 45 * d}, {-60 * d, -15 * d}};
            break;
    }
    return plan;
}

ReadingSet simulate_readings(const SimulationPlan& plan, const SimulatedMachine& machine, std::mt19937_64& rng,
                             int repeat) {
    if (machine.socket_offsets_mm.size() != plan.sockets_mm.size())
        throw AnalysisError("simulation: one socket offset per socket of the plan is needed");
    ReadingSet out;
    out.machine = plan.machine;
    const std::vector<Vec3> dirs = location_directions();
    std::normal_distribution<double> noise(0.0, machine.noise_mm);
    const RotaryAxes axes = rotary_axes(plan.machine.type);
    double t = 0;
    int location = 0;
    for (int pass = 0; pass < repeat; ++pass) {
        for (const auto& [first, second] : plan.rotary) {
            for (std::size_t k = 0; k < plan.sockets_mm.size(); ++k, ++location) {
                Pose rot;
                rot.A_rad = first;
                (axes.second == 'C' ? rot.C_rad : rot.B_rad) = second;
                const Vec3& socket = plan.sockets_mm[k];
                const Vec3 s = nominal_table_ball(plan.machine, rot, socket);
                const Vec3 actual_socket = socket + machine.socket_offsets_mm[k];
                for (std::size_t i = 0; i < dirs.size(); ++i) {
                    Reading r;
                    r.pose = command_for_tool_ball(plan.machine, rot, s + plan.bar_length_mm * dirs[i]);
                    r.socket_mm = socket;
                    r.time_s = t;
                    const double temp = machine.bar_temp_start_C + machine.bar_temp_drift_K_per_h * t / 3600.0 +
                                        machine.bar_temp_wave_K * std::sin(2.0 * kPi * t / machine.bar_temp_period_s);
                    r.bar_temp_C = temp;
                    r.location = location;
                    r.point = static_cast<int>(i);
                    r.measured_mm = predicted_reading(plan.machine, machine.errors, r.pose, actual_socket,
                                                      ReadingConditions{t, temp}) +
                                    noise(rng);
                    out.readings.push_back(r);
                    t += plan.seconds_per_reading;
                }
            }
        }
    }
    return out;
}

SimulatedMachine random_base_machine(const SimulationPlan& plan, std::mt19937_64& rng) {
    SimulatedMachine m;
    for (Param p : rotary_params_for(plan.machine.type)) {
        const ParamUnit unit = param_info(p).unit;
        // Location errors of tens of µm and tens of µrad, as the second seed found them.
        m.errors[p] = unit == ParamUnit::mm ? uniform(rng, -0.05, 0.05) : uniform(rng, -100e-6, 100e-6);
    }
    for (std::size_t k = 0; k < plan.sockets_mm.size(); ++k)
        m.socket_offsets_mm.emplace_back(uniform(rng, -0.03, 0.03), uniform(rng, -0.03, 0.03),
                                         uniform(rng, -0.03, 0.03));
    m.bar_temp_start_C = uniform(rng, 19.5, 21.5);
    m.bar_temp_drift_K_per_h = uniform(rng, -1.5, 1.5);
    m.bar_temp_wave_K = uniform(rng, 0.3, 0.8);
    return m;
}

double random_effect_value(Param p, std::mt19937_64& rng) {
    using enum Param;
    const double s = random_sign(rng);
    switch (p) {
        case bar_length:
            return s * uniform(rng, 0.005, 0.020);
        case bar_kappa:
            return s * uniform(rng, 10e-6, 30e-6);
        case spindle_growth:
            return s * uniform(rng, 0.010, 0.030);
        case EXX:
        case EYY:
        case EZZ:
            return s * uniform(rng, 40e-6, 100e-6);
        case C0Y:
        case B0Z:
        case A0Z:
            return s * uniform(rng, 40e-6, 100e-6);
        case tool_length:
            return s * uniform(rng, 0.010, 0.050);
        default:
            break;
    }
    return param_info(p).unit == ParamUnit::mm ? s * uniform(rng, 0.010, 0.050) : s * uniform(rng, 40e-6, 100e-6);
}

}  // namespace ballbar::analysis
