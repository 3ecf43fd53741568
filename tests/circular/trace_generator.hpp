// SPDX-License-Identifier: MIT
// An independent generator of ballbar-trace/1 circular tests, written from the format's text alone
// (docs/formats/trace.md): it simulates the part program's motion of two linear axes through their
// first-order servo lags, applies every effect of the format's table to the axes as the table
// defines it, measures the bar length to a misplaced socket, adds noise, and works out the true
// ISO 230-4 figures from the true positions by its own circle fit. It shares no code with the
// project's emulator or analysis (it does not even use Eigen).
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace ballbar::testgen {

struct GenRun {
    bool ccw = true;
    double start_deg = 0.0, overshoot_deg = 45.0, data_arc_deg = 360.0;
};

struct GenSpec {
    int plane = 0;  ///< 0 XY, 1 YZ, 2 ZX
    double radius_mm = 100.0;
    std::array<double, 3> centre_mm{0.0, 0.0, 0.0};
    double feed_mm_min = 1000.0;
    double feed_in_mm = 1.5;
    std::vector<GenRun> runs;
    double sample_hz = 1000.0;
    double noise_um = 0.2;
};

/// The machine's effects, p and q as the plane's first and second axis. Zero: absent.
struct GenEffects {
    std::array<double, 2> backlash_um{0, 0};
    std::array<double, 2> spike_um{0, 0};
    double squareness_um_per_m = 0.0;
    std::array<double, 2> scale_ppm{0, 0};  ///< s_p, s_q
    std::array<double, 2> lag_ms{10, 10};   ///< τ_p, τ_q
    std::array<double, 2> cyclic_um{0, 0};
    std::array<double, 2> pitch_mm{5, 5};
    std::array<double, 2> cyclic_phase{0, 0};
    std::array<double, 2> straightness_um{0, 0};  ///< k·R² of p's motion bowing in q, and q's in p
    double vibration_um = 0.0, vibration_hz = 20.0, vibration_phase = 0.0;
    std::array<double, 3> socket_offset_um{0, 0, 0};  ///< socket − programmed centre (X, Y, Z)
};

struct GenTrace {
    std::vector<double> time_s, measured_mm;
    std::vector<double> g_um;  ///< true G of each run
    double gb_um = 0.0;        ///< true G(b) over all runs
    double h_um = -1.0;        ///< true H between the first run of each direction; −1: one direction only
    double f_max_um = 0.0, f_min_um = 0.0;
};

const char* plane_text(int plane);
GenTrace generate(const GenSpec& spec, const GenEffects& fx, std::mt19937_64& rng);
/// The trace as a ballbar-trace/1 file.
std::string to_file(const GenSpec& spec, const GenTrace& trace);

/// A random test: plane, radius 50–150 mm, feed 500–2000 mm/min, noise 0.1–0.25 µm, full circle or
/// 180° partial arc, both directions; each effect present with probability `p_effect`.
struct GenCase {
    GenSpec spec;
    GenEffects fx;
    /// bl p, bl q, spike p, spike q, square, scale, servo, cyc p, cyc q, str p, str q, vib
    std::array<bool, 12> present{};
};
GenCase random_case(std::mt19937_64& rng, double p_effect = 0.35);

}  // namespace ballbar::testgen
