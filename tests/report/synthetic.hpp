// SPDX-License-Identifier: MIT
// Synthetic report content for tests and the benchmark: a plausible SSM session of each machine type
// (dwell plateaus with noise, moves between them, capture windows, position and orientation errors,
// an identified model, discovery steps and compensation). Deterministic for a seed.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/report/decimate.hpp"
#include "ballbar/report/report.hpp"

namespace ballbar::report::testing {

inline analysis::MachineGeometry synthetic_machine(analysis::MachineType type) {
    analysis::MachineGeometry m;
    m.type = type;
    switch (type) {
        case analysis::MachineType::RRTTT:
            m.name = "Head-head HX-5";
            m.tool_ball_mm = {0, 0, -250};
            break;
        case analysis::MachineType::TTTRR:
            m.name = "DL-5X trunnion";
            m.c_offset_mm = {0, 0, -100};
            break;
        case analysis::MachineType::RTTTR:
            m.name = "Mixed MX-400";
            m.tool_ball_mm = {0, 0, -180};
            m.a_pivot_mm = {0, 0, -50};
            break;
    }
    return m;
}

/// A session of `samples` bar samples at 1 kHz over `points` dwell points split across `locations`.
inline Report synthetic_report(analysis::MachineType type, std::uint64_t samples = 200000, std::uint64_t seed = 1,
                               int locations = 4, int points_per_location = 6) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, 0.25);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    Report r;
    Header& h = r.header;
    h.session_id = static_cast<std::int64_t>(seed % 1000) + 7;
    h.session_name = "acceptance " + std::string(analysis::to_string(type));
    h.status = "completed";
    h.started_at = "2026-11-21T09:14:03Z";
    h.finished_at = "2026-11-21T09:31:40Z";
    h.machine = synthetic_machine(type);
    h.instrument_model = "BB-100";
    h.instrument_serial = "SN-0042";
    h.instrument_calibration_date = "2026-06-30";
    h.calibrated_length_mm = 100.0;
    h.operator_name = "J. Operator";
    h.bar_temp_C = {20.12, 20.31, 20.47};
    h.machine_temp_C = {21.0, 21.4, 21.9};
    h.software_version = "0.1.0";

    // Trace: per point a move (ramp), a dwell plateau (captured), and so on; 1 kHz samples.
    const int points = locations * points_per_location;
    const double dt = 1e-3, total_s = static_cast<double>(samples) * dt;
    const double slot = total_s / points;
    MinMaxDecimator dec(0, total_s, 2000);
    double level = 0, lo = 1e300, hi = -1e300;
    std::vector<double> plateau(static_cast<std::size_t>(points));
    for (auto& p : plateau) p = 40 * uni(rng);
    for (std::uint64_t i = 0; i < samples; ++i) {
        const double t = static_cast<double>(i) * dt;
        const auto k = std::min(points - 1, static_cast<int>(t / slot));
        const double phase = (t - k * slot) / slot;
        const double target = plateau[static_cast<std::size_t>(k)];
        level = phase < 0.3 ? level + (target - level) * 0.01 : target;  // move, then dwell
        const double v = level + noise(rng);
        lo = std::min(lo, v), hi = std::max(hi, v);
        dec.add(t, v);
    }
    XYSeries kept = dec.take();
    r.trace.time_s = std::move(kept.x);
    r.trace.displacement_um = std::move(kept.y);
    r.trace.samples = samples;
    if (samples > 0) r.trace.min_um = lo, r.trace.max_um = hi;

    for (int k = 0; k < points; ++k) {
        CaptureWindow c;
        c.start_s = (k + 0.45) * slot;
        c.end_s = (k + 0.9) * slot;
        c.location = k / points_per_location;
        c.point = k % points_per_location;
        c.mean_um = plateau[static_cast<std::size_t>(k)];
        r.captures.push_back(c);
    }

    r.procedure.push_back({0, "2026-11-21T09:14:03Z", "step", "connect", "instrument BB-100 SN-0042"});
    r.procedure.push_back({12.5, "2026-11-21T09:14:15Z", "step", "reference", "bar zeroed"});
    for (int l = 0; l < locations; ++l) {
        const double t = l * points_per_location * slot;
        r.procedure.push_back({t, "", "step", "location " + std::to_string(l),
                               "capture " + std::to_string(points_per_location) + " points"});
        if (l == 1)
            r.procedure.push_back(
                {t + slot * 1.5, "", "repeat", "location 1, point 2", "bar not settled (std 2.1 µm)"});
        if (l == 2) {
            r.procedure.push_back({t + slot * 2.2, "", "pause", "location 2", "operator: door opened"});
            r.procedure.push_back({t + slot * 2.6, "", "resume", "location 2", ""});
        }
    }
    r.procedure.push_back({total_s, "2026-11-21T09:31:40Z", "finish", "solve", "SSM and orientation errors"});

    const char* labels[] = {"before rotation", "A = 30°", "A = 60°", "A = 90°", "C = 90°", "C = 180°"};
    for (int l = 0; l < locations; ++l) {
        LocationError e;
        e.location = l;
        e.label = labels[l % 6];
        e.position_mm = {100.0 * std::cos(l * 0.9), 80.0 * std::sin(l * 0.9), -120.0 + 30.0 * l};
        e.error_um = {12.0 * uni(rng), 12.0 * uni(rng), 8.0 * uni(rng)};
        e.uncertainty_um = {0.3 + 0.2 * std::abs(uni(rng)), 0.3 + 0.2 * std::abs(uni(rng)),
                            0.2 + 0.2 * std::abs(uni(rng))};
        e.points = points_per_location;
        e.residual_rms_um = 0.2 + 0.1 * std::abs(uni(rng));
        e.condition = 1.4;
        r.locations.push_back(e);
    }
    const auto axes = analysis::rotary_axes(type);
    const char* symbol_of[] = {"Δα", "Δβ", "Δγ"};
    for (int l = 1; l < locations; ++l) {
        OrientationError o;
        const bool first = l % 2 == 1;
        const char axis = first ? axes.first : axes.second;
        o.axis = std::string(1, axis);
        o.symbol = symbol_of[axis - 'A'];
        o.commanded_rad = analysis::deg_to_rad(30.0 * l);
        o.exact_rad = analysis::deg_to_rad(0.002 * uni(rng));
        o.first_order_rad = *o.exact_rad * (1 + 0.01 * uni(rng));
        o.uncertainty_rad = analysis::deg_to_rad(0.0001);
        o.from_location = 0;
        o.to_location = l;
        r.orientation.push_back(o);
    }

    IdentifiedModel m;
    m.name = "rotary location errors (" + std::string(analysis::to_string(type)) + ")";
    for (auto p : analysis::rotary_params_for(type)) {
        const auto& info = analysis::param_info(p);
        const bool angle = info.unit == analysis::ParamUnit::rad;
        ModelParameter mp;
        mp.name = std::string(info.name);
        mp.unit = angle ? "arcsec" : "µm";
        mp.value = (angle ? 20.0 : 15.0) * uni(rng);
        mp.uncertainty = 0.4 + 0.3 * std::abs(uni(rng));
        mp.observability = 0.5 + 0.5 * std::abs(uni(rng));
        if (*mp.observability < 0.6) mp.note = "poorly observable";
        m.parameters.push_back(mp);
    }
    m.converged = true;
    m.iterations = 5;
    m.residual_rms_before_um = 9.81;
    m.residual_rms_after_um = 0.42;
    m.condition = 37.5;
    r.model = m;

    const char* effects[][3] = {{"spindle growth", "session time", "min"},
                                {"bar expansion", "bar temperature", "°C"},
                                {"scale error EXX", "X position", "mm"}};
    for (const auto& eff : effects) {
        DiscoveryStep s;
        s.effect = eff[0];
        s.variable = eff[1];
        s.variable_unit = eff[2];
        const double slope = 2.0 * uni(rng);
        double sb = 0, sa = 0;
        for (int i = 0; i < points; ++i) {
            const double x = i * 1.0;
            const double res = noise(rng) * 2;
            s.x.push_back(x);
            s.before_um.push_back(slope * (x - points / 2.0) + res);
            s.after_um.push_back(res);
            sb += s.before_um.back() * s.before_um.back();
            sa += res * res;
        }
        s.rms_before_um = std::sqrt(sb / points);
        s.rms_after_um = std::sqrt(sa / points);
        s.accepted = *s.rms_after_um < *s.rms_before_um * 0.8;
        r.discovery.push_back(s);
    }

    r.compensation_metric = "max |error| over the check path";
    r.compensation = {{"X", "µm", 18.2, 2.3},
                      {"Y", "µm", 11.7, 3.6},
                      {"Z", "µm", 21.4, 2.6},
                      {std::string(1, axes.first), "arcsec", 14.0, 1.9},
                      {std::string(1, axes.second), "arcsec", 9.5, 2.2}};
    return r;
}

}  // namespace ballbar::report::testing
