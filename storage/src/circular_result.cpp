// SPDX-License-Identifier: MIT
// The stored payload of a circular test's result ("ballbar circular/1").
#include "ballbar/storage/circular_result.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <vector>

namespace ballbar::storage {

namespace {
namespace circ = analysis::circular;
using ojson = nlohmann::ordered_json;
}  // namespace

std::string circular_result_json(const circ::CircularResult& r, const TraceFile& trace,
                                 std::optional<double> tolerance_um) {
    ojson j;
    j["test"] = ojson::parse(test_json(r.test));
    ojson runs = ojson::array();
    for (const auto& run : r.runs)
        runs.push_back({{"direction", circ::direction_name(run.direction)},
                        {"circularity_um", run.circularity_um},
                        {"radial_deviation_um", {{"max", run.radial_max_um}, {"min", run.radial_min_um}}},
                        {"feed_in_end_s", run.feed_in_end_s},
                        {"feed_in_lag_ms", run.servo_lag_s * 1e3},
                        {"data_start_s", run.data_start_s},
                        {"data_end_s", run.data_end_s},
                        {"samples", run.last_sample - run.first_sample}});
    j["runs"] = runs;
    j["bidirectional_circularity_um"] = r.bidirectional_um ? ojson(*r.bidirectional_um) : ojson(nullptr);
    j["radial_deviation_um"] = {{"max", r.radial_max_um}, {"min", r.radial_min_um}};
    // docs/cli.md's vocabulary: the detected diagnostics one list, ranked first by their share of the
    // circular deviation; each with its unit, value and standard uncertainty.
    ojson diags = ojson::array(), missing = ojson::array();
    int rank = 0;
    for (const bool ranked : {true, false})
        for (const auto& d : r.diagnostics) {
            if (!d.detected || (d.contribution_um > 0.0) != ranked) continue;
            diags.push_back({{"key", d.key},
                             {"unit", circ::diagnostic_unit(d.diag)},
                             {"value", d.value},
                             {"value_std", d.std_uncertainty},
                             {"share_percent", ranked ? ojson(d.share_percent) : ojson(nullptr)},
                             {"rank", ranked ? ojson(++rank) : ojson(nullptr)}});
        }
    for (const auto& d : r.diagnostics)
        if (!d.detected) missing.push_back(d.key);
    j["diagnostics"] = diags;
    j["not_detected"] = missing;
    ojson groups = ojson::array();
    for (const auto& g : r.unseparable) {
        const bool combined = !g.combined_key.empty();
        groups.push_back({{"keys", g.keys},
                          {"reason", g.reason},
                          {"combined_key", combined ? ojson(g.combined_key) : ojson(nullptr)},
                          {"combined_value", combined ? ojson(g.combined_value) : ojson(nullptr)},
                          {"combined_value_std", combined ? ojson(g.combined_std) : ojson(nullptr)}});
    }
    j["unseparable"] = groups;
    j["residual_rms_um"] = r.residual_rms_um;
    j["mean_radius_um"] = r.mean_radius_um;
    j["mean_radius_um_std"] = r.mean_radius_std_um;
    ojson cond = {{"plane", circ::plane_name(r.test.plane)},
                  {"radius_mm", r.test.radius_mm},
                  {"feed_mm_min", r.test.feed_mm_min},
                  {"sample_rate_hz", r.sample_rate_hz},
                  {"samples_used", r.samples_used}};
    auto range = [](const std::vector<std::optional<double>>& v) -> ojson {
        double lo = 1e300, hi = -1e300;
        for (const auto& x : v)
            if (x) lo = std::min(lo, *x), hi = std::max(hi, *x);
        return lo <= hi ? ojson{{"min", lo}, {"max", hi}} : ojson(nullptr);
    };
    cond["bar_temp_C"] = range(trace.bar_temp_C);
    cond["air_temp_C"] = range(trace.air_temp_C);
    cond["instrument"] = trace.instrument_json.empty() ? ojson(nullptr) : ojson::parse(trace.instrument_json);
    j["conditions"] = cond;
    j["tolerance"] = nullptr;
    if (tolerance_um) {
        bool pass = true;
        for (const auto& run : r.runs) pass = pass && run.circularity_um <= *tolerance_um;
        j["tolerance"] = {{"circularity_um", *tolerance_um}, {"pass", pass}};
    }
    return j.dump();
}

}  // namespace ballbar::storage
