// SPDX-License-Identifier: MIT
// Fills a database with one synthetic session the way acquisition stores one: samples through the
// SampleWriter (dwell plateaus with noise at 1 kHz), one point per dwell with its sample window, and the
// "ssm" and "orientation" results. Used by the build_report tests and the report benchmark.
#pragma once

#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/store.hpp"
#include "synthetic.hpp"

namespace ballbar::report::testing {

struct StoredSession {
    std::int64_t id = 0;
    std::vector<nlohmann::json> ssm;          ///< payloads of the stored "ssm" results
    std::vector<nlohmann::json> orientation;  ///< payloads of the stored "orientation" results
};

inline StoredSession store_synthetic_session(storage::Store& store, analysis::MachineType type, std::uint64_t samples,
                                             std::uint64_t seed = 1, int tests = 2, int points_per_step = 3) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, 250.0);  // nm
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    storage::NewSession ns;
    ns.machine = synthetic_machine(type);
    ns.instrument = storage::Instrument{"BB-100", "SN-0042", "1.0.0", 100.0, "2026-06-30", ""};
    ns.source = storage::SessionSource::emulator;
    ns.operator_name = "J. Operator";
    ns.procedure = "ssm";
    ns.started_at = "2026-11-21T09:14:03.000Z";
    StoredSession out;
    out.id = store.create_session(ns);
    store.start_session(out.id);

    const int locations = tests * 2, points = locations * points_per_step;
    const std::uint64_t per_point = std::max<std::uint64_t>(1, samples / static_cast<std::uint64_t>(points));
    {
        storage::SampleWriter writer(store, out.id);
        int32_t level = 0;
        for (int k = 0; k < points; ++k) {
            const auto target = static_cast<int32_t>(40000 * uni(rng));
            const std::uint64_t begin = static_cast<std::uint64_t>(k) * per_point;
            const std::uint64_t end = k + 1 == points ? samples : begin + per_point;
            for (std::uint64_t i = begin; i < end; ++i) {
                const double phase = static_cast<double>(i - begin) / static_cast<double>(per_point);
                if (phase < 0.3)
                    level += (target - level) / 100;
                else
                    level = target;
                analysis::BarSample s;
                s.device_time_us = 5'000'000 + i * 1000;
                s.displacement_nm = level + static_cast<int32_t>(std::lround(noise(rng)));
                s.bar_temp_C = static_cast<float>(20.2 + 0.1 * static_cast<double>(i) / static_cast<double>(samples));
                writer.append(s);
            }
            storage::PointRecord p;
            p.reading.location = k / points_per_step;
            p.reading.point = k % points_per_step;
            p.reading.step = (k / points_per_step) % 2 + 1;
            p.reading.socket_mm = {0, 0, 0};
            p.reading.pose.X_mm = 100.0 + k;
            p.nominal_mm = 100.0;
            p.reading.measured_mm = 100.0 + target * 1e-6;
            p.reading.time_s = (static_cast<double>(begin) + 0.65 * static_cast<double>(end - begin)) * 1e-3;
            p.reading.machine_temp_C = 21.0 + 0.05 * k;
            p.reading.n = static_cast<int>((end - begin) * 4 / 10);
            p.first_seq = begin + (end - begin) / 2;
            p.last_seq = begin + (end - begin) * 9 / 10;
            store.add_point(out.id, p);
        }
        writer.flush();
    }
    for (int t = 0; t < tests; ++t) {
        for (int step = 1; step <= 2; ++step) {
            nlohmann::json j{{"test", t},
                             {"step", step},
                             {"datum_mm", {80.0 * t, -30.0 * step, -100.0 + 20 * t}},
                             {"e_exact_mm", {0.01 * uni(rng), 0.01 * uni(rng), 0.01 * uni(rng)}},
                             {"e_linear_mm", {0.01 * uni(rng), 0.01 * uni(rng), 0.01 * uni(rng)}},
                             {"e_std_mm", {0.0004, 0.00035, 0.0003}},
                             {"dV_mm", {0.012 * uni(rng), 0.012 * uni(rng), 0.008 * uni(rng)}},
                             {"condition_number", 1.3},
                             {"n", points_per_step}};
            store.add_result(out.id, "ssm", j.dump());
            out.ssm.push_back(j);
        }
        const char* kind = type == analysis::MachineType::RTTTR ? (t % 2 ? "TableAlpha" : "SpindleBeta") : "BothAxes";
        auto errs = [&] {
            return nlohmann::json{
                {"d_alpha_rad", 3e-5 * uni(rng)}, {"d_beta_rad", 3e-5 * uni(rng)}, {"d_gamma_rad", 3e-5 * uni(rng)}};
        };
        nlohmann::json o{{"test", t},
                         {"kind", kind},
                         {"dV1_mm", {0.0, 0.0, 0.0}},
                         {"dV2_mm", {0.0, 0.0, 0.0}},
                         {"first_order", errs()},
                         {"exact", errs()},
                         {"std", nullptr}};
        store.add_result(out.id, "orientation", o.dump());
        out.orientation.push_back(o);
    }
    store.finish_session(out.id);
    return out;
}

}  // namespace ballbar::report::testing
