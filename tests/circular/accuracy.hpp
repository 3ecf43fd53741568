// SPDX-License-Identifier: MIT
// Judging an analysis against the independent generator's truth (shared by the ctest campaign and
// bench/circular). The acceptance rule: an injected diagnostic within 20 % or the equivalent of
// 0.25 µm radial amplitude (whichever is larger), pitch and frequency within 5 %, nothing reported
// above twice that where nothing was injected; G and G(b) within 0.5 µm.
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "ballbar/analysis/circular.hpp"
#include "trace_generator.hpp"

namespace ballbar::testgen {

namespace circ = ballbar::analysis::circular;

inline circ::TestSpec to_test(const GenSpec& s) {
    circ::TestSpec t;
    t.plane = s.plane == 0 ? circ::Plane::XY : s.plane == 1 ? circ::Plane::YZ : circ::Plane::ZX;
    t.radius_mm = s.radius_mm;
    t.centre_mm = s.centre_mm;
    t.feed_mm_min = s.feed_mm_min;
    t.feed_in_mm = s.feed_in_mm;
    for (const auto& r : s.runs)
        t.runs.push_back(
            {r.ccw ? circ::Direction::Ccw : circ::Direction::Cw, r.start_deg, r.overshoot_deg, r.data_arc_deg});
    return t;
}

inline std::vector<circ::TraceSample> to_samples(const GenTrace& g) {
    std::vector<circ::TraceSample> out(g.time_s.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = {g.time_s[i], g.measured_mm[i]};
    return out;
}

struct Check {
    std::string name;  ///< diagnostic key family (plane-independent): backlash_p, ..., G, G(b)
    bool injected = false;
    double truth = 0.0, estimate = 0.0, error = 0.0, tolerance = 0.0;
    bool pass = false;
};

/// Radial µm per unit of each amplitude diagnostic, from the format's definitions.
inline double radial_per_unit(int family, const GenSpec& s) {
    switch (family) {
        case 0:
        case 1:
            return 0.5;  // backlash: steps of ±b/2
        case 4:
        case 5:
            return s.radius_mm * 1e-3 / 2.0;  // squareness, scale: R/2 per 1e-6
        case 6:
            return s.feed_mm_min / 60.0 / 2.0;  // servo: v/2 µm per ms
        case 9:
        case 10:
            return 2.0 / (3.0 * std::sqrt(3.0));
        default:
            return 1.0;  // spikes, cyclic, vibration
    }
}

inline std::vector<Check> judge(const GenCase& c, const GenTrace& truth, const circ::CircularResult& r) {
    using circ::Diag;
    const Diag diags[12] = {Diag::BacklashP,  Diag::BacklashQ,     Diag::SpikeP,        Diag::SpikeQ,
                            Diag::Squareness, Diag::ScaleMismatch, Diag::ServoMismatch, Diag::CyclicP,
                            Diag::CyclicQ,    Diag::StraightnessP, Diag::StraightnessQ, Diag::Vibration};
    const char* names[12] = {"backlash_p",     "backlash_q",     "reversal_spike_p", "reversal_spike_q",
                             "squareness",     "scale_mismatch", "servo_mismatch",   "cyclic_error_p",
                             "cyclic_error_q", "straightness_p", "straightness_q",   "vibration"};
    const GenEffects& f = c.fx;
    const double truths[12] = {f.backlash_um[0],
                               f.backlash_um[1],
                               f.spike_um[0],
                               f.spike_um[1],
                               f.squareness_um_per_m,
                               f.scale_ppm[0] - f.scale_ppm[1],
                               f.lag_ms[0] - f.lag_ms[1],
                               f.cyclic_um[0],
                               f.cyclic_um[1],
                               f.straightness_um[0],
                               f.straightness_um[1],
                               f.vibration_um};
    std::vector<Check> out;
    for (int i = 0; i < 12; ++i) {
        Check k;
        k.name = names[i];
        k.injected = c.present[static_cast<std::size_t>(i)];
        k.truth = k.injected ? truths[i] : 0.0;
        const auto* d = r.find(diags[i]);
        const double floor = 0.25 / radial_per_unit(i, c.spec);
        if (!d) {  // not reported as separable
            k.estimate = NAN, k.error = INFINITY, k.tolerance = floor, k.pass = false;
            out.push_back(k);
            continue;
        }
        k.estimate = d->detected ? d->value : 0.0;
        k.error = std::abs(k.estimate - k.truth);
        k.tolerance = k.injected ? std::max(0.2 * std::abs(k.truth), floor) : 2.0 * floor;
        k.pass = k.error <= k.tolerance;
        out.push_back(k);
    }
    auto period = [&](const char* name, Diag diag, bool injected, double t) {
        if (!injected) return;
        Check k;
        k.name = name;
        k.injected = true;
        k.truth = t;
        const auto* d = r.find(diag);
        k.estimate = d ? d->value : NAN;
        k.error = d ? std::abs(d->value - t) : INFINITY;
        k.tolerance = 0.05 * t;
        k.pass = k.error <= k.tolerance;
        out.push_back(k);
    };
    period("cyclic_pitch_p", Diag::CyclicPitchP, c.present[7], f.pitch_mm[0]);
    period("cyclic_pitch_q", Diag::CyclicPitchQ, c.present[8], f.pitch_mm[1]);
    period("vibration_hz", Diag::VibrationHz, c.present[11], f.vibration_hz);
    for (std::size_t k = 0; k < truth.g_um.size() && k < r.runs.size(); ++k) {
        Check g;
        g.name = "G";
        g.injected = true;
        g.truth = truth.g_um[k], g.estimate = r.runs[k].circularity_um;
        g.error = std::abs(g.estimate - g.truth), g.tolerance = 0.5, g.pass = g.error <= 0.5;
        out.push_back(g);
    }
    auto figure = [&](const char* name, double t, std::optional<double> estimate) {  // within 0.5 µm
        Check k;
        k.name = name;
        k.injected = true;
        k.truth = t, k.estimate = estimate.value_or(NAN);
        k.error = std::abs(k.estimate - k.truth), k.tolerance = 0.5, k.pass = k.error <= 0.5;
        out.push_back(k);
    };
    figure("G(b)", truth.gb_um, r.bidirectional_um);
    if (truth.h_um >= 0) figure("H", truth.h_um, r.hysteresis_um);
    return out;
}

}  // namespace ballbar::testgen
