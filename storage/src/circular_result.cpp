// SPDX-License-Identifier: MIT
// The stored payload of a circular test's result ("ballbar circular/1").
#include "ballbar/storage/circular_result.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <vector>

namespace ballbar::storage {

namespace {
namespace circ = analysis::circular;
using json = nlohmann::ordered_json;
}  // namespace

std::string circular_result_json(const circ::CircularResult& r, const TraceFile& trace,
                                 std::optional<double> tolerance_um) {
    json j;
    j["test"] = json::parse(test_json(r.test));
    json runs = json::array();
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
    j["bidirectional_circularity_um"] = r.bidirectional_um ? json(*r.bidirectional_um) : json(nullptr);
    j["radial_deviation_um"] = {{"max", r.radial_max_um}, {"min", r.radial_min_um}};
    json diags = json::object(), unc = json::object(), share = json::object(), ranking = json::array(),
         missing = json::array();
    for (const auto& d : r.diagnostics) {
        if (!d.detected) {
            missing.push_back(d.key);
            continue;
        }
        diags[d.key] = d.value;
        unc[d.key] = d.std_uncertainty;
        if (d.contribution_um > 0.0) {
            share[d.key] = d.share_percent;
            ranking.push_back(d.key);
        }
    }
    j["diagnostics"] = diags;
    j["uncertainties"] = unc;
    j["shares_percent"] = share;
    j["ranking"] = ranking;
    j["not_detected"] = missing;
    json groups = json::array();
    for (const auto& g : r.unseparable) {
        json e = {{"keys", g.keys}, {"reason", g.reason}};
        if (!g.combined_key.empty())
            e["combined"] = {{"as", g.combined_key}, {"value", g.combined_value}, {"std_uncertainty", g.combined_std}};
        groups.push_back(e);
    }
    j["unseparable"] = groups;
    j["residual_rms_um"] = r.residual_rms_um;
    j["mean_radius_um"] = {{"value", r.mean_radius_um}, {"std_uncertainty", r.mean_radius_std_um}};
    json cond = {{"plane", circ::plane_name(r.test.plane)},
                 {"radius_mm", r.test.radius_mm},
                 {"feed_mm_min", r.test.feed_mm_min},
                 {"sample_rate_hz", r.sample_rate_hz},
                 {"samples_used", r.samples_used}};
    auto range = [](const std::vector<std::optional<double>>& v) -> json {
        double lo = 1e300, hi = -1e300;
        for (const auto& x : v)
            if (x) lo = std::min(lo, *x), hi = std::max(hi, *x);
        return lo <= hi ? json{{"min", lo}, {"max", hi}} : json(nullptr);
    };
    cond["bar_temp_C"] = range(trace.bar_temp_C);
    cond["air_temp_C"] = range(trace.air_temp_C);
    cond["instrument"] = trace.instrument_json.empty() ? json(nullptr) : json::parse(trace.instrument_json);
    j["conditions"] = cond;
    if (tolerance_um) {
        bool pass = true;
        for (const auto& run : r.runs) pass = pass && run.circularity_um <= *tolerance_um;
        j["tolerance"] = {{"circularity_um", *tolerance_um}, {"pass", pass}};
    }
    return j.dump();
}

}  // namespace ballbar::storage
